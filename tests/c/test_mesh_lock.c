/*
 * test_mesh_lock.c - a lossy mesh holds when neither side can drive the other
 * (physics.md 1-2 and 11), with hand values.
 *
 * A torque-driven rigid rig at rest, motor torque T_m on the base, a held
 * load L on the driven side. With a = omega_F/omega_B (Simple Gear s/g, Rack
 * & Pinion s_R*r_P) and at rest (no inertia, no viscous torque), the mesh
 * sees T_B = T_m and T_F = L. Which side could drive follows from the loss
 * laws of section 2 written for the two power-flow directions (eq. 1.2:
 * s*g*T_B + T_F - tau_mesh = 0, i.e. T_B = a*(tau_mesh - T_F)):
 *
 *  - the base drives the follower against its load when the motor torque
 *    transmitted through the loss exceeds the load:
 *      constant / temperature efficiency   |T_m| > |a|*|L|/eta        (|T_F| = eta*|T_B|/|a|)
 *      load-dependent (2.6)                |T_m| > |a|*(C0 + (1 + k)*|L|)   (tau_mesh = C0 + k*|T_F| against
 *                                                                           the motion, C0 = g*tau_idle)
 *      T x load table (2.7)                |T_m| > |a|*|L|/eta(T, |L|/g)
 *  - the load drives the base (back-drives the motor) when the motor torque
 *    is below what the load delivers through the loss:
 *      constant / temperature efficiency   |T_m| < eta*|a|*|L|
 *      load-dependent                      |T_m| < |a|*((1 - k)*|L| - C0)
 *      T x load table                      |T_m| < |a|*|L|*(2 - 1/eta)
 *  - in between (the motor pushing against the load), neither can drive
 *    the other: a real gear stays at rest (self-locking), and so must the
 *    rig, with tau_B = T_m, tau_F = L and no power anywhere.
 *
 * The ramps start at rest inside that band and move the motor torque in
 * steps chosen so that the threshold falls half-way between two steps: the
 * rig must stay at exactly 0.0 speed up to the step before and move at the
 * step after. Both blocks, every lossy friction model at one point, both
 * power-flow directions, both load signs across the cases.
 */
#include "test_common.h"

#define DT         1e-3
#define RAMP_STEPS 200

typedef struct {
    const char *name;
    int gear;
    gs_friction_model model;
    double load;           /* L, N*m or N */
    double threshold_base; /* |T_m| above which the base drives (by hand) */
    double threshold_load; /* |T_m| below which the load drives (by hand) */
    double motor_sign;     /* the sign of a motor torque that pushes against the load */
} lock_case;

static void gear_params(gs_simple_gear_params *g, gs_friction_model model)
{
    *g = gs_simple_gear_params_default();
    g->teeth_ratio = R(2.5);
    g->output_shaft_rotates = GS_ROTATES_OPPOSITE;
    g->friction_model = model;
    g->efficiency_const = R(0.3);
    g->idle_torque_Nm = R(0.04);
    g->nominal_output_torque_Nm = R(2.0);
    g->efficiency_nominal = R(0.7);
    /* 2-D table: 2 temperatures x 2 loads (base load |T_F|/g) */
    g->temperature_count = 2;
    g->load_count = 2;
    g->temperature_vector_K[0] = R(280.0);
    g->temperature_vector_K[1] = R(320.0);
    g->load_vector_Nm[0] = R(0.0);
    g->load_vector_Nm[1] = R(4.0);
    g->efficiency_matrix[0][0] = R(0.6);
    g->efficiency_matrix[0][1] = R(0.9);
    g->efficiency_matrix[1][0] = R(0.55);
    g->efficiency_matrix[1][1] = R(0.8);
    g->efficiency_vector[0] = R(0.45);
    g->efficiency_vector[1] = R(0.25);
}

static void rack_params(gs_rack_pinion_params *k, gs_friction_model model)
{
    *k = gs_rack_pinion_params_default();
    k->pinion_radius_m = R(0.04);
    k->rack_directionality = GS_RACK_NEGATIVE;
    k->friction_model = model;
    k->efficiency_const = R(0.2);
    k->temperature_count = 2;
    k->temperature_vector_K[0] = R(280.0);
    k->temperature_vector_K[1] = R(320.0);
    k->efficiency_vector[0] = R(0.45);
    k->efficiency_vector[1] = R(0.25);
}

/* The measured temperature of every case (physics.md 11: the tables use it). */
#define TEMPERATURE 300.0

