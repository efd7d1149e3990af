/*
 * test_backlash.c - backlash and hard-stop contact (docs/physics.md section 4,
 * rig.h).
 *
 *  v = r_B*omega_B - s*r_F*omega_F, r_F = g*r_B (4.1); dx/dt = v (4.2)
 *  lost motion from the centre: t = (b/2)/v
 *  contact laws (4.3) full damped, (4.4) full undamped (damping only while
 *  the teeth close), (4.5) smooth (cubic step S over the transition region),
 *  optional no-pull clip; tooth torques T_B = r_B*f, T_F0 = -s*r_F*f (4.6)
 *  rebound: a conservative contact (D = 0) returns the impact speed;
 *  damping lowers the rebound, full_damped more than full_undamped.
 *  Newton on the follower: J_F*domega_F/dt = load - tau_F, tau_F = -s*r_F*f.
 */
#include "test_common.h"

static const gs_hard_stop_model hard_stop_models[3] = {GS_HARD_STOP_SMOOTH, GS_HARD_STOP_FULL_UNDAMPED,
                                                       GS_HARD_STOP_FULL_DAMPED};

static double cubic_step(double xi)
{
    return xi * xi * (3.0 - 2.0 * xi);
}

/* Hand contact law f(x, v) of physics.md 4.3-4.5 with the no-pull clip. */
static double contact_law(gs_hard_stop_model m, int no_pull, double K, double D, double d, double hb, double x,
                          double v)
{
    double f = 0.0;
    if (x >= hb) {
        const double pen = x - hb;
        if (m == GS_HARD_STOP_SMOOTH)
            f = cubic_step(pen / d < 1.0 ? pen / d : 1.0) * (K * pen + D * v);
        else if (m == GS_HARD_STOP_FULL_UNDAMPED)
            f = K * pen + (v >= 0.0 ? D * v : 0.0);
        else
            f = K * pen + D * v;
        if (no_pull && f < 0.0) f = 0.0;
    } else if (x <= -hb) {
        const double pen = x + hb; /* <= 0 */
        if (m == GS_HARD_STOP_SMOOTH)
            f = cubic_step(-pen / d < 1.0 ? -pen / d : 1.0) * (K * pen + D * v);
        else if (m == GS_HARD_STOP_FULL_UNDAMPED)
            f = K * pen + (v <= 0.0 ? D * v : 0.0);
        else
            f = K * pen + D * v;
        if (no_pull && f > 0.0) f = 0.0;
    }
    return f;
}

static gs_simple_gear_params backlash_gear(double g, gs_output_rotation rot, gs_hard_stop_model m, double b, double rB,
                                           double K, double D)
{
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gp.teeth_ratio = R(g);
    gp.output_shaft_rotates = rot;
    gp.friction_model = GS_FRICTION_NONE;
    gp.backlash.enabled = 1;
    gp.backlash.hard_stop_model = m;
    gp.backlash.linear_backlash_m = R(b);
    gp.backlash.base_radius_m = R(rB);
    gp.backlash.transition_region_m = R(1e-4);
    gp.backlash.stiffness_N_m = R(K);
    gp.backlash.damping_N_s_m = R(D);
    gp.backlash.initial_position_m = R(0.0);
    gp.backlash.no_pull = 1;
    return gp;
}

/* ---- Block level: explicit Euler position and the contact laws. */
static void run_block_contact(gs_hard_stop_model m, int no_pull, int lower)
{
    const double g = 2.0, rB = 0.05, b = 1e-3, K = 1e5, D = 200.0, dt = 1e-3, wF = 0.1;
    gs_simple_gear_params gp = backlash_gear(g, GS_ROTATES_OPPOSITE, m, b, rB, K, D);
    test_gear gear;
    gs_gear_ports_in in;
    gs_gear_ports_out out;
    const double s = -1.0, rF = g * rB;
    double hb, x_before, d, Kd, Dd;
    int k, conv = 0, contacts = 0;
    const double side = lower ? -1.0 : 1.0;
    gp.backlash.no_pull = no_pull;
    gp.viscous_coefficients[0] = R(0.01);
    gp.viscous_coefficients[1] = R(0.02);
    gp.backlash.initial_position_m = R(side * (b / 2.0 - 3.5e-5));
    INIT_GEAR(&gear, &gp);
    hb = 0.5 * (double)gp.backlash.linear_backlash_m;
    d = (double)gp.backlash.transition_region_m;
    Kd = (double)gp.backlash.stiffness_N_m;
    Dd = (double)gp.backlash.damping_N_s_m;
    x_before = (double)gp.backlash.initial_position_m;
    memset(&in, 0, sizeof in);
    for (k = 0; k < 26; ++k) {
        /* 12 steps closing (+-0.02 m/s) past the transition region, then 14 opening */
        const double v_cmd = side * (k < 12 ? 0.02 : -0.02);
        double v, f_before, f_after, f, x_after, tol;
        int mb, ma;
        in.follower_speed_rad_s = R(wF);
        in.base_speed_rad_s = R((v_cmd + s * rF * wF) / rB);
        v = rB * (double)in.base_speed_rad_s - s * rF * (double)in.follower_speed_rad_s;
        gs_simple_gear_step(&gear.c, &gear.s, R(dt), &in, &out);
        x_after = (double)out.backlash_position_m;
        ASSERT_NEAR(x_after, x_before + dt * v, 0.0, 8.0 * GS_EPS * b);
        f_before = contact_law(m, no_pull, Kd, Dd, d, hb, x_before, v);
        f_after = contact_law(m, no_pull, Kd, Dd, d, hb, x_after, v);
        f = (double)out.contact_force_N;
        tol = TOL_REL * (Kd * b + Dd * fabs(v)) + 16.0 * GS_EPS * (Kd * b + Dd * fabs(v));
        mb = near_enough(f, f_before, 0.0, tol);
        ma = near_enough(f, f_after, 0.0, tol);
        if (!mb && !ma) {
            print_error("step %d: x %.9g -> %.9g, v %.6g: f = %.12g, law gives %.12g (x before) or "
                        "%.12g (x after)\n",
                        k, x_before, x_after, v, f, f_before, f_after);
            fail();
        }
        /* one convention for the whole run */
        if (mb && !ma) {
            assert_true(conv != 2);
            conv = 1;
        }
        if (ma && !mb) {
            assert_true(conv != 1);
            conv = 2;
        }
        if (!is_zero(f)) ++contacts;
        /* tooth torques (4.6) plus viscous terms */
        ASSERT_NEAR(out.base_torque_Nm, rB * f + 0.01 * (double)in.base_speed_rad_s, TOL_REL, tol * rB);
        ASSERT_NEAR(out.follower_torque_Nm, -s * rF * f + 0.02 * wF, TOL_REL, tol * rF);
        x_before = x_after;
    }
    assert_true(contacts >= 10);
}

