/*
 * test_energy.c - energy balance on every step over random operating points
 * (docs/physics.md section 0 and eq. 1.3):
 *
 *   sum(port powers) = P_loss + dE_stored/dt,   P_loss >= 0.
 *
 * Rigid mesh (no stored energy): port_power == loss_power to rounding,
 * and port_power == tau_B*omega_B + tau_F*omega_F from the outputs.
 * Backlash: the stored energy is the contact spring's; the implicit contact
 * integration may only dissipate, so on every step
 *   port_power*dt >= loss_power*dt + (E_n - E_{n-1}) - rounding.
 * Operating points come from a seeded xorshift64 generator (test_common.h):
 * speeds and loads jump, hold, reverse and dwell near zero, inside and far
 * outside the smoothing thresholds.
 */
#include "test_common.h"

#define RIGID_STEPS    3000
#define BACKLASH_STEPS 4000

static void set_2d_table(gs_simple_gear_params *gp)
{
    static const double T[3] = {280.0, 310.0, 340.0};
    static const double L[3] = {0.0, 2.0, 10.0};
    static const double E[3][3] = {{0.80, 0.90, 0.95}, {0.75, 0.88, 0.93}, {0.70, 0.85, 0.90}};
    int i, j;
    gp->temperature_count = 3;
    gp->load_count = 3;
    for (i = 0; i < 3; ++i) {
        gp->temperature_vector_K[i] = R(T[i]);
        gp->load_vector_Nm[i] = R(L[i]);
        for (j = 0; j < 3; ++j)
            gp->efficiency_matrix[i][j] = R(E[i][j]);
    }
}

static gs_simple_gear_params lossy_gear(gs_friction_model fm, gs_output_rotation rot, gs_loss_smoothing sm, double g)
{
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gp.teeth_ratio = R(g);
    gp.output_shaft_rotates = rot;
    gp.friction_model = fm;
    gp.loss_smoothing = sm;
    gp.efficiency_const = R(0.85);
    gp.power_threshold_W = R(0.5);
    gp.idle_torque_Nm = R(0.05);
    gp.nominal_output_torque_Nm = R(5.0);
    gp.efficiency_nominal = R(0.9);
    gp.speed_threshold_rad_s = R(0.2);
    gp.viscous_coefficients[0] = R(0.01);
    gp.viscous_coefficients[1] = R(0.02);
    gp.thermal_mass_J_K = R(5.0);
    if (fm == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY) set_2d_table(&gp);
    return gp;
}

static gs_rig_params lossy_rig(gs_base_drive drive)
{
    gs_rig_params rp = gs_rig_params_default();
    rp.dt_s = R(1e-3);
    rp.base_drive = drive;
    rp.base_inertia_kg_m2 = R(0.005);
    rp.initial_base_speed_rad_s = R(3.0);
    rp.driven_inertia = R(0.02);
    rp.load_coulomb_friction = R(0.1);
    rp.load_coulomb_speed_threshold = R(0.05);
    rp.load_offset = R(0.2);
    rp.heat_path = 1;
    rp.thermal_resistance_K_W = R(3.0);
    rp.accel_filter_time_constant_s = R(0.002);
    return rp;
}

/* Random piecewise input: holds, jumps, small values near zero. */
typedef struct {
    double base, load;
    int hold;
} walk;

static void walk_next(test_rng *rng, walk *w, double base_max, double load_max, int max_hold)
{
    if (w->hold > 0) {
        --w->hold;
        return;
    }
    w->hold = (int)(rng_unit(rng) * max_hold);
    w->base = rng_range(rng, -base_max, base_max) * (rng_unit(rng) < 0.25 ? 0.01 : 1.0);
    w->load = rng_range(rng, -load_max, load_max) * (rng_unit(rng) < 0.25 ? 0.01 : 1.0);
}

/* The input of a speed- or torque-driven rig from the walk's values. */
static gs_rig_input walk_input(gs_base_drive drive, const walk *w)
{
    return drive == GS_BASE_SPEED_DRIVEN ? rig_speed_input(w->base, w->load) : rig_torque_input(w->base, w->load);
}

static void check_rigid_step(const gs_rig_output *o, gs_base_drive drive, int passive)
{
    const double gross = fabs((double)o->base_port_torque * (double)o->base_speed) +
                         fabs((double)o->follower_port_torque * (double)o->follower_speed);
    assert_true(rig_output_finite(o));
    if (passive) {
        assert_true((double)o->mesh_loss_power >= 0.0);
        assert_true((double)o->loss_power >= 0.0);
        ASSERT_LE(o->mesh_loss_power, o->loss_power, TOL_REL * gross + 1e-15);
    }
    ASSERT_NEAR(o->port_power, o->loss_power, 0.0, TOL_REL * gross + 1e-12);
    if (drive == GS_BASE_SPEED_DRIVEN) {
        /* port power = tau_B*omega_B + tau_F*omega_F of the same step */
        const double pp = (double)o->base_port_torque * (double)o->base_speed +
                          (double)o->follower_port_torque * (double)o->follower_speed;
        ASSERT_NEAR(o->port_power, pp, 0.0, TOL_REL * gross + 1e-12);
    }
    ASSERT_NEAR(o->contact_energy, 0.0, 0.0, 0.0); /* rigid: nothing stored */
}