static gs_rig_params torque_rig(void)
{
    gs_rig_params rp = gs_rig_params_default();
    rp.dt_s = R(DT);
    rp.base_drive = GS_BASE_TORQUE_DRIVEN;
    rp.base_inertia_kg_m2 = R(2e-3);
    rp.driven_inertia = R(3e-2);
    rp.temperature_source = GS_TEMPERATURE_FROM_INPUT;
    return rp;
}

/* Hand thresholds of one case (see the header), from the gs_real parameters. */
static lock_case make_case(const char *name, int gear, gs_friction_model model, double load)
{
    lock_case c;
    double a, eta, k, c0;
    c.name = name;
    c.gear = gear;
    c.model = model;
    c.load = load;
    if (gear) {
        gs_simple_gear_params g;
        double w_t, e_lo, e_hi;
        gear_params(&g, model);
        a = -1.0 / (double)g.teeth_ratio;
        switch (model) {
        case GS_FRICTION_CONSTANT_EFFICIENCY:
            eta = (double)g.efficiency_const;
            c.threshold_base = fabs(a * load) / eta;
            c.threshold_load = eta * fabs(a * load);
            break;
        case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY:
            c0 = (double)g.teeth_ratio * (double)g.idle_torque_Nm;
            k = 1.0 / (double)g.efficiency_nominal - 1.0 - c0 / (double)g.nominal_output_torque_Nm; /* eq. 2.5 */
            c.threshold_base = fabs(a) * (c0 + (1.0 + k) * fabs(load));
            c.threshold_load = fabs(a) * ((1.0 - k) * fabs(load) - c0);
            break;
        case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
            w_t = (TEMPERATURE - (double)g.temperature_vector_K[0]) /
                  ((double)g.temperature_vector_K[1] - (double)g.temperature_vector_K[0]);
            eta = (double)g.efficiency_vector[0] +
                  w_t * ((double)g.efficiency_vector[1] - (double)g.efficiency_vector[0]);
            c.threshold_base = fabs(a * load) / eta;
            c.threshold_load = eta * fabs(a * load);
            break;
        case GS_FRICTION_NONE: /* no band: not a case here */
            c.threshold_base = c.threshold_load = fabs(a * load);
            break;
        case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY: { /* bilinear at (T, |L|/g) */
            const double base_load = fabs(load) / (double)g.teeth_ratio;
            const double w_l = base_load / (double)g.load_vector_Nm[1];
            w_t = (TEMPERATURE - (double)g.temperature_vector_K[0]) /
                  ((double)g.temperature_vector_K[1] - (double)g.temperature_vector_K[0]);
            e_lo = (double)g.efficiency_matrix[0][0] +
                   w_l * ((double)g.efficiency_matrix[0][1] - (double)g.efficiency_matrix[0][0]);
            e_hi = (double)g.efficiency_matrix[1][0] +
                   w_l * ((double)g.efficiency_matrix[1][1] - (double)g.efficiency_matrix[1][0]);
            eta = e_lo + w_t * (e_hi - e_lo);
            c.threshold_base = fabs(a * load) / eta;
            c.threshold_load = fabs(a * load) * (2.0 - 1.0 / eta);
            break;
        }
        }
    } else {
        gs_rack_pinion_params kp;
        rack_params(&kp, model);
        a = -(double)kp.pinion_radius_m;
        if (model == GS_FRICTION_CONSTANT_EFFICIENCY) {
            eta = (double)kp.efficiency_const;
        } else {
            const double w_t = (TEMPERATURE - (double)kp.temperature_vector_K[0]) /
                               ((double)kp.temperature_vector_K[1] - (double)kp.temperature_vector_K[0]);
            eta = (double)kp.efficiency_vector[0] +
                  w_t * ((double)kp.efficiency_vector[1] - (double)kp.efficiency_vector[0]);
        }
        c.threshold_base = fabs(a * load) / eta;
        c.threshold_load = eta * fabs(a * load);
    }
    /* against the load: the follower would move opposite to L, the base
     * opposite to a*L */
    c.motor_sign = a * load > 0.0 ? -1.0 : 1.0;
    return c;
}

static void init_case(test_rig *rig, const lock_case *c)
{
    gs_rig_params rp = torque_rig();
    if (c->gear) {
        gs_simple_gear_params g;
        gear_params(&g, c->model);
        INIT_GEAR_RIG(rig, &g, &rp);
    } else {
        gs_rack_pinion_params k;
        rack_params(&k, c->model);
        INIT_RACK_RIG(rig, &k, &rp);
    }
}

static gs_rig_output step(test_rig *rig, double motor, double load)
{
    gs_rig_input in = rig_torque_input(motor, load);
    gs_rig_output o;
    in.measured_temperature = R(TEMPERATURE);
    gs_rig_step(&rig->c, &rig->s, &in, &o);
    return o;
}