static void test_block_contact_laws(void **state)
{
    int m, np, lower;
    (void)state;
    for (m = 0; m < 3; ++m)
        for (np = 0; np < 2; ++np)
            for (lower = 0; lower < 2; ++lower)
                run_block_contact(hard_stop_models[m], np, lower);
}

/* Contact, first seen in step k_contact (1-based), starts in that step, i.e.
 * t_contact lies in ((k_contact - 1)*dt, k_contact*dt]. */
static void assert_contact_step(const char *what, int k_contact, double dt, double t_contact)
{
    if (k_contact < 0) fail_msg("%s: no contact within 400 steps (expected at %.4f s)", what, t_contact);
    if (!(k_contact * dt >= t_contact - 1e-9 && (k_contact - 1) * dt <= t_contact + dt)) {
        print_error("%s: contact in step %d (t = %.4f s), expected %.4f s = (b/2)/(r_B*omega_B)\n", what, k_contact,
                    k_contact * dt, t_contact);
        fail();
    }
}

/* ---- Rig: lost motion. The base turns at constant speed, the follower rests
 * centred in the gap; contact after (b/2)/(r_B*omega_B). Then the base carries
 * the follower (held against the flank by a drag on the driven side). */
static void test_lost_motion_gear(void **state)
{
    const gs_output_rotation rots[2] = {GS_ROTATES_SAME, GS_ROTATES_OPPOSITE};
    int ir, k;
    (void)state;
    for (ir = 0; ir < 2; ++ir) {
        const double g = 2.0, rB = 0.1, b = 2e-3;
        gs_simple_gear_params gp = backlash_gear(g, rots[ir], GS_HARD_STOP_FULL_DAMPED, b, rB, 1e6, 1e3);
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig;
        gs_rig_output out;
        const double s = gear_sign(rots[ir]);
        const double t_contact = 0.1005;
        const double wB = (b / 2.0) / (rB * t_contact);
        double dt, x_prev = 0.0, v;
        int k_contact = -1;
        gs_rig_input in;
        rp.dt_s = R(1e-3);
        /* a drag on the follower keeps the teeth together after the impact;
         * it is tanh-smoothed, so it is exactly zero while the follower rests */
        rp.load_coulomb_friction = R(0.5);
        rp.load_coulomb_speed_threshold = R(1e-2);
        INIT_GEAR_RIG(&rig, &gp, &rp);
        dt = (double)rp.dt_s;
        /* the rig's first sample sets both speeds (teeth moving together,
         * rig.c): start from rest, then hold omega_B from t = 0 */
        {
            const gs_rig_input rest = rig_speed_input(0.0, 0.0);
            gs_rig_step(&rig.c, &rig.s, &rest, &out);
            ASSERT_NEAR(out.follower_speed, 0.0, 0.0, 0.0);
            ASSERT_NEAR(out.backlash_position, 0.0, 0.0, 0.0);
        }
        in = rig_speed_input(wB, 0.0);
        v = rB * (double)in.base_speed; /* the follower rests */
        for (k = 1; k <= 400; ++k) {
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            assert_true(rig_output_finite(&out));
            if (k_contact < 0) {
                if (!is_zero((double)out.contact_force) || !is_zero((double)out.follower_speed)) {
                    k_contact = k;
                } else if (k >= 2) {
                    /* free play: x advances by v*dt, nothing moves the follower */
                    ASSERT_NEAR((double)out.backlash_position - x_prev, v * dt, 1e-9, 8.0 * GS_EPS * b);
                    ASSERT_NEAR(out.contact_energy, 0.0, 0.0, 0.0);
                    ASSERT_NEAR(out.base_port_torque, 0.0, 0.0, 0.0);
                }
            }
            x_prev = (double)out.backlash_position;
        }
        assert_contact_step("lost motion", k_contact, dt, t_contact);
        /* afterwards the base carries the follower: omega_F = s*omega_B/g */
        ASSERT_NEAR(out.follower_speed, s * wB / g, 1e-3, 0.0);
        assert_true((double)out.backlash_position > b / 2.0 - 1e-5);
    }
}