static void run_random_rigid_gear(gs_friction_model fm, gs_output_rotation rot, gs_loss_smoothing sm,
                                  gs_base_drive drive, uint64_t seed)
{
    test_rng rng = rng_seed(seed);
    const double g = rng_range(&rng, 0.4, 4.0);
    gs_simple_gear_params gp = lossy_gear(fm, rot, sm, g);
    gs_rig_params rp = lossy_rig(drive);
    test_rig rig;
    gs_rig_output out;
    walk w = {0.0, 0.0, 0};
    double max_loss = 0.0;
    int k;
    INIT_GEAR_RIG(&rig, &gp, &rp);
    for (k = 0; k < RIGID_STEPS; ++k) {
        gs_rig_input in;
        walk_next(&rng, &w, drive == GS_BASE_SPEED_DRIVEN ? 30.0 : 1.5, 8.0, 40);
        in = walk_input(drive, &w);
        in.ambient_temperature = R(rng_range(&rng, 290.0, 310.0));
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        check_rigid_step(&out, drive, sm == GS_SMOOTHING_PASSIVE);
        max_loss = dmax(max_loss, (double)out.loss_power);
    }
    assert_true(max_loss > 0.1); /* the scenario does dissipate */
}

/* Every gear friction model with passive smoothing, both rotation senses;
 * seeds seed_same + i and seed_opposite + i for model i. */
static void run_random_rigid_gear_models(gs_base_drive drive, uint64_t seed_same, uint64_t seed_opposite)
{
    static const gs_friction_model fms[5] = {
        GS_FRICTION_NONE, GS_FRICTION_CONSTANT_EFFICIENCY, GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY,
        GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY, GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY};
    int i;
    for (i = 0; i < 5; ++i) {
        run_random_rigid_gear(fms[i], GS_ROTATES_SAME, GS_SMOOTHING_PASSIVE, drive, seed_same + (uint64_t)i);
        run_random_rigid_gear(fms[i], GS_ROTATES_OPPOSITE, GS_SMOOTHING_PASSIVE, drive, seed_opposite + (uint64_t)i);
    }
}

static void test_random_rigid_gear_speed_driven(void **state)
{
    (void)state;
    run_random_rigid_gear_models(GS_BASE_SPEED_DRIVEN, 1000u, 2000u);
    /* Simscape smoothing: the balance still holds (loss may dip below 0) */
    run_random_rigid_gear(GS_FRICTION_CONSTANT_EFFICIENCY, GS_ROTATES_OPPOSITE, GS_SMOOTHING_SIMSCAPE,
                          GS_BASE_SPEED_DRIVEN, 3001u);
}

static void test_random_rigid_gear_torque_driven(void **state)
{
    (void)state;
    run_random_rigid_gear_models(GS_BASE_TORQUE_DRIVEN, 4000u, 5000u);
}

static void run_random_rigid_rack(gs_friction_model fm, gs_rack_direction dir, gs_base_drive drive, uint64_t seed)
{
    test_rng rng = rng_seed(seed);
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    gs_rig_params rp = lossy_rig(drive);
    test_rig rig;
    gs_rig_output out;
    walk w = {0.0, 0.0, 0};
    double max_loss = 0.0;
    int k;
    pp.pinion_radius_m = R(rng_range(&rng, 0.01, 0.2));
    pp.rack_directionality = dir;
    pp.friction_model = fm;
    pp.efficiency_const = R(0.8);
    pp.power_threshold_W = R(0.3);
    pp.pinion_viscous_coefficient = R(0.01);
    pp.rack_viscous_coefficient = R(2.0);
    pp.thermal_mass_J_K = R(5.0);
    rp.driven_inertia = R(1.5);        /* kg */
    rp.load_coulomb_friction = R(3.0); /* N */
    rp.load_coulomb_speed_threshold = R(0.01);
    rp.load_offset = R(-4.0);
    INIT_RACK_RIG(&rig, &pp, &rp);
    for (k = 0; k < RIGID_STEPS; ++k) {
        gs_rig_input in;
        walk_next(&rng, &w, drive == GS_BASE_SPEED_DRIVEN ? 30.0 : 1.5, 80.0, 40);
        in = walk_input(drive, &w);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        check_rigid_step(&out, drive, 1);
        max_loss = dmax(max_loss, (double)out.loss_power);
    }
    assert_true(max_loss > 0.1);
}