/* At rest and held: exactly zero speeds, the port torques the outside
 * applies, no power. */
static void assert_held(const gs_rig_output *o, double motor, double load, const char *name, int k)
{
    if (!is_zero((double)o->base_speed) || !is_zero((double)o->follower_speed)) {
        print_error("%s: moved at step %d with T_m = %.9g (w_B %.9g, w_F %.9g)\n", name, k, motor,
                    (double)o->base_speed, (double)o->follower_speed);
        fail();
    }
    ASSERT_NEAR(o->base_port_torque, R(motor), TOL_REL, 0.0);
    ASSERT_NEAR(o->follower_port_torque, R(load), TOL_REL, 0.0);
    assert_true(is_zero((double)o->loss_power) && is_zero((double)o->port_power));
}

/* Ramps |T_m| from inside the band across one threshold; the rig must move
 * first at step RAMP_STEPS, where the ramp first passes it. base_drives: the
 * ramp rises through threshold_base, else it falls through threshold_load. */
static void ramp_case(const lock_case *c, int base_drives)
{
    test_rig rig;
    const double lo = c->threshold_load > 0.0 ? c->threshold_load : 0.0;
    const double start = 0.5 * (lo + c->threshold_base);
    const double target = base_drives ? c->threshold_base : c->threshold_load;
    /* the threshold sits half a ramp step before step RAMP_STEPS */
    const double increment = (target - start) / ((double)RAMP_STEPS - 0.5);
    gs_rig_output o;
    int k;
    assert_true(c->threshold_base > lo * 1.2); /* a band to hold in */
    init_case(&rig, c);
    for (k = 0; k <= RAMP_STEPS; ++k) {
        const double motor = c->motor_sign * (start + increment * (double)k);
        o = step(&rig, motor, c->load);
        if (k < RAMP_STEPS) {
            assert_held(&o, motor, c->load, c->name, k);
        }
    }
    /* it moves, and the way the driving side pushes */
    if (base_drives) {
        assert_true((double)o.base_speed * c->motor_sign > 0.0);
        assert_true((double)o.follower_speed * c->load < 0.0);
    } else {
        assert_true((double)o.base_speed * c->motor_sign < 0.0);
        assert_true((double)o.follower_speed * c->load > 0.0);
    }
    print_message("%-34s %-14s breaks away at step %d: |T_m| = %.6g (threshold by hand %.6g)\n", c->name,
                  base_drives ? "base drives" : "load drives", RAMP_STEPS, start + increment * RAMP_STEPS, target);
}

static void test_issue_case_stays_at_rest(void **state)
{
    /* teeth ratio 2, constant efficiency 0.01, J_B 1e-3, J_F 1e-2, dt 1e-3,
     * base torque 2 against a load of 5: the base could drive only above
     * |a|*L/eta = 0.5*5/0.01 = 250 N*m, the load only below eta*|a|*L =
     * 0.025 N*m */
    gs_simple_gear_params g = gs_simple_gear_params_default();
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    int k;
    (void)state;
    g.teeth_ratio = R(2.0);
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.efficiency_const = R(0.01);
    rp.base_drive = GS_BASE_TORQUE_DRIVEN;
    rp.base_inertia_kg_m2 = R(1e-3);
    rp.driven_inertia = R(1e-2);
    rp.dt_s = R(1e-3);
    INIT_GEAR_RIG(&rig, &g, &rp);
    for (k = 0; k < 2000; ++k) {
        gs_rig_input in = rig_torque_input(2.0, 5.0);
        gs_rig_output o;
        gs_rig_step(&rig.c, &rig.s, &in, &o);
        assert_held(&o, 2.0, 5.0, "teeth ratio 2, eta 0.01", k);
        assert_true(is_zero((double)o.base_angle) && is_zero((double)o.follower_position));
    }
}

static void test_breakaway_thresholds(void **state)
{
    const lock_case cases[] = {
        make_case("gear, constant efficiency", 1, GS_FRICTION_CONSTANT_EFFICIENCY, 3.0),
        make_case("gear, load-dependent efficiency", 1, GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY, -3.0),
        make_case("gear, temperature efficiency", 1, GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY, -2.0),
        make_case("gear, T x load table", 1, GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY, 6.0),
        make_case("rack, constant efficiency", 0, GS_FRICTION_CONSTANT_EFFICIENCY, 40.0),
        make_case("rack, temperature efficiency", 0, GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY, -25.0),
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        ramp_case(&cases[i], 1);
        ramp_case(&cases[i], 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_issue_case_stays_at_rest),
        cmocka_unit_test(test_breakaway_thresholds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