static void test_lost_motion_rack(void **state)
{
    const gs_rack_direction dirs[2] = {GS_RACK_POSITIVE, GS_RACK_NEGATIVE};
    int id, k;
    (void)state;
    for (id = 0; id < 2; ++id) {
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig;
        gs_rig_output out;
        const double r = 0.05, b = 1e-3, t_contact = 0.0805;
        const double wP = (b / 2.0) / (r * t_contact);
        double dt;
        int k_contact = -1;
        gs_rig_input in;
        pp.pinion_radius_m = R(r);
        pp.rack_directionality = dirs[id];
        pp.backlash = gs_simple_gear_params_default().backlash;
        pp.backlash.enabled = 1;
        pp.backlash.hard_stop_model = GS_HARD_STOP_FULL_DAMPED;
        pp.backlash.linear_backlash_m = R(b);
        pp.backlash.stiffness_N_m = R(1e6);
        pp.backlash.damping_N_s_m = R(2e3);
        pp.backlash.initial_position_m = R(0.0);
        rp.driven_inertia = R(2.0);
        rp.load_coulomb_friction = R(5.0);
        rp.load_coulomb_speed_threshold = R(1e-3);
        INIT_RACK_RIG(&rig, &pp, &rp);
        dt = (double)rp.dt_s;
        {
            const gs_rig_input rest = rig_speed_input(0.0, 0.0);
            gs_rig_step(&rig.c, &rig.s, &rest, &out);
        }
        in = rig_speed_input(wP, 0.0);
        for (k = 1; k <= 400; ++k) {
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            assert_true(rig_output_finite(&out));
            if (k_contact < 0 && (!is_zero((double)out.contact_force) || !is_zero((double)out.follower_speed)))
                k_contact = k;
        }
        assert_contact_step("rack lost motion", k_contact, dt, t_contact);
        ASSERT_NEAR(out.follower_speed, rack_sign(dirs[id]) * r * wP, 1e-3, 0.0);
    }
}

/* ---- Rig: a free follower (J_F) coasts into the lower flank of a base held
 * at zero speed. Returns -omega_after/omega_before. Also checks, every step,
 * Newton's law on the follower, and for D = 0 that kinetic plus contact
 * energy never exceeds the kinetic energy before the impact. */
typedef struct {
    double ratio;
    int pulled; /* a step whose mean contact force pulled (x > 0: f < 0; x < 0: f > 0) */
} impact_result;

static impact_result impact(gs_hard_stop_model m, double D, int no_pull, int substeps, int steps)
{
    const double g = 2.0, rB = 0.1, b = 1e-3, K = 1e4, JF = 0.01, pulse = 0.1;
    gs_simple_gear_params gp = backlash_gear(g, GS_ROTATES_SAME, m, b, rB, K, D);
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    impact_result res = {0.0, 0};
    const double s = 1.0, rF = g * rB;
    double dt, w_prev = 0.0, w_before = 0.0, ke_before = 0.0;
    int k, contact = 0, released = -1;
    gp.backlash.no_pull = no_pull;
    rp.dt_s = R(1e-3);
    rp.driven_inertia = R(JF);
    rp.contact_substeps = substeps;
    INIT_GEAR_RIG(&rig, &gp, &rp);
    dt = (double)rp.dt_s;
    for (k = 1; k <= steps; ++k) {
        const double load = k <= 5 ? pulse : 0.0;
        const gs_rig_input in = rig_speed_input(0.0, load);
        double w, f, x;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        assert_true(rig_output_finite(&out));
        w = (double)out.follower_speed;
        f = (double)out.contact_force;
        x = (double)out.backlash_position;
        /* Newton on the follower: J*dw/dt = load - tau_F, tau_F = -s*r_F*f */
        {
            const double scale = fabs(load) + rF * fabs(f) + 1e-6;
            ASSERT_NEAR(out.follower_port_torque, -s * rF * f, TOL_REL, 1e-12);
            /* rounding: the speed is accumulated over the sub-steps */
            ASSERT_NEAR(JF * (w - w_prev) / dt, load - (double)out.follower_port_torque, dmax(1e-7, TOL_REL),
                        1e-9 * scale + (substeps + 8) * GS_EPS * JF * (fabs(w) + fabs(w_prev)) / dt);
        }
        if ((x > 0.0 && f < 0.0) || (x < 0.0 && f > 0.0)) res.pulled = 1;
        if (k == 20) {
            w_before = w;
            ke_before = 0.5 * JF * w * w;
            assert_true(w > 0.0); /* moving towards the lower flank (v = -r_F*omega_F) */
            assert_true(contact == 0);
        }
        if (k > 20 && contact == 0) {
            if (!is_zero(f))
                contact = 1;
            else
                ASSERT_NEAR(w, w_before, 1e-9, 1e-12); /* coasting */
        }
        if (k > 20 && is_zero(D)) {
            /* conservative contact: nothing may be created */
            ASSERT_LE(0.5 * JF * w * w + (double)out.contact_energy, ke_before, TOL_ENERGY * ke_before + 1e-15);
        }
        if (contact == 1 && is_zero(f) && x > -b / 2.0) {
            contact = 2; /* separated */
            released = k;
        }
        if (contact == 2 && k == released + 2) {
            res.ratio = -w / w_before;
            return res;
        }
        w_prev = w;
    }
    if (steps >= 200) fail_msg("impact scenario did not complete (contact state %d)", contact);
    return res;
}

