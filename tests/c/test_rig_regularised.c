/*
 * test_rig_regularised.c - the rig's regularised driven-side friction, the
 * compliant mesh (compliance with no base inertia) and the step-mean speed of
 * the speed-driven rigid rig (docs/physics.md section 11), against values
 * derived by hand from the equations there:
 *
 *  Regularised friction  F(v)*tanh(4 v/v_th) on a freely moving driven side
 *             (F the Coulomb level, v_th = load_coulomb_speed_threshold).
 *             Under a held load L < F with viscous mu = 0 the driven side
 *             creeps at v* = (v_th/4)*atanh(L/F) instead of sticking.
 *             Decelerating freely from v0 (J dv/dt = -F tanh(k v), k = 4/v_th):
 *             sinh(k v(t)) = sinh(k v0)*exp(-k F t/J).
 *             The meshing loss takes its smoothing's strength at each
 *             step's start: the idle torque of the load-dependent law
 *             lets the gear creep at w_F = (w_th/4)*atanh(T_m/tau_0).
 *  Compliant mesh        base_inertia 0: the spring k, c carries the drive's
 *             torque to the driven side alone, J_eff = a^2*J_F. Drive at
 *             rest, load L: the twist settles at phi_inf = -a*L/k whatever the
 *             friction when it is regularised (it vanishes at rest); the
 *             set-valued law holds the follower wherever it stops while
 *             |L| <= F. With the friction in its linear range (|v| << v_th/4)
 *             the follower sees a damper c_f = 4F/v_th, at the base
 *             a^2*c_f, and the twist follows
 *             J_eff phi'' + (c + a^2 c_f) phi' + k phi = -a L.
 *  Step-mean speed       base_speed_ramp: the speed-driven rigid rig takes
 *             w = (w_prev + w_k)/2 for its speed terms; with no meshing loss
 *             and no load the drive pays a^2*(J_F*alpha + mu_F*w), alpha the
 *             backward difference of the samples; the angle advances by
 *             dt*w, so on a linear ramp w_k = alpha*t_k it is alpha*t^2/2.
 */
#include "test_common.h"

/* Gear rig g = 2, opposite rotation (a = -1/2); rack rig r_P = 0.05 m,
 * negative direction (a = -0.05 m/rad); no meshing loss. */
#define GEAR_RATIO    2.0
#define PINION_RADIUS 0.05

static double follower_per_base(int rack)
{
    return rack ? -PINION_RADIUS : -1.0 / GEAR_RATIO;
}

static void make_rig(test_rig *rig, int rack, int backlash, double mu_follower, const gs_rig_params *rp)
{
    if (rack) {
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        pp.pinion_radius_m = R(PINION_RADIUS);
        pp.rack_directionality = GS_RACK_NEGATIVE;
        pp.rack_viscous_coefficient = R(mu_follower);
        pp.backlash.enabled = backlash;
        pp.backlash.linear_backlash_m = R(0.02); /* a wide gap: the follower flies */
        pp.backlash.transition_region_m = R(1e-4);
        INIT_RACK_RIG(rig, &pp, rp);
        return;
    }
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gp.teeth_ratio = R(GEAR_RATIO);
    gp.output_shaft_rotates = GS_ROTATES_OPPOSITE;
    gp.viscous_coefficients[1] = R(mu_follower);
    gp.backlash.enabled = backlash;
    gp.backlash.linear_backlash_m = R(0.02);
    gp.backlash.base_radius_m = R(0.05);
    gp.backlash.transition_region_m = R(1e-4);
    INIT_GEAR_RIG(rig, &gp, rp);
}

/* ---- Regularised friction ---- */

/* Torque-driven rigid rig (no motor torque) and a speed-driven backlash rig
 * with the base at rest and the follower inside the gap: under a held load
 * below the Coulomb level the follower creeps at v* = (v_th/4)*atanh(L/F);
 * with the set-valued law it stays at exactly zero speed. */
