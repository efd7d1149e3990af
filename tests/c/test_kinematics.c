/*
 * test_kinematics.c - kinematics, signs, inertia terms and tooth
 * parameterization (docs/physics.md sections 1, 6, 11; rig.h).
 *
 * Hand relations used:
 *   gear:  omega_F = s*omega_B/g  (1.1), ideal tau_B = -s*tau_F/g (1.2)
 *   rack:  v_R = s_R*r_P*omega_P (6.1), ideal tau_P = -s_R*r_P*F_R (6.3)
 *   tooth: r_P = N_P*x_R/(2*pi) (6.2)
 *   rig:   tau_F = load + offset - C*tanh(4*omega_F/omega_th) - J_F*alpha_F,
 *          base_torque = tau_B + J_B*alpha_B (speed-driven),
 *          alpha_B = T/(J_B + J_F/(eta*g^2)) (torque-driven, base driving).
 */
#include "test_common.h"

static gs_simple_gear_params ideal_gear(double g, gs_output_rotation rot)
{
    gs_simple_gear_params p = gs_simple_gear_params_default();
    p.teeth_ratio = R(g);
    p.output_shaft_rotates = rot;
    p.friction_model = GS_FRICTION_NONE;
    return p;
}

/* Speed-driven gear rig at constant base speed: follower speed and sign,
 * ideal torque transfer, angles, both output_shaft_rotates options and both
 * speed signs. */
static void test_gear_rig_speed_driven_signs(void **state)
{
    const gs_output_rotation rots[2] = {GS_ROTATES_SAME, GS_ROTATES_OPPOSITE};
    const double speeds[2] = {7.5, -3.25};
    const double g = 2.5, load = 0.8;
    int ir, iw, k;
    (void)state;
    for (ir = 0; ir < 2; ++ir) {
        for (iw = 0; iw < 2; ++iw) {
            gs_simple_gear_params gp = ideal_gear(g, rots[ir]);
            gs_rig_params rp = gs_rig_params_default();
            test_rig rig;
            gs_rig_output out, prev;
            const double s = gear_sign(rots[ir]);
            const double wB = speeds[iw];
            const gs_rig_input in = rig_speed_input(wB, load);
            double dt;
            rp.driven_inertia = R(0.05);
            INIT_GEAR_RIG(&rig, &gp, &rp);
            dt = (double)rp.dt_s;
            memset(&prev, 0, sizeof prev);
            for (k = 1; k <= 6; ++k) {
                gs_rig_step(&rig.c, &rig.s, &in, &out);
                ASSERT_NEAR(out.base_speed, wB, TOL_REL, 0.0);
                ASSERT_NEAR(out.follower_speed, s * (double)in.base_speed / g, TOL_REL, 0.0);
                /* rigid mesh from a common zero: theta_F = s*theta_B/g */
                ASSERT_NEAR(out.follower_position, s * (double)out.base_angle / g, TOL_REL, 1e-12);
                if (k >= 2) {
                    ASSERT_NEAR((double)out.base_angle - (double)prev.base_angle, wB * dt, TOL_ACC, 0.0);
                    ASSERT_NEAR(out.follower_acceleration, 0.0, 0.0, 1e-9);
                    ASSERT_NEAR(out.follower_port_torque, load, TOL_REL, 0.0);
                    ASSERT_NEAR(out.base_port_torque, -s * load / g, TOL_REL, 0.0);
                    ASSERT_NEAR(out.base_torque, -s * load / g, TOL_REL, 0.0);
                    /* ideal gear: no loss, port powers cancel */
                    ASSERT_NEAR(out.mesh_loss_power, 0.0, 0.0, 1e-12);
                    ASSERT_NEAR(out.loss_power, 0.0, 0.0, 1e-12);
                    ASSERT_NEAR(out.port_power, 0.0, 0.0, TOL_REL * fabs(load * wB));
                }
                prev = out;
            }
            /* the drive supplies power iff the load opposes the follower */
            assert_true(((double)out.base_torque * wB > 0.0) == (load * (double)out.follower_speed < 0.0));
        }
    }
}