static void test_rebound_conservative(void **state)
{
    int m;
    (void)state;
    for (m = 0; m < 3; ++m) {
        const impact_result r = impact(hard_stop_models[m], 0.0, 1, 64, 200);
        print_message("hard stop %d, D = 0: rebound/impact speed = %.6f\n", (int)hard_stop_models[m], r.ratio);
        assert_true(r.ratio > 0.97);
        ASSERT_LE(r.ratio, 1.0, 1e-6);
    }
}

static void test_rebound_damping(void **state)
{
    impact_result undamped, damped;
    (void)state;
    /* zeta = D/(2*sqrt(K*m_eff)) = 20/(2*sqrt(1e4*0.25)) = 0.2 */
    undamped = impact(GS_HARD_STOP_FULL_UNDAMPED, 20.0, 1, 64, 200);
    damped = impact(GS_HARD_STOP_FULL_DAMPED, 20.0, 1, 64, 200);
    print_message("D = 20: full_undamped %.4f, full_damped %.4f\n", undamped.ratio, damped.ratio);
    assert_true(damped.ratio > 0.0);
    /* damping while closing still dissipates in the undamped-rebound model */
    assert_true(undamped.ratio < 0.97);
    assert_true(damped.ratio < undamped.ratio - 0.05);
}

/* no_pull = 1: the mean contact force never pulls (x > 0: f >= 0, x < 0:
 * f <= 0). The same scenario without the clip does pull, so the check bites. */
static void test_no_pull(void **state)
{
    const gs_hard_stop_model models[2] = {GS_HARD_STOP_FULL_DAMPED, GS_HARD_STOP_SMOOTH};
    int m;
    (void)state;
    for (m = 0; m < 2; ++m) {
        const impact_result with_clip = impact(models[m], 50.0, 1, 16, 150);
        const impact_result without = impact(models[m], 50.0, 0, 16, 150);
        assert_int_equal(with_clip.pulled, 0);
        assert_int_equal(without.pulled, 1);
    }
}

/* Stiff contact at a coarse step: K = 1e8 N/m, D = 1e4 N*s/m, dt = 1 ms,
 * J_F = 1e-4 kg*m^2 (omega_n*dt = 200). A reversing base speed
 * (amplitude W) drags the follower through the gap thousands of times.
 * Physical bounds: |omega_F| <= 2*W/g (a contact cannot return more than the
 * base tooth's speed plus the approach speed), penetration tiny, energy never
 * created, Newton's law on the follower. */
static void run_stiff(gs_hard_stop_model m, int substeps, double load_amp)
{
    const double g = 2.0, rB = 0.1, b = 1e-3, JF = 1e-4, W = 10.0;
    gs_simple_gear_params gp = backlash_gear(g, GS_ROTATES_OPPOSITE, m, b, rB, 1e8, 1e4);
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double s = -1.0, rF = g * rB;
    double dt, w_prev = 0.0, e_prev = 0.0, f_prev = 0.0;
    int k, contacts = 0;
    gp.backlash.transition_region_m = R(1e-5);
    rp.dt_s = R(1e-3);
    rp.driven_inertia = R(JF);
    rp.contact_substeps = substeps;
    INIT_GEAR_RIG(&rig, &gp, &rp);
    dt = (double)rp.dt_s;
    for (k = 1; k <= 4000; ++k) {
        const double t = (k - 1) * dt; /* first sample at rest (see lost motion) */
        const double load = load_amp * sin(2.0 * TEST_PI * 0.7 * t);
        const gs_rig_input in = rig_speed_input(W * sin(2.0 * TEST_PI * 2.0 * t), load);
        double w, f, e;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        assert_true(rig_output_finite(&out));
        w = (double)out.follower_speed;
        f = (double)out.contact_force;
        e = (double)out.contact_energy;
        if (!(fabs((double)out.backlash_position) <= b / 2.0 + 1e-5) ||
            (is_zero(load_amp) && !(fabs(w) <= 2.0 * W / g * (1.0 + 1e-6))))
            print_error("stiff contact, hard stop %d, substeps %d, load amplitude %g, step %d: "
                        "x %.9g m (prev. E %.6g J), f %.9g N, omega_B %.6g, omega_F %.6g -> %.6g, "
                        "E %.6g J\n",
                        (int)m, substeps, load_amp, k, (double)out.backlash_position, e_prev, f, (double)out.base_speed,
                        w_prev, w, e);
        if (is_zero(load_amp)) ASSERT_LE(fabs(w), 2.0 * W / g, 1e-6 * W);
        ASSERT_LE(fabs((double)out.backlash_position), b / 2.0 + 1e-5, 0.0);
        {
            const double scale = fabs(load) + rF * fabs(f) + 1e-6;
            ASSERT_NEAR(JF * (w - w_prev) / dt, load + s * rF * f, dmax(1e-6, TOL_REL),
                        1e-9 * scale + (16 + 8) * GS_EPS * JF * (fabs(w) + fabs(w_prev)) / dt);
        }
        {
            const double gross = (fabs((double)out.base_port_torque * (double)out.base_speed) +
                                  fabs((double)out.follower_port_torque * w)) *
                                 dt;
            /* + rounding of the stored energy: x is known to ~eps*b, so E to
             * ~|f|*eps*b (negligible in double, ~1e-11 J in float here) */
            ASSERT_LE((double)out.loss_power * dt + (e - e_prev), (double)out.port_power * dt,
                      TOL_ENERGY * (gross + e + e_prev) + 1e-15 + 4.0 * GS_EPS * b * (fabs(f) + fabs(f_prev)));
        }
        if (!is_zero(f)) ++contacts;
        w_prev = w;
        e_prev = e;
        f_prev = f;
    }
    assert_true(contacts > 100);
}