static void test_creep_under_load(void **state)
{
    const double coulomb = 2.0, v_th = 0.04;
    const double loads[] = {0.5, -1.5, 1.9};
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int backlash = 0; backlash <= 1; ++backlash)
            for (int regularised = 0; regularised <= 1; ++regularised)
                for (size_t i = 0; i < sizeof loads / sizeof loads[0]; ++i) {
                    gs_rig_params rp = gs_rig_params_default();
                    rp.driven_inertia = R(0.2);
                    rp.load_coulomb_friction = R(coulomb);
                    rp.load_coulomb_speed_threshold = R(v_th);
                    rp.load_friction_regularised = regularised;
                    if (!backlash) {
                        rp.base_drive = GS_BASE_TORQUE_DRIVEN;
                        rp.base_inertia_kg_m2 = R(0.01);
                    }
                    test_rig rig;
                    make_rig(&rig, rack, backlash, 0.0, &rp);
                    const double load = loads[i];
                    const gs_rig_input in = backlash ? rig_speed_input(0.0, load) : rig_torque_input(0.0, load);
                    gs_rig_output out;
                    /* the creep settles at the rate F*k*sech^2(k v*)/J (k = 4/v_th), J
                     * the inertia it moves: the follower alone in the gap (over 97 1/s:
                     * 0.4 s, while it moves by less than 8 mm, inside the 20 mm gap),
                     * follower and base together when torque-driven (the rack's base
                     * inertia seen at the rack is 4 kg: over 4.6 1/s; 8 s) */
                    const int steps = backlash ? 400 : 8000;
                    for (int k = 0; k < steps; ++k)
                        gs_rig_step(&rig.c, &rig.s, &in, &out);
                    const double v_star = regularised ? 0.25 * v_th * atanh(load / coulomb) : 0.0;
                    if (regularised)
                        ASSERT_NEAR(out.follower_speed, v_star, TOL_ACC, 0.0);
                    else
                        assert_true(is_zero((double)out.follower_speed));
                    if (backlash) /* the teeth never touched */
                        assert_true(is_zero((double)out.contact_force));
                }
}

/* The meshing loss regularised (physics.md 11.6): a torque-driven rigid
 * gear with the load-dependent law, idle torque tau_0 on the base, no load,
 * a motor torque T_m below tau_0. The set-valued mesh holds it at exactly
 * zero speed; regularised, the loss takes the strength
 * s = |tanh(4 w_F/w_th)| at each step's start, and the gear settles where
 * the motor torque balances the idle loss, |T_m| = tau_0*s (the net
 * follower torque is zero then, so the load slope drops out):
 * |w_F| = (w_th/4)*atanh(|T_m|/tau_0), turning the way the motor pushes. The
 * approach rate, tau_0*(4/(g w_th))/J_eff = 833 1/s at dt = 1 ms, is inside
 * the explicit strength's stable range (< 2/dt). */
static void test_mesh_loss_creeps(void **state)
{
    const double tau_idle = 1.0, w_th = 0.04, j_b = 0.01, j_f = 0.2;
    const double motors[] = {0.3, -0.7, 0.95};
    (void)state;
    for (int regularised = 0; regularised <= 1; ++regularised)
        for (size_t i = 0; i < sizeof motors / sizeof motors[0]; ++i) {
            gs_rig_params rp = gs_rig_params_default();
            rp.base_drive = GS_BASE_TORQUE_DRIVEN;
            rp.base_inertia_kg_m2 = R(j_b);
            rp.driven_inertia = R(j_f);
            rp.load_friction_regularised = regularised;
            gs_simple_gear_params gp = gs_simple_gear_params_default();
            gp.teeth_ratio = R(GEAR_RATIO);
            gp.output_shaft_rotates = GS_ROTATES_OPPOSITE;
            gp.friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
            gp.idle_torque_Nm = R(tau_idle);
            gp.nominal_output_torque_Nm = R(100.0); /* room for the idle torque: g*tau_0 <= 100*(1/0.9 - 1) */
            gp.efficiency_nominal = R(0.9);
            gp.speed_threshold_rad_s = R(w_th);
            test_rig rig;
            INIT_GEAR_RIG(&rig, &gp, &rp);
            const gs_rig_input in = rig_torque_input(motors[i], 0.0);
            gs_rig_output out;
            for (int k = 0; k < 2000; ++k)
                gs_rig_step(&rig.c, &rig.s, &in, &out);
            if (!regularised) {
                assert_true(is_zero((double)out.base_speed));
                continue;
            }
            /* opposite rotation: the follower turns against the base */
            const double w_f = -copysign(0.25 * w_th * atanh(fabs(motors[i]) / tau_idle), motors[i]);
            ASSERT_NEAR(out.follower_speed, w_f, TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_speed, -GEAR_RATIO * w_f, TOL_ACC, 0.0);
        }
}