/* The block alone (form A): follower speed and ideal torque transfer. */
static void test_gear_block_signs(void **state)
{
    const gs_output_rotation rots[2] = {GS_ROTATES_SAME, GS_ROTATES_OPPOSITE};
    const double g = 3.0;
    int ir;
    (void)state;
    for (ir = 0; ir < 2; ++ir) {
        gs_simple_gear_params gp = ideal_gear(g, rots[ir]);
        test_gear gear;
        gs_gear_ports_in in;
        gs_gear_ports_out out;
        const double s = gear_sign(rots[ir]);
        INIT_GEAR(&gear, &gp);
        memset(&in, 0, sizeof in);
        in.base_speed_rad_s = R(-12.0);
        in.follower_torque_Nm = R(-4.5);
        gs_simple_gear_step(&gear.c, &gear.s, R(1e-3), &in, &out);
        ASSERT_NEAR(out.follower_speed_rad_s, s * -12.0 / g, TOL_REL, 0.0);
        ASSERT_NEAR(out.base_torque_Nm, -s * -4.5 / g, TOL_REL, 0.0);
        ASSERT_NEAR(out.follower_torque_Nm, -4.5, TOL_REL, 0.0);
        ASSERT_NEAR(out.mesh_loss_torque_Nm, 0.0, 0.0, 1e-12);
        ASSERT_NEAR(out.loss_power_W, 0.0, 0.0, 1e-12);
    }
}

/* Rack rig and block: v_R = s_R*r_P*omega_P, tau_P = -s_R*r_P*F_R, both rack
 * directions and both speed signs. */
static void test_rack_signs(void **state)
{
    const gs_rack_direction dirs[2] = {GS_RACK_POSITIVE, GS_RACK_NEGATIVE};
    const double speeds[2] = {9.0, -2.5};
    const double r = 0.05, force = 40.0;
    int id, iw, k;
    (void)state;
    for (id = 0; id < 2; ++id) {
        for (iw = 0; iw < 2; ++iw) {
            gs_rack_pinion_params pp = gs_rack_pinion_params_default();
            gs_rig_params rp = gs_rig_params_default();
            test_rig rig;
            gs_rig_output out;
            test_rack blk;
            gs_rack_ports_in bin;
            gs_rack_ports_out bout;
            const double sR = rack_sign(dirs[id]);
            const double wP = speeds[iw];
            const gs_rig_input in = rig_speed_input(wP, force);
            pp.parameterization = GS_PARAMETERIZE_PINION_RADIUS;
            pp.pinion_radius_m = R(r);
            pp.rack_directionality = dirs[id];
            pp.friction_model = GS_FRICTION_NONE;
            rp.driven_inertia = R(3.0);
            INIT_RACK_RIG(&rig, &pp, &rp);
            for (k = 1; k <= 5; ++k)
                gs_rig_step(&rig.c, &rig.s, &in, &out);
            ASSERT_NEAR(out.follower_speed, sR * r * wP, TOL_REL, 0.0);
            ASSERT_NEAR(out.follower_position, sR * r * (double)out.base_angle, TOL_REL, 1e-12);
            ASSERT_NEAR(out.follower_acceleration, 0.0, 0.0, 1e-9);
            ASSERT_NEAR(out.follower_port_torque, force, TOL_REL, 0.0);
            ASSERT_NEAR(out.base_port_torque, -sR * r * force, TOL_REL, 0.0);
            ASSERT_NEAR(out.port_power, 0.0, 0.0, TOL_REL * fabs(force * r * wP));

            INIT_RACK(&blk, &pp);
            memset(&bin, 0, sizeof bin);
            bin.pinion_speed_rad_s = R(wP);
            bin.rack_force_N = R(-force);
            gs_rack_pinion_step(&blk.c, &blk.s, R(1e-3), &bin, &bout);
            ASSERT_NEAR(bout.rack_velocity_m_s, sR * r * wP, TOL_REL, 0.0);
            ASSERT_NEAR(bout.pinion_torque_Nm, sR * r * force, TOL_REL, 0.0);
            ASSERT_NEAR(bout.rack_force_N, -force, TOL_REL, 0.0);
        }
    }
}

/* r_P = N_P*x_R/(2*pi), from the helper and through the kinematics. */
static void test_tooth_parameterization(void **state)
{
    const double teeth[3] = {20.0, 37.0, 12.0};
    const double spacing[3] = {0.005, 0.0031, 0.0125};
    int i, k;
    (void)state;
    for (i = 0; i < 3; ++i) {
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig;
        gs_rig_output out;
        double r;
        const gs_rig_input in = rig_speed_input(6.0, -15.0);
        pp.parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS;
        pp.teeth_count = R(teeth[i]);
        pp.spacing_m = R(spacing[i]);
        pp.pinion_radius_m = R(0.3); /* must be ignored */
        pp.rack_directionality = (i == 1) ? GS_RACK_NEGATIVE : GS_RACK_POSITIVE;
        r = (double)pp.teeth_count * (double)pp.spacing_m / (2.0 * TEST_PI);
        ASSERT_NEAR(gs_rack_pinion_radius(&pp), r, TOL_REL, 0.0);
        INIT_RACK_RIG(&rig, &pp, &rp);
        for (k = 1; k <= 4; ++k)
            gs_rig_step(&rig.c, &rig.s, &in, &out);
        ASSERT_NEAR(out.follower_speed, rack_sign(pp.rack_directionality) * r * 6.0, TOL_REL, 0.0);
        ASSERT_NEAR(out.base_port_torque, -rack_sign(pp.rack_directionality) * r * -15.0, TOL_REL, 0.0);
    }
    {
        /* seed defaults: 20 teeth x 5 mm = 15.915 mm */
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        pp.parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS;
        ASSERT_NEAR(gs_rack_pinion_radius(&pp), 0.1 / (2.0 * TEST_PI), TOL_REL, 0.0);
        ASSERT_NEAR(gs_rack_pinion_radius(&pp), 0.015915, 0.0, 1e-6);
        pp.parameterization = GS_PARAMETERIZE_PINION_RADIUS;
        pp.pinion_radius_m = R(0.042);
        ASSERT_NEAR(gs_rack_pinion_radius(&pp), 0.042, TOL_REL, 0.0);
    }
}