static void test_random_rigid_rack(void **state)
{
    const gs_friction_model fms[3] = {GS_FRICTION_NONE, GS_FRICTION_CONSTANT_EFFICIENCY,
                                      GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY};
    int i;
    (void)state;
    for (i = 0; i < 3; ++i) {
        run_random_rigid_rack(fms[i], GS_RACK_POSITIVE, GS_BASE_SPEED_DRIVEN, 6000u + (uint64_t)i);
        run_random_rigid_rack(fms[i], GS_RACK_NEGATIVE, GS_BASE_SPEED_DRIVEN, 7000u + (uint64_t)i);
        run_random_rigid_rack(fms[i], GS_RACK_NEGATIVE, GS_BASE_TORQUE_DRIVEN, 8000u + (uint64_t)i);
    }
}

/* ---- Backlash: per-step dissipation inequality. */
static void check_backlash_step(const gs_rig_output *o, double e_prev, double f_prev, double dt, int step,
                                const char *label)
{
    const double e = (double)o->contact_energy;
    const double gross = (fabs((double)o->base_port_torque * (double)o->base_speed) +
                          fabs((double)o->follower_port_torque * (double)o->follower_speed)) *
                         dt;
    /* rounding slack: the energies' own scale, and the stored energy's
     * sensitivity to the rounding of x (~|f|*eps*b, b = 1e-3 m here) */
    const double tol = TOL_ENERGY * (gross + fabs((double)o->loss_power) * dt + e + e_prev) + 1e-15 +
                       4.0 * GS_EPS * 1e-3 * (fabs((double)o->contact_force) + fabs(f_prev));
    const double lhs = (double)o->loss_power * dt + (e - e_prev);
    const double rhs = (double)o->port_power * dt;
    /* the contact's share of the loss, (f - f_spring)*u, comes from an
     * impulse balance: allow rounding relative to the power through the ports */
    const double loss_floor = -TOL_ENERGY * gross / dt;
    if (!rig_output_finite(o) || !((double)o->loss_power >= loss_floor) || !((double)o->mesh_loss_power >= 0.0) ||
        !(e >= 0.0) || !(lhs <= rhs + tol)) {
        print_error("%s, step %d: loss %.9g W, mesh loss %.9g W, port %.9g W, E %.9g -> %.9g J, "
                    "loss*dt + dE - port*dt = %.3g J (tol %.3g), x = %.9g m, f = %.9g N, "
                    "omega_B %.6g, omega_F %.6g\n",
                    label, step, (double)o->loss_power, (double)o->mesh_loss_power, (double)o->port_power, e_prev, e,
                    lhs - rhs, tol, (double)o->backlash_position, (double)o->contact_force, (double)o->base_speed,
                    (double)o->follower_speed);
        fail();
    }
}

static const gs_hard_stop_model hard_stop_models[3] = {GS_HARD_STOP_SMOOTH, GS_HARD_STOP_FULL_UNDAMPED,
                                                       GS_HARD_STOP_FULL_DAMPED};

typedef struct {
    gs_hard_stop_model model;
    double damping;
    int no_pull;
    int substeps;
    gs_friction_model friction;
    gs_base_drive drive;
    int rack;
} backlash_case;