/* Backlash rig, base at rest, no load: the follower given a speed in the
 * gap decelerates by the regularised friction along the closed form
 * sinh(k v) = sinh(k v0) exp(-k F t/J); backward Euler is first order in the
 * sub-step, so the error falls about four-fold from 16 to 64 sub-steps. */
static double free_deceleration_error(int rack, int substeps, double *worst_at_end)
{
    const double coulomb = 0.5, v_th = 0.02, j = 0.05, v0 = 0.05, dt = 1e-3;
    const double k = 4.0 / v_th;
    gs_rig_params rp = gs_rig_params_default();
    rp.driven_inertia = R(j);
    rp.load_coulomb_friction = R(coulomb);
    rp.load_coulomb_speed_threshold = R(v_th);
    rp.load_friction_regularised = 1;
    rp.contact_substeps = substeps;
    test_rig rig;
    make_rig(&rig, rack, 1, 0.0, &rp);
    const gs_rig_input in = rig_speed_input(0.0, 0.0);
    gs_rig_output out;
    gs_rig_step(&rig.c, &rig.s, &in, &out); /* the first step sets the speeds (at rest) */
    rig.s.follower_speed = R(v0);           /* a state is plain data */
    double worst = 0.0;
    for (int n = 1; n <= 20; ++n) {
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        const double t = n * dt;
        const double want = asinh(sinh(k * v0) * exp(-k * coulomb * t / j)) / k;
        worst = dmax(worst, fabs((double)out.follower_speed - want) / v0);
        assert_true(is_zero((double)out.contact_force));
        assert_true((double)out.follower_speed > 0.0); /* it never reverses */
    }
    *worst_at_end = worst;
    return worst;
}

static void test_free_deceleration(void **state)
{
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        double e16, e64;
        free_deceleration_error(rack, 16, &e16);
        free_deceleration_error(rack, 64, &e64);
        print_message("%s: worst relative speed error %.3g (16 sub-steps), %.3g (64)\n", rack ? "rack" : "gear", e16,
                      e64);
        assert_true(e64 < 1e-2);
        assert_true(e64 < 0.4 * e16);
    }
}

/* ---- Compliant mesh (compliance with no base inertia) ---- */

typedef struct {
    double a, j_eff, k, c, load, phi_inf;
} mesh_case;

static mesh_case mesh_setup(int rack, double omega_n, double zeta, double load, gs_rig_params *rp)
{
    mesh_case m;
    const double j_f = rack ? 4.0 : 0.05;
    m.a = follower_per_base(rack);
    m.j_eff = m.a * m.a * j_f;
    m.k = m.j_eff * omega_n * omega_n;
    m.c = 2.0 * zeta * sqrt(m.k * m.j_eff);
    m.load = load;
    m.phi_inf = -m.a * load / m.k;
    *rp = gs_rig_params_default();
    rp->base_inertia_kg_m2 = R(0.0);
    rp->driven_inertia = R(j_f);
    rp->compliance_stiffness_Nm_rad = R(m.k);
    rp->compliance_damping_Nm_s_rad = R(m.c);
    return m;
}

/* Drive at rest, held load: without friction the mesh rings at
 * omega_n = sqrt(k/(a^2 J_F)) (zero crossings) and settles at phi_inf; the
 * drive then carries -a*L. */
static void test_compliant_mesh_ring(void **state)
{
    enum { N = 400 };
    const double dt = 1e-3, zeta = 0.03;
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        gs_rig_params rp;
        const double omega_n = 2.0 * TEST_PI * 40.0;
        const mesh_case m = mesh_setup(rack, omega_n, zeta, rack ? 30.0 : 4.0, &rp);
        test_rig rig;
        make_rig(&rig, rack, 0, 0.0, &rp);
        const gs_rig_input in = rig_speed_input(0.0, m.load);
        gs_rig_output out;
        static double dev[N + 1];
        dev[0] = -m.phi_inf;
        for (int k = 1; k <= N; ++k) {
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            dev[k] = (double)rig.s.shaft_twist - m.phi_inf;
        }
        double first = -1.0, last = -1.0;
        int crossings = 0;
        for (int k = 1; k <= N; ++k)
            if ((dev[k - 1] < 0.0) != (dev[k] < 0.0)) {
                const double t = ((k - 1) + dev[k - 1] / (dev[k - 1] - dev[k])) * dt;
                if (first < 0.0) first = t;
                last = t;
                ++crossings;
            }
        const double f_ring = 0.5 * (crossings - 1) / (last - first);
        const double f_want = omega_n * sqrt(1.0 - zeta * zeta) / (2.0 * TEST_PI);
        print_message("%s compliant mesh: ring %.4f Hz (closed form %.4f)\n", rack ? "rack" : "gear", f_ring, f_want);
        ASSERT_NEAR(f_ring, f_want, 0.005, 0.0);
        for (int k = 0; k < 3000; ++k)
            gs_rig_step(&rig.c, &rig.s, &in, &out);
        ASSERT_NEAR(rig.s.shaft_twist, m.phi_inf, TOL_ACC, 0.0);
        ASSERT_NEAR(out.base_torque, -m.a * m.load, TOL_ACC, 0.0);
    }
}