/* Speed ramp: alpha from the backward difference, inertia, load offset and
 * the rig's tanh-smoothed Coulomb load in the driven-port torque; base inertia
 * in the drive torque. */
static void test_gear_rig_inertia_and_load_terms(void **state)
{
    const gs_output_rotation rots[2] = {GS_ROTATES_SAME, GS_ROTATES_OPPOSITE};
    const double g = 2.5, a = 40.0, JF = 0.05, JB = 0.02, load = 1.5, offset = -0.3;
    const double coul = 0.4, wth = 0.5;
    int ir, k;
    (void)state;
    for (ir = 0; ir < 2; ++ir) {
        gs_simple_gear_params gp = ideal_gear(g, rots[ir]);
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig;
        gs_rig_output out;
        double s = gear_sign(rots[ir]), dt, prev_w = 0.0;
        rp.driven_inertia = R(JF);
        rp.base_inertia_kg_m2 = R(JB);
        rp.load_offset = R(offset);
        rp.load_coulomb_friction = R(coul);
        rp.load_coulomb_speed_threshold = R(wth);
        rp.accel_filter_time_constant_s = R(0.0);
        INIT_GEAR_RIG(&rig, &gp, &rp);
        dt = (double)rp.dt_s;
        for (k = 0; k < 60; ++k) {
            /* slow start through zero speed so the Coulomb tanh is exercised */
            const gs_rig_input in = rig_speed_input(-0.2 + a * k * dt, load);
            const double wB = (double)in.base_speed;
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            if (k >= 2) {
                const double alphaB = (wB - prev_w) / dt;
                const double wF = s * wB / g;
                const double alphaF = s * alphaB / g;
                const double tauF = load + (double)rp.load_offset -
                                    (double)rp.load_coulomb_friction * tanh(4.0 * wF / wth) - JF * alphaF;
                const double tauB = -s * tauF / g;
                ASSERT_NEAR(out.follower_acceleration, alphaF, 1e-9, 8.0 * GS_EPS * 3.0 / dt);
                ASSERT_NEAR(out.follower_port_torque, tauF, 1e-9, 8.0 * GS_EPS * 3.0 / dt);
                ASSERT_NEAR(out.base_port_torque, tauB, 1e-9, 8.0 * GS_EPS * 3.0 / dt);
                ASSERT_NEAR(out.base_torque, tauB + JB * alphaB, 1e-9, 8.0 * GS_EPS * 3.0 / dt);
            }
            prev_w = wB;
        }
    }
}

/* First-order filter on the base acceleration: time constant tau. After a
 * ramp starts, the filtered acceleration reaches 1 - 1/e (0.632, discretised
 * 0.58-0.68) of the ramp's acceleration after tau and converges to it. */
static void test_accel_filter_time_constant(void **state)
{
    gs_simple_gear_params gp = ideal_gear(2.0, GS_ROTATES_SAME);
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double a = 50.0;
    double dt, tau, tol;
    int k, ramp = 0;
    (void)state;
    rp.dt_s = R(1e-3);
    rp.accel_filter_time_constant_s = R(0.01); /* 10 steps */
    INIT_GEAR_RIG(&rig, &gp, &rp);
    dt = (double)rp.dt_s;
    tau = (double)rp.accel_filter_time_constant_s;
    /* rounding of the speeds (up to 20 rad/s) in the backward difference */
    tol = 1e-6 + 100.0 * GS_EPS * 20.0 / (a * dt);
    for (k = 0; k < 20; ++k) {
        const gs_rig_input in = rig_speed_input(0.0, 0.0);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        ASSERT_NEAR(out.follower_acceleration, 0.0, 0.0, 1e-12);
    }
    for (ramp = 1; ramp <= 400; ++ramp) {
        const gs_rig_input in = rig_speed_input(a * ramp * dt, 0.0);
        const double alphaF = a / 2.0; /* s = +1, g = 2 */
        double ratio;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        ratio = (double)out.follower_acceleration / alphaF;
        /* a low-pass never overshoots a step */
        assert_true(ratio > 0.0);
        ASSERT_LE(ratio, 1.0, tol);
        if (ramp == 1) assert_true(ratio < 0.5); /* filtered, not the raw difference */
        if (ramp == (int)(tau / dt + 0.5)) {
            assert_true(ratio > 0.58);
            assert_true(ratio < 0.68);
        }
        if (ramp == 400) ASSERT_NEAR(ratio, 1.0, tol, 0.0);
    }
}