/* The rig's contact is backward Euler: with one sub-step h = dt, the force
 * of a step must equal the contact law at the END of the step,
 * f = law(x1, u) with u = (x1 - x0)/h. Checked against the hand law above
 * at every step. The solver never evaluates this law (closed forms for the
 * full laws, Newton on side-normalised variables for the smooth one), so
 * this is an independent check of its root. Where the law jumps (damping
 * switched on at first contact of the full laws) Phi has no root: the
 * teeth must then stop exactly at the stop's edge, with a force inside the
 * jump [0, D*|u|]. The smooth law's root is found to its documented
 * accuracy (docs/model.md): a residual within 1e-7 (float 1e-5) of the
 * force plus the closing motion's impulse, |u|*m_eff/h; twice that here. */
typedef struct {
    gs_hard_stop_model model;
    double K, D, d, hb, dt, x0;
    double inv_c; /* m_eff/h, kg/s: the closing motion's impulse per speed */
    int transition, beyond, at_edge;
} be_check;

static void check_backward_euler_step(be_check *c, const gs_rig_output *out, int step)
{
#ifdef GS_SINGLE_PRECISION
    const double rtol = 2e-3, solver = 2e-5;
#else
    const double rtol = 1e-8, solver = 2e-7;
#endif
    const double x1 = (double)out->backlash_position;
    const double u = (x1 - c->x0) / c->dt;
    const double f = (double)out->contact_force;
    const double law = contact_law(c->model, 1, c->K, c->D, c->d, c->hb, x1, u);
    const double pen = fabs(x1) - c->hb;
    const double atol = rtol * (fabs(f) + 1.0) + 2.0 * GS_EPS * c->hb * (c->K + c->D / c->dt) +
                        (c->model == GS_HARD_STOP_SMOOTH ? solver * (fabs(f) + fabs(u) * c->inv_c) : 0.0);
    const int on_edge = fabs(pen) <= 4.0 * GS_EPS * c->hb;
    const int at_edge = on_edge && !is_zero(f);
    if (!near_enough(f, law, 0.0, atol) &&
        !(c->model != GS_HARD_STOP_SMOOTH && on_edge && f * sgn(x1) >= -atol && f * sgn(x1) <= fabs(c->D * u) + atol))
        fail_msg("hard stop %d, step %d: x0 %.17g m, x1 %.17g m, u %.17g m/s: force %.17g N, "
                 "law %.17g N",
                 (int)c->model, step, c->x0, x1, u, f, law);
    if (at_edge)
        ++c->at_edge;
    else if (pen > 0.0 && pen < c->d)
        ++c->transition;
    else if (pen >= c->d)
        ++c->beyond;
    c->x0 = x1;
}

static void run_backward_euler_residual(gs_hard_stop_model m)
{
    /* K*d = 20 N against tooth forces up to 40 N: both pieces of the smooth law */
    const double g = 2.0, rB = 0.1, b = 1e-3, K = 1e6, D = 1e3, d = 2e-5, dt = 1e-3;
    gs_simple_gear_params gp = backlash_gear(g, GS_ROTATES_OPPOSITE, m, b, rB, K, D);
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    be_check c = {m, K, D, d, b / 2.0, dt, 0.0, 0.0, 0, 0, 0};
    gs_rig_info info;
    int k, trial;
    gp.backlash.transition_region_m = R(d);
    rp.dt_s = R(dt);
    rp.contact_substeps = 1;
    INIT_GEAR_RIG(&rig, &gp, &rp);
    /* (h*omega_n)^2 = K*h^2/m_eff, at h = dt */
    gs_rig_get_info(&rig.c, &info);
    c.inv_c = K * dt / ((double)info.contact_h_omega_n * (double)info.contact_h_omega_n);
    /* reversing drive, load changing sign: sustained contact on both flanks */
    for (k = 0; k < 8000; ++k) {
        const double t = k * dt;
        const gs_rig_input in =
            rig_speed_input(20.0 * sin(2.0 * TEST_PI * 0.5 * t) + 4.0 * sin(2.0 * TEST_PI * 1.25 * t),
                            2.0 + 6.0 * sin(2.0 * TEST_PI * 0.25 * t + 0.3));
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        check_backward_euler_step(&c, &out, k);
    }
    /* free impacts from the centre at 64 closing speeds: the edge is reached
     * at every fraction of a step, so the full laws' jump is hit too */
    for (trial = 0; trial < 64; ++trial) {
        gs_rig_reset(&rig.c, &rig.s);
        c.x0 = 0.0;
        for (k = 0; k < 40; ++k) {
            const gs_rig_input in = rig_speed_input(k == 0 ? 0.0 : 0.3 + 0.05 * trial, 0.0);
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            check_backward_euler_step(&c, &out, k);
        }
    }
    print_message("hard stop %d: %d steps in the transition region, %d beyond, %d at a jump\n", (int)m, c.transition,
                  c.beyond, c.at_edge);
    /* both pieces of each law were exercised */
    assert_true(c.beyond > 100);
    if (m == GS_HARD_STOP_SMOOTH)
        assert_true(c.transition > 100);
    else
        assert_true(c.at_edge > 10);
}