/* The overdamped twist x(t) = phi(t) - phi_inf from rest (x(0) = -phi_inf,
 * x'(0) = 0) of J x'' + C x' + K x = 0 with real roots s1, s2. */
static double overdamped(double j, double c, double k, double x0, double t)
{
    const double disc = sqrt(c * c - 4.0 * j * k);
    const double s1 = (-c + disc) / (2.0 * j), s2 = (-c - disc) / (2.0 * j);
    return x0 * (s2 * exp(s1 * t) - s1 * exp(s2 * t)) / (s2 - s1);
}

/* Drive at rest, a load below the friction level on the follower behind
 * the mesh: regularised, the follower creeps until the spring carries the
 * whole load (phi -> phi_inf), along the overdamped closed form with the
 * friction's damper 4F/v_th in series with the spring; set-valued, it never
 * moves and the spring stays unloaded. */
static void test_compliant_mesh_creep(void **state)
{
    /* dt resolves the friction's fast pole -(4F/v_th)/J_F (-1600 1/s on the gear) */
    const double dt = 1e-4, coulomb_ratio = 20.0;
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int regularised = 0; regularised <= 1; ++regularised) {
            gs_rig_params rp;
            const double load = rack ? 3.0 : 0.4;
            /* overdamped: the friction's damper 4F/v_th above 2 J_F omega_n */
            const double v_th = rack ? 0.04 : 0.4;
            const double coulomb = coulomb_ratio * load;
            const mesh_case m = mesh_setup(rack, 2.0 * TEST_PI * 30.0, 0.0, load, &rp);
            rp.load_coulomb_friction = R(coulomb);
            rp.load_coulomb_speed_threshold = R(v_th);
            rp.load_friction_regularised = regularised;
            rp.dt_s = R(dt);
            test_rig rig;
            make_rig(&rig, rack, 0, 0.0, &rp);
            gs_rig_info info;
            gs_rig_get_info(&rig.c, &info);
            const gs_rig_input in = rig_speed_input(0.0, load);
            gs_rig_output out;
            const double c_base = m.a * m.a * 4.0 * coulomb / v_th;
            double worst = 0.0, v_max = 0.0;
            for (int n = 1; n <= 3000; ++n) {
                gs_rig_step(&rig.c, &rig.s, &in, &out);
                v_max = dmax(v_max, fabs((double)out.follower_speed));
                if (!regularised) {
                    assert_true(is_zero((double)out.follower_speed));
                    assert_true(is_zero((double)rig.s.shaft_twist));
                    continue;
                }
                const double want = m.phi_inf + overdamped(m.j_eff, c_base, m.k, -m.phi_inf, n * dt);
                worst = dmax(worst, fabs((double)rig.s.shaft_twist - want) / fabs(m.phi_inf));
            }
            if (regularised) {
                print_message("%s compliant mesh creep: worst twist error %.3g of phi_inf, %d sub-steps, "
                              "max |v| %.3g of v_th/4\n",
                              rack ? "rack" : "gear", worst, info.compliance_substeps, v_max / (0.25 * v_th));
                /* the linear range of the friction: tanh(x) = x to 1e-3 here */
                assert_true(v_max < 0.06 * 0.25 * v_th);
                assert_true(worst < 5e-3);
            }
        }
}

/* Regularised friction inside the compliant mesh only ever takes energy out:
 * drive at rest, no load, an initial twist, friction in and beyond its
 * linear range; spring plus kinetic energy never rises, and the block's
 * power balance holds in each step. */