/* Torque-driven rigid rig: alpha_B = T/(J_B + J_F/g^2) without losses;
 * with constant efficiency the follower inertia is divided by eta when the
 * base drives (accelerating) and multiplied by eta when the follower drives
 * (decelerating, its kinetic energy flows back to the base). */
static void run_torque_driven(gs_output_rotation rot, gs_friction_model fm, double eta, double w0, double motor,
                              double expected_alpha)
{
    gs_simple_gear_params gp = ideal_gear(2.0, rot);
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double JB = 0.01, JF = 0.05;
    double s = gear_sign(rot), dt, prev_w = w0;
    int k;
    gp.friction_model = fm;
    gp.efficiency_const = R(eta);
    gp.power_threshold_W = R(1e-6);
    rp.base_drive = GS_BASE_TORQUE_DRIVEN;
    rp.base_inertia_kg_m2 = R(JB);
    rp.driven_inertia = R(JF);
    rp.initial_base_speed_rad_s = R(w0);
    rp.dt_s = R(1e-2);
    INIT_GEAR_RIG(&rig, &gp, &rp);
    dt = (double)rp.dt_s;
    for (k = 1; k <= 30; ++k) {
        const gs_rig_input in = rig_torque_input(motor, 0.0);
        double wB, alpha;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        wB = (double)out.base_speed;
        alpha = (wB - prev_w) / dt;
        ASSERT_NEAR(out.follower_speed, s * wB / 2.0, TOL_REL, 1e-12);
        ASSERT_NEAR(out.base_torque, motor, TOL_REL, 0.0);
        if (k >= 3) {
            ASSERT_NEAR(alpha, expected_alpha, 1e-7, 16.0 * GS_EPS * fabs(wB) / dt);
            /* Newton on the base shaft: J_B*alpha_B = T - tau_B */
            ASSERT_NEAR(out.base_port_torque, motor - JB * alpha, 1e-7, 16.0 * GS_EPS * fabs(wB) / dt * JB);
            ASSERT_NEAR(out.follower_acceleration, s * alpha / 2.0, 1e-7, 16.0 * GS_EPS * fabs(wB) / dt);
        }
        prev_w = wB;
    }
}

static void test_torque_driven_acceleration(void **state)
{
    const double JB = 0.01, JF = 0.05, g = 2.0, eta = 0.9;
    (void)state;
    /* ideal, from rest and from a speed, both rotation senses */
    run_torque_driven(GS_ROTATES_SAME, GS_FRICTION_NONE, 1.0, 0.0, 0.6, 0.6 / (JB + JF / (g * g)));
    run_torque_driven(GS_ROTATES_OPPOSITE, GS_FRICTION_NONE, 1.0, 3.0, -0.6, -0.6 / (JB + JF / (g * g)));
    /* base drives the follower inertia up: J_F/(eta*g^2) */
    run_torque_driven(GS_ROTATES_SAME, GS_FRICTION_CONSTANT_EFFICIENCY, eta, 5.0, 1.0, 1.0 / (JB + JF / (eta * g * g)));
    run_torque_driven(GS_ROTATES_OPPOSITE, GS_FRICTION_CONSTANT_EFFICIENCY, eta, -5.0, -1.0,
                      -1.0 / (JB + JF / (eta * g * g)));
    /* braking: the follower's kinetic energy drives the base: eta*J_F/g^2 */
    run_torque_driven(GS_ROTATES_SAME, GS_FRICTION_CONSTANT_EFFICIENCY, eta, 50.0, -1.0,
                      -1.0 / (JB + eta * JF / (g * g)));
    run_torque_driven(GS_ROTATES_OPPOSITE, GS_FRICTION_CONSTANT_EFFICIENCY, eta, -50.0, 1.0,
                      1.0 / (JB + eta * JF / (g * g)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gear_rig_speed_driven_signs),
        cmocka_unit_test(test_gear_block_signs),
        cmocka_unit_test(test_rack_signs),
        cmocka_unit_test(test_tooth_parameterization),
        cmocka_unit_test(test_gear_rig_inertia_and_load_terms),
        cmocka_unit_test(test_accel_filter_time_constant),
        cmocka_unit_test(test_torque_driven_acceleration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