static void test_backward_euler_residual(void **state)
{
    (void)state;
    run_backward_euler_residual(GS_HARD_STOP_SMOOTH);
    run_backward_euler_residual(GS_HARD_STOP_FULL_UNDAMPED);
    run_backward_euler_residual(GS_HARD_STOP_FULL_DAMPED);
}

/* ---- Block level, steady contact (physics.md 4.6, "Meshing loss with
 * backlash"): once the teeth rest against each other, the block with backlash
 * passes on the torques of the rigid law. g = 2, opposite rotation (s = -1),
 * r_B = 0.1 m, r_F = 0.2 m, D = 0, no viscous losses: the contact force f
 * gives T_B = r_B*f and the loss-free T_F0 = -s*r_F*f, and by hand
 *   constant efficiency, base drives:     T_F = eta*T_F0  (|T_F| = eta*g*|T_B|)
 *   constant efficiency, follower drives: T_F = T_F0/eta  (g*|T_B| = eta*|T_F|)
 *   load-dependent (2.6), omega_F > 0:   T_F = (T_F0 + C0)/(1 - k)
 *                          omega_F < 0:   T_F = (T_F0 - C0)/(1 + k)
 * with C0 = g*tau_idle, k = 1/eta_nom - 1 - g*tau_idle/tau_nom (2.5). */
static double steady_block_follower_torque(gs_friction_model model, double eta, double w_b, double *contact_force,
                                           double *base_torque)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.friction_model = model;
    g.efficiency_const = (gs_real)eta;
    g.idle_torque_Nm = R(0.5);
    g.nominal_output_torque_Nm = R(20.0);
    g.efficiency_nominal = R(0.8);
    g.backlash.enabled = 1;
    g.backlash.damping_N_s_m = R(0.0);
    test_gear gear;
    INIT_GEAR(&gear, &g);
    gs_gear_ports_out out;
    /* close the gap: the base tooth advances 0.1 m/s against a held follower */
    for (int k = 0; k < 7; ++k) {
        const gs_gear_ports_in in = {R(1.0), R(0.0), R(0.0), R(0.0), R(300.0), 0};
        gs_simple_gear_step(&gear.c, &gear.s, R(1e-3), &in, &out);
    }
    /* then turn together (v = r_B*w_B - s*r_F*w_F = 0): x and f stay put */
    for (int k = 0; k < 5; ++k) {
        const gs_gear_ports_in in = {(gs_real)w_b, (gs_real)(-w_b / 2.0), R(0.0), R(0.0), R(300.0), 0};
        gs_simple_gear_step(&gear.c, &gear.s, R(1e-3), &in, &out);
    }
    *contact_force = (double)out.contact_force_N;
    *base_torque = (double)out.base_torque_Nm;
    return (double)out.follower_torque_Nm;
}

static void test_block_steady_contact_rigid_torques(void **state)
{
    (void)state;
    const double etas[3] = {0.9, 0.5, 0.3};
    for (int i = 0; i < 3; ++i) {
        for (int dir = 0; dir < 2; ++dir) {
            /* w_B = +10: omega_F = -5, T_F0 > 0, base drives; w_B = -10: follower drives */
            const double w_b = dir == 0 ? 10.0 : -10.0;
            double f, t_b;
            const double t_f = steady_block_follower_torque(GS_FRICTION_CONSTANT_EFFICIENCY, etas[i], w_b, &f, &t_b);
            const double t_f0 = 0.2 * f;
            assert_true(f > 100.0); /* the teeth are in contact */
            ASSERT_NEAR(t_b, 0.1 * f, TOL_REL, 0.0);
            const double want = dir == 0 ? etas[i] * t_f0 : t_f0 / etas[i];
            ASSERT_NEAR(t_f, want, TOL_REL, 0.0);
        }
    }
    const double c0 = 2.0 * 0.5;
    const double k = 1.0 / 0.8 - 1.0 - 2.0 * 0.5 / 20.0;
    for (int dir = 0; dir < 2; ++dir) {
        const double w_b = dir == 0 ? 10.0 : -10.0; /* omega_F = -5 or +5 */
        double f, t_b;
        const double t_f = steady_block_follower_torque(GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY, 0.9, w_b, &f, &t_b);
        const double t_f0 = 0.2 * f;
        const double want = dir == 0 ? (t_f0 - c0) / (1.0 + k) : (t_f0 + c0) / (1.0 - k);
        ASSERT_NEAR(t_f, want, TOL_REL, 0.0);
    }
}