static void test_compliant_mesh_passive(void **state)
{
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        gs_rig_params rp;
        mesh_case m = mesh_setup(rack, 2.0 * TEST_PI * 60.0, 0.0, rack ? 30.0 : 4.0, &rp);
        rp.load_coulomb_friction = R(rack ? 5.0 : 0.7);
        rp.load_coulomb_speed_threshold = R(rack ? 1e-3 : 1e-2);
        rp.load_friction_regularised = 1;
        test_rig rig;
        make_rig(&rig, rack, 0, 0.0, &rp);
        const gs_rig_input loaded = rig_speed_input(0.0, 5.0 * m.load);
        const gs_rig_input free_in = rig_speed_input(0.0, 0.0);
        gs_rig_output out;
        for (int k = 0; k < 40; ++k)
            gs_rig_step(&rig.c, &rig.s, &loaded, &out);
        double e_prev = 0.0, e0 = 0.0;
        for (int k = 0; k < 2000; ++k) {
            gs_rig_step(&rig.c, &rig.s, &free_in, &out);
            const double w = (double)rig.s.base_speed, phi = (double)rig.s.shaft_twist;
            const double e = 0.5 * m.j_eff * w * w + 0.5 * m.k * phi * phi;
            if (k == 0)
                e0 = e;
            else
                ASSERT_LE(e, e_prev, TOL_ENERGY * e0);
            e_prev = e;
            const double scale = fabs((double)out.base_port_torque * (double)out.base_speed) +
                                 fabs((double)out.follower_port_torque * (double)out.follower_speed);
            ASSERT_NEAR(out.port_power, out.loss_power, 0.0, 256.0 * GS_EPS * scale + 1e-300);
        }
        assert_true(e0 > 0.0);
        assert_true(e_prev < 1e-3 * e0);
    }
}

/* ---- Step-mean speed ---- */

/* A linear speed ramp alpha*t_k on the speed-driven rigid rig with viscous
 * mu_F and follower inertia J_F, no loss, no load: with base_speed_ramp the
 * drive pays a^2*(J_F*alpha + mu_F*(w_{k-1} + w_k)/2) and the angle is
 * alpha*t^2/2 exactly; without it, a^2*(J_F*alpha + mu_F*w_k). The speeds
 * reported are the samples either way. */
static void test_step_mean_speed(void **state)
{
    const double dt = 1e-3, alpha = 40.0, mu_f = 0.3;
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int ramp = 0; ramp <= 1; ++ramp) {
            gs_rig_params rp = gs_rig_params_default();
            rp.driven_inertia = R(rack ? 3.0 : 0.04);
            rp.base_speed_ramp = ramp;
            test_rig rig;
            make_rig(&rig, rack, 0, mu_f, &rp);
            const double a = follower_per_base(rack), j_f = (double)rp.driven_inertia;
            gs_rig_output out;
            const gs_rig_input rest = rig_speed_input(0.0, 0.0);
            gs_rig_step(&rig.c, &rig.s, &rest, &out);
            for (int k = 1; k <= 50; ++k) {
                const double w_prev = alpha * (k - 1) * dt, w = alpha * k * dt;
                const gs_rig_input in = rig_speed_input(w, 0.0);
                gs_rig_step(&rig.c, &rig.s, &in, &out);
                const double w_terms = ramp ? 0.5 * (w_prev + w) : w;
                ASSERT_NEAR(out.base_torque, a * a * (j_f * alpha + mu_f * w_terms), TOL_REL * 100.0, 0.0);
                ASSERT_NEAR(out.base_speed, w, TOL_REL, 0.0);
                ASSERT_NEAR(out.follower_speed, a * w, TOL_REL, 0.0);
                if (ramp) ASSERT_NEAR(out.base_angle, 0.5 * alpha * (k * dt) * (k * dt), TOL_ACC, 0.0);
                /* the block's power balance at the speed the terms used */
                ASSERT_NEAR(out.port_power, out.loss_power, 0.0,
                            256.0 * GS_EPS * fabs((double)out.base_port_torque * w_terms) + 1e-300);
            }
        }
}

/* The switches' defaults leave both off. */
static void test_defaults_off(void **state)
{
    const gs_rig_params rp = gs_rig_params_default();
    (void)state;
    assert_int_equal(rp.load_friction_regularised, 0);
    assert_int_equal(rp.base_speed_ramp, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_creep_under_load),     cmocka_unit_test(test_free_deceleration),
        cmocka_unit_test(test_mesh_loss_creeps),     cmocka_unit_test(test_compliant_mesh_ring),
        cmocka_unit_test(test_compliant_mesh_creep), cmocka_unit_test(test_compliant_mesh_passive),
        cmocka_unit_test(test_step_mean_speed),      cmocka_unit_test(test_defaults_off),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