static void run_random_backlash(backlash_case c, uint64_t seed)
{
    test_rng rng = rng_seed(seed);
    gs_rig_params rp = lossy_rig(c.drive);
    gs_backlash_params bl;
    test_rig rig;
    gs_rig_output out;
    walk w = {0.0, 0.0, 0};
    double e_prev, f_prev = 0.0, dt, max_e = 0.0;
    int k;
    char label[160];
    snprintf(label, sizeof label, "%s rig, hard stop %d, D %g, no_pull %d, substeps %d, friction %d, %s-driven",
             c.rack ? "rack" : "gear", (int)c.model, c.damping, c.no_pull, c.substeps, (int)c.friction,
             c.drive == GS_BASE_SPEED_DRIVEN ? "speed" : "torque");
    bl = gs_simple_gear_params_default().backlash;
    bl.enabled = 1;
    bl.hard_stop_model = c.model;
    bl.linear_backlash_m = R(1e-3);
    bl.base_radius_m = R(0.1);
    bl.transition_region_m = R(5e-5);
    bl.stiffness_N_m = R(rng_range(&rng, 2e5, 2e6));
    bl.damping_N_s_m = R(c.damping);
    bl.initial_position_m = R(rng_range(&rng, -5e-4, 5e-4));
    bl.no_pull = c.no_pull;
    rp.contact_substeps = c.substeps;
    rp.load_coulomb_friction = R(0.0);
    rp.driven_inertia = R(0.01);
    rp.heat_path = 0;
    if (c.rack) {
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        pp.pinion_radius_m = R(0.05);
        pp.friction_model = c.friction;
        pp.efficiency_const = R(0.85);
        /* thresholds inside the explicit-friction stability bounds of
         * docs/model.md (p_th > 2*L*T^2*h/J_eff for contact forces of
         * several hundred N), so a failure is not threshold chatter */
        pp.power_threshold_W = R(100.0);
        pp.rack_viscous_coefficient = R(1.0);
        pp.backlash = bl;
        rp.driven_inertia = R(2.0);
        INIT_RACK_RIG(&rig, &pp, &rp);
    } else {
        gs_simple_gear_params gp = lossy_gear(c.friction, GS_ROTATES_OPPOSITE, GS_SMOOTHING_PASSIVE, 2.0);
        /* thresholds inside the explicit-friction stability bounds of
         * docs/model.md (p_th > 2*L*T_F^2*h/J_F, omega_th > 2*tau_C*h/J_F
         * for tooth torques of tens of N*m) */
        gp.power_threshold_W = R(100.0);
        gp.speed_threshold_rad_s = R(2.0);
        gp.backlash = bl;
        INIT_GEAR_RIG(&rig, &gp, &rp);
    }
    dt = (double)rp.dt_s;
    e_prev = 0.0; /* the initial position is inside the gap: nothing stored */
    for (k = 0; k < BACKLASH_STEPS; ++k) {
        gs_rig_input in;
        walk_next(&rng, &w, c.drive == GS_BASE_SPEED_DRIVEN ? 20.0 : 0.8, c.rack ? 40.0 : 2.0, 80);
        in = walk_input(c.drive, &w);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        check_backlash_step(&out, e_prev, f_prev, dt, k, label);
        e_prev = (double)out.contact_energy;
        f_prev = (double)out.contact_force;
        max_e = dmax(max_e, e_prev);
    }
    /* the scenario does load the contact spring */
    assert_true(max_e > 0.0);
}

/* Contact only (no meshing loss): what the backward-Euler contact
 * integration itself does. */
static void test_random_backlash_energy_contact(void **state)
{
    /* damping, no_pull, substeps (0 = automatic), drive */
    static const struct {
        double damping;
        int no_pull, substeps;
        gs_base_drive drive;
    } variants[6] = {{0.0, 1, 0, GS_BASE_SPEED_DRIVEN},    {300.0, 1, 0, GS_BASE_SPEED_DRIVEN},
                     {300.0, 1, 0, GS_BASE_TORQUE_DRIVEN}, {300.0, 0, 0, GS_BASE_SPEED_DRIVEN},
                     {300.0, 1, 1, GS_BASE_SPEED_DRIVEN},  {0.0, 1, 8, GS_BASE_SPEED_DRIVEN}};
    uint64_t seed = 9000u;
    int m, v, rack;
    (void)state;
    for (m = 0; m < 3; ++m) {
        for (v = 0; v < 6; ++v) {
            for (rack = 0; rack < 2; ++rack) {
                backlash_case c;
                c.model = hard_stop_models[m];
                c.damping = variants[v].damping;
                c.no_pull = variants[v].no_pull;
                c.substeps = variants[v].substeps;
                c.friction = GS_FRICTION_NONE;
                c.drive = variants[v].drive;
                c.rack = rack;
                run_random_backlash(c, seed++);
            }
        }
    }
}

/* With meshing loss (constant, load-dependent or temperature-dependent
 * efficiency) on top of the contact: the loss must still be accounted so
 * that no step creates energy. */
static void test_random_backlash_energy_mesh_loss(void **state)
{
    uint64_t seed = 9500u;
    int m, v, rack;
    (void)state;
    for (m = 0; m < 3; ++m) {
        for (v = 0; v < 3; ++v) {
            for (rack = 0; rack < 2; ++rack) {
                backlash_case c;
                c.model = hard_stop_models[m];
                c.damping = (v == 2) ? 0.0 : 300.0;
                c.no_pull = 1;
                c.substeps = (v == 2) ? 8 : 0;
                c.friction = (v == 1) ? (rack ? GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY
                                              : GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY)
                                      : GS_FRICTION_CONSTANT_EFFICIENCY;
                c.drive = GS_BASE_SPEED_DRIVEN;
                c.rack = rack;
                run_random_backlash(c, seed++);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_rigid_gear_speed_driven),
        cmocka_unit_test(test_random_rigid_gear_torque_driven),
        cmocka_unit_test(test_random_rigid_rack),
        cmocka_unit_test(test_random_backlash_energy_contact),
        cmocka_unit_test(test_random_backlash_energy_mesh_loss),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