/* The same for the Rack & Pinion block (follower radius 1, r_P = 0.1 m,
 * positive direction s_R = +1, D = 0): T_P = r_P*f, F0 = -s_R*f, and by hand
 *   base (pinion) drives:    F_R = eta*F0      (|F_R| = eta*|T_P|/r_P)
 *   rack drives:             F_R = F0/eta      (|T_P| = eta*r_P*|F_R|) */
static double steady_rack_block_force(double eta, double w_p, double *contact_force, double *pinion_torque)
{
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    pp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    pp.efficiency_const = (gs_real)eta;
    pp.backlash.enabled = 1;
    pp.backlash.damping_N_s_m = R(0.0);
    test_rack rp;
    INIT_RACK(&rp, &pp);
    gs_rack_ports_out out;
    for (int k = 0; k < 7; ++k) { /* close the gap: 0.1 m/s against a held rack */
        const gs_rack_ports_in in = {R(1.0), R(0.0), R(0.0), R(0.0), R(300.0), 0};
        gs_rack_pinion_step(&rp.c, &rp.s, R(1e-3), &in, &out);
    }
    for (int k = 0; k < 5; ++k) { /* then move together: v = r_P*w_P - v_R = 0 */
        const gs_rack_ports_in in = {(gs_real)w_p, (gs_real)(0.1 * w_p), R(0.0), R(0.0), R(300.0), 0};
        gs_rack_pinion_step(&rp.c, &rp.s, R(1e-3), &in, &out);
    }
    *contact_force = (double)out.contact_force_N;
    *pinion_torque = (double)out.pinion_torque_Nm;
    return (double)out.rack_force_N;
}

static void test_rack_block_steady_contact_rigid_forces(void **state)
{
    (void)state;
    const double etas[3] = {0.9, 0.5, 0.3};
    for (int i = 0; i < 3; ++i) {
        for (int dir = 0; dir < 2; ++dir) {
            /* w_P = +10: v_R = +1 m/s, F0 < 0, the pinion drives; w_P = -10: the rack drives */
            const double w_p = dir == 0 ? 10.0 : -10.0;
            double f, t_p;
            const double f_r = steady_rack_block_force(etas[i], w_p, &f, &t_p);
            const double f0 = -f;
            assert_true(f > 100.0); /* the teeth are in contact */
            ASSERT_NEAR(t_p, 0.1 * f, TOL_REL, 0.0);
            const double want = dir == 0 ? etas[i] * f0 : f0 / etas[i];
            ASSERT_NEAR(f_r, want, TOL_REL, 0.0);
        }
    }
}

/* ---- Static-contact lock (physics.md 4): it engages only on teeth that
 * are at or beyond a stop and closing or at rest, never while they separate.
 * A torque-driven rig with one sub-step and a 5 mm/s speed threshold, under
 * a motor torque and a load that reverse at different rates, engages and
 * releases the lock many times; every engagement is checked against the
 * motion of x over that step (the lock is the rig's public state). The rule
 * before 2026-11 (any slow motion beyond a stop) fails this at step 92. */
static void test_lock_never_engages_while_separating(void **state)
{
    (void)state;
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.backlash.enabled = 1;
    g.backlash.stiffness_N_m = GS_R(1e5);
    g.backlash.damping_N_s_m = GS_R(50.0);
    g.backlash.lock_enabled = 1;
    g.backlash.contact_speed_threshold_m_s = GS_R(0.005);
    g.backlash.contact_release_force_N = GS_R(0.0);
    gs_rig_params rp = gs_rig_params_default();
    rp.base_drive = GS_BASE_TORQUE_DRIVEN;
    rp.base_inertia_kg_m2 = GS_R(0.01);
    rp.driven_inertia = GS_R(0.001);
    rp.contact_substeps = 1;
    test_rig rig;
    INIT_GEAR_RIG(&rig, &g, &rp);
    const double half_gap = 0.5 * (double)g.backlash.linear_backlash_m;
    int engaged = 0;
    for (int k = 0; k < 4000; ++k) {
        const double t = 1e-3 * (double)k;
        gs_rig_input in = {GS_R(0.0), (gs_real)(0.2 * sin(2.0 * TEST_PI * 3.0 * t)),
                           (gs_real)(0.1 * sin(2.0 * TEST_PI * 5.0 * t + 1.0)), GS_R(293.15), GS_R(293.15)};
        gs_rig_output out;
        const int locked_before = rig.s.block.contact_locked;
        const double x0 = (double)rig.s.block.backlash_position;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        if (!locked_before && rig.s.block.contact_locked) {
            const double x1 = (double)rig.s.block.backlash_position;
            ++engaged;
            if (!(fabs(x1) >= half_gap * (1.0 - 1e-6) && x1 * (x1 - x0) >= 0.0)) {
                fail_msg("step %d: lock engaged with x %.9g -> %.9g (separating or inside the gap)", k, x0, x1);
            }
        }
    }
    print_message("lock engagements checked: %d\n", engaged);
    assert_true(engaged >= 10);
}

/* gs_rig_get_info: the sub-step count, h*omega_n = (dt/n)*sqrt(K*(r_F^2/J_F
 * (+ r_B^2/J_B))) by hand, and the cap flag of the automatic choice. */
static void check_info(double stiffness, double follower_inertia, int substeps_param, int expect_n, int expect_capped)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.backlash.enabled = 1;
    g.backlash.stiffness_N_m = (gs_real)stiffness;
    gs_rig_params rp = gs_rig_params_default();
    rp.driven_inertia = (gs_real)follower_inertia;
    rp.contact_substeps = substeps_param;
    test_rig rig;
    INIT_GEAR_RIG(&rig, &g, &rp);
    gs_rig_info info;
    gs_rig_get_info(&rig.c, &info);
    const double r_f = (double)g.teeth_ratio * (double)g.backlash.base_radius_m;
    const double h = (double)rp.dt_s / (double)expect_n;
    const double h_omega_n = h * sqrt(stiffness * r_f * r_f / follower_inertia);
    assert_int_equal(info.contact_substeps, expect_n);
    assert_int_equal(info.substeps_capped, expect_capped);
    assert_true(fabs((double)info.contact_h_omega_n - h_omega_n) <= 1e-5 * h_omega_n);
}

static void test_rig_info(void **state)
{
    (void)state;
    /* the smallest count with h*omega_n <= GS_AUTO_H_OMEGA_N_MAX (1.0), dt 1 ms:
     * K 1e6, r_F 0.2 m, J_F 0.05: omega_n = 894.4 rad/s, n = 1 gives 0.894;
     * K 1.3e6: omega_n = 1019.8 rad/s, n = 1 gives 1.02, n = 2 gives 0.510;
     * K 9e6: omega_n = 2683 rad/s, n = 2 gives 1.34, n = 3 gives 0.894 */
    check_info(1e6, 0.05, 0, 1, 0);
    check_info(1.3e6, 0.05, 0, 2, 0);
    check_info(9e6, 0.05, 0, 3, 0);
    /* K 1e9, J_F 1e-4: omega_n = 6.32e5 rad/s; 16 sub-steps leave 39.5 */
    check_info(1e9, 1e-4, 0, GS_AUTO_SUBSTEPS_MAX, 1);
    /* the same, chosen by the user: no cap to report */
    check_info(1e9, 1e-4, 64, 64, 0);
    /* rigid: one step, nothing to resolve */
    gs_simple_gear_params g = gs_simple_gear_params_default();
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    INIT_GEAR_RIG(&rig, &g, &rp);
    gs_rig_info info;
    gs_rig_get_info(&rig.c, &info);
    assert_int_equal(info.contact_substeps, 1);
    assert_int_equal(info.substeps_capped, 0);
    assert_true(!(info.contact_h_omega_n > GS_R(0.0)) && !(info.contact_h_omega_n < GS_R(0.0)));
}

typedef struct {
    gs_hard_stop_model model;
    int substeps;
    double load_amp;
} stiff_case;

static const stiff_case stiff_cases[9] = {
    {GS_HARD_STOP_SMOOTH, 0, 0.0},        {GS_HARD_STOP_SMOOTH, 1, 0.0},        {GS_HARD_STOP_SMOOTH, 0, 0.05},
    {GS_HARD_STOP_FULL_UNDAMPED, 0, 0.0}, {GS_HARD_STOP_FULL_UNDAMPED, 1, 0.0}, {GS_HARD_STOP_FULL_UNDAMPED, 0, 0.05},
    {GS_HARD_STOP_FULL_DAMPED, 0, 0.0},   {GS_HARD_STOP_FULL_DAMPED, 1, 0.0},   {GS_HARD_STOP_FULL_DAMPED, 0, 0.05}};

static void test_stiff_contact_stability(void **state)
{
    const stiff_case *c = (const stiff_case *)*state;
    run_stiff(c->model, c->substeps, c->load_amp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_block_contact_laws),
        cmocka_unit_test(test_lost_motion_gear),
        cmocka_unit_test(test_lost_motion_rack),
        cmocka_unit_test(test_rebound_conservative),
        cmocka_unit_test(test_rebound_damping),
        cmocka_unit_test(test_no_pull),
        cmocka_unit_test(test_backward_euler_residual),
        cmocka_unit_test(test_block_steady_contact_rigid_torques),
        cmocka_unit_test(test_rack_block_steady_contact_rigid_forces),
        cmocka_unit_test(test_lock_never_engages_while_separating),
        cmocka_unit_test(test_rig_info),
        /* hard stop (smooth, full_undamped, full_damped) x (automatic sub-steps,
         * one sub-step, automatic with a load) */
        {"test_stiff_smooth_auto_substeps", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[0]},
        {"test_stiff_smooth_1_substep", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[1]},
        {"test_stiff_smooth_auto_substeps_load", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[2]},
        {"test_stiff_full_undamped_auto_substeps", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[3]},
        {"test_stiff_full_undamped_1_substep", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[4]},
        {"test_stiff_full_undamped_auto_substeps_load", test_stiff_contact_stability, NULL, NULL,
         (void *)&stiff_cases[5]},
        {"test_stiff_full_damped_auto_substeps", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[6]},
        {"test_stiff_full_damped_1_substep", test_stiff_contact_stability, NULL, NULL, (void *)&stiff_cases[7]},
        {"test_stiff_full_damped_auto_substeps_load", test_stiff_contact_stability, NULL, NULL,
         (void *)&stiff_cases[8]},
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
