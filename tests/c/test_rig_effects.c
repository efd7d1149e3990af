/*
 * test_rig_effects.c - the rig's Stribeck friction, compliant base shaft and
 * base-side torque ripple (docs/physics.md section 11), against values
 * derived by hand from the equations there:
 *
 *  Stribeck   F(v) = F_C + (F_brk - F_C)*exp(-(v/v_S)^2) on the driven side.
 *             Held at rest while |applied| <= F_brk; the speed-driven rigid
 *             rig's torque at a steady speed; the steady speed v* under a held
 *             load L with viscous mu: L = F(v*) + mu*v* (solved by bisection).
 *  Compliance drive held at rest, load L on the follower, a = follower per
 *             base speed (s/g or s_R*r_P), J_eff = J_B + a^2*J_F:
 *             J_eff*phi'' + c*phi' + k*phi = -a*L for the twist phi, so
 *             phi_inf = -a*L/k, omega_n = sqrt(k/J_eff),
 *             zeta = c/(2*sqrt(k*J_eff)), and from rest
 *             phi(t) = phi_inf*(1 - e^(-zeta*omega_n*t)*(cos(omega_d*t)
 *                      + zeta/sqrt(1 - zeta^2)*sin(omega_d*t))).
 *             The stored energy J_eff*w^2/2 + k*(phi - phi_inf)^2/2 is
 *             constant without damping and falls by exp(-2*zeta*omega_n*T)
 *             over any damped period T.
 *  Ripple     tau_r(theta) = sum_i A_i*cos(i*theta + phi_i)
 *                          + sum_j M_j*cos(j*Z*theta + psi_j), added to the
 *             torque the drive applies, evaluated at the step's mid angle.
 */
#include "test_common.h"

#ifdef GS_SINGLE_PRECISION
#define TOL_EXP 3e-4 /* the core's exp(-z) squares a polynomial ten times */
#else
#define TOL_EXP 1e-11
#endif

/* Gear rig g = 2, opposite rotation (a = -1/2); rack rig r_P = 0.05 m,
 * negative direction (a = -0.05 m/rad). No meshing loss. */
#define GEAR_RATIO    2.0
#define PINION_RADIUS 0.05

static double follower_per_base(int rack)
{
    return rack ? -PINION_RADIUS : -1.0 / GEAR_RATIO;
}

static gs_status init_rig(test_rig *rig, int rack, int backlash, double mu_follower, const gs_rig_params *rp,
                          gs_error *err)
{
    if (rack) {
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        pp.pinion_radius_m = R(PINION_RADIUS);
        pp.rack_directionality = GS_RACK_NEGATIVE;
        pp.rack_viscous_coefficient = R(mu_follower);
        pp.backlash.enabled = backlash;
        return gs_rig_init_rack(&rig->c, &rig->s, &pp, rp, err);
    }
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gp.teeth_ratio = R(GEAR_RATIO);
    gp.output_shaft_rotates = GS_ROTATES_OPPOSITE;
    gp.viscous_coefficients[1] = R(mu_follower);
    gp.backlash.enabled = backlash;
    return gs_rig_init_gear(&rig->c, &rig->s, &gp, rp, err);
}

static void make_rig(test_rig *rig, int rack, int backlash, double mu_follower, const gs_rig_params *rp)
{
    gs_error err;
    const gs_status st = init_rig(rig, rack, backlash, mu_follower, rp, &err);
    if (st != GS_OK) report_init_failure("init_rig", st, &err, __FILE__, __LINE__);
}

static double stribeck_level(double coulomb, double breakaway, double v_s, double v)
{
    return coulomb + (breakaway - coulomb) * exp(-(v / v_s) * (v / v_s));
}

/* ---- Stribeck ---- */

/* Speed-driven rigid rig at a steady speed: the friction is the Stribeck
 * level times tanh(4 v/v_th); the drive pays -a*T_F with
 * T_F = L - F(v)*tanh(4 v/v_th) - mu_F*v. */
static void test_stribeck_speed_driven_settled(void **state)
{
    const double speeds[] = {-0.03, -0.01, -0.002, 0.0005, 0.004, 0.01, 0.02, 0.05};
    const double coulomb = 1.0, breakaway = 3.0, v_s = 0.01, v_th = 1e-3, mu_f = 0.5, load = 0.7;
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        const double a = follower_per_base(rack);
        for (size_t i = 0; i < sizeof speeds / sizeof speeds[0]; ++i) {
            gs_rig_params rp = gs_rig_params_default();
            rp.load_coulomb_friction = R(coulomb);
            rp.load_coulomb_speed_threshold = R(v_th);
            rp.load_breakaway_friction = R(breakaway);
            rp.load_stribeck_speed = R(v_s);
            test_rig rig;
            make_rig(&rig, rack, 0, mu_f, &rp);
            const gs_rig_input in = rig_speed_input(speeds[i] / a, load);
            gs_rig_output out;
            for (int k = 0; k < 3; ++k)
                gs_rig_step(&rig.c, &rig.s, &in, &out);
            const double v = (double)out.follower_speed; /* = a*w_B, rounded like the rig's */
            const double friction = stribeck_level(coulomb, breakaway, v_s, v) * tanh(4.0 * v / v_th);
            ASSERT_NEAR(v, speeds[i], TOL_REL, 0.0);
            ASSERT_NEAR(out.follower_port_torque, load - friction, TOL_EXP, 1e-12);
            ASSERT_NEAR(out.base_torque, -a * (load - friction - mu_f * v), TOL_EXP, 1e-12);
        }
    }
}

/* Load ramped slowly on a rig at rest (torque-driven base without torque, or
 * a speed-driven base at rest with backlash): the follower stays at exactly
 * zero speed while |L| <= F_brk and moves at the first step where |L| > F_brk.
 * The ramp L_k = (k - 1/2)*dL never lands on the level itself. Without a
 * breakaway friction the level is F_C. */
static int breakaway_step(int rack, int backlash, double sign, double coulomb, double breakaway)
{
    const double dL = 0.01;
    gs_rig_params rp = gs_rig_params_default();
    rp.load_coulomb_friction = R(coulomb);
    rp.load_breakaway_friction = R(breakaway);
    rp.load_stribeck_speed = R(0.01);
    if (!backlash) {
        rp.base_drive = GS_BASE_TORQUE_DRIVEN;
        rp.base_inertia_kg_m2 = R(0.01);
    }
    test_rig rig;
    make_rig(&rig, rack, backlash, 0.0, &rp);
    for (int k = 1; k <= 1000; ++k) {
        const gs_rig_input in = backlash ? rig_speed_input(0.0, sign * ((double)k - 0.5) * dL)
                                         : rig_torque_input(0.0, sign * ((double)k - 0.5) * dL);
        gs_rig_output out;
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        if (!is_zero((double)out.follower_speed)) {
            /* it breaks away along the load */
            assert_true((double)out.follower_speed * sign > 0.0);
            return k;
        }
    }
    return -1;
}

static void test_stribeck_breakaway_threshold(void **state)
{
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int backlash = 0; backlash <= 1; ++backlash)
            for (int s = -1; s <= 1; s += 2) {
                /* F_brk = 3: L_300 = 2.995, L_301 = 3.005 */
                assert_int_equal(breakaway_step(rack, backlash, (double)s, 1.0, 3.0), 301);
                /* no Stribeck: F_C = 1 */
                assert_int_equal(breakaway_step(rack, backlash, (double)s, 1.0, 0.0), 101);
                /* breakaway level equal to F_C: no hump */
                assert_int_equal(breakaway_step(rack, backlash, (double)s, 1.5, 1.5), 151);
            }
}

/* v* with L = F(v*) + mu*v*: F + mu*v increases when mu exceeds the steepest
 * fall of the hump, (F_brk - F_C)*sqrt(2/e)/v_S, so bisection finds the one
 * root in (0, L/mu). */
static double steady_speed(double load, double coulomb, double breakaway, double v_s, double mu)
{
    double lo = 0.0, hi = load / mu;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (stribeck_level(coulomb, breakaway, v_s, mid) + mu * mid < load)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* Torque-driven rig, no motor torque, a held load above breakaway: the
 * follower settles where the load equals the Stribeck level plus viscous. */
static void test_stribeck_steady_speed_under_load(void **state)
{
    const double coulomb = 1.0, breakaway = 3.0, v_s = 0.01, mu = 400.0;
    const double loads[] = {3.5, 5.0, -4.0};
    (void)state;
    assert_true(mu > (breakaway - coulomb) * sqrt(2.0 / exp(1.0)) / v_s);
    for (int rack = 0; rack <= 1; ++rack)
        for (size_t i = 0; i < sizeof loads / sizeof loads[0]; ++i) {
            gs_rig_params rp = gs_rig_params_default();
            rp.base_drive = GS_BASE_TORQUE_DRIVEN;
            rp.base_inertia_kg_m2 = R(0.01);
            rp.driven_inertia = R(1.0);
            rp.load_coulomb_friction = R(coulomb);
            rp.load_breakaway_friction = R(breakaway);
            rp.load_stribeck_speed = R(v_s);
            test_rig rig;
            make_rig(&rig, rack, 0, mu, &rp);
            const gs_rig_input in = rig_torque_input(0.0, loads[i]);
            gs_rig_output out;
            for (int k = 0; k < 2000; ++k)
                gs_rig_step(&rig.c, &rig.s, &in, &out);
            const double v_star = sgn(loads[i]) * steady_speed(fabs(loads[i]), coulomb, breakaway, v_s, mu);
            print_message("%s L = %g: v* = %.9g, rig %.9g\n", rack ? "rack" : "gear", loads[i], v_star,
                          (double)out.follower_speed);
            ASSERT_NEAR(out.follower_speed, v_star, TOL_EXP, 0.0);
            /* the hump at v*: well above F_C, below F_brk */
            const double level = stribeck_level(coulomb, breakaway, v_s, v_star);
            assert_true(level > coulomb + 0.1 && level < breakaway);
        }
}

/* ---- Compliance ---- */

typedef struct {
    double a, j_eff, k, c, load, phi_inf, omega_n, zeta;
} shaft_case;

static shaft_case shaft_setup(int rack, double omega_n, double zeta, double load, gs_rig_params *rp)
{
    shaft_case s;
    const double j_b = 0.01, j_f = rack ? 4.0 : 0.05;
    s.a = follower_per_base(rack);
    s.j_eff = j_b + s.a * s.a * j_f;
    s.omega_n = omega_n;
    s.zeta = zeta;
    s.k = s.j_eff * omega_n * omega_n;
    s.c = 2.0 * zeta * sqrt(s.k * s.j_eff);
    s.load = load;
    s.phi_inf = -s.a * load / s.k;
    *rp = gs_rig_params_default();
    rp->base_inertia_kg_m2 = R(j_b);
    rp->driven_inertia = R(j_f);
    rp->compliance_stiffness_Nm_rad = R(s.k);
    rp->compliance_damping_Nm_s_rad = R(s.c);
    return s;
}

/* The block's power balance, port_power = loss_power, to rounding of the
 * port terms (the shaft and the ripple are outside the block). */
static void assert_block_balance(const gs_rig_output *o)
{
    const double scale = fabs((double)o->base_port_torque * (double)o->base_speed) +
                         fabs((double)o->follower_port_torque * (double)o->follower_speed) +
                         fabs((double)o->loss_power);
    ASSERT_NEAR(o->port_power, o->loss_power, 0.0, 256.0 * GS_EPS * scale + 1e-300);
}

/* The shaft's energy relative to the loaded equilibrium (J). */
static double shaft_energy(const shaft_case *s, const gs_rig_state *st)
{
    const double w = (double)st->base_speed, dphi = (double)st->shaft_twist - s->phi_inf;
    return 0.5 * s->j_eff * w * w + 0.5 * s->k * dphi * dphi;
}

/* Held load, drive at rest: the twist settles at -a*L/k, the drive carries
 * -a*L, the follower is displaced by a^2*L/k; soft and very stiff shafts. */
static void test_compliance_static_deflection(void **state)
{
    const double omegas[] = {2.0 * TEST_PI * 50.0, 2.0 * TEST_PI * 3000.0};
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int i = 0; i < 2; ++i) {
            gs_rig_params rp;
            const shaft_case s = shaft_setup(rack, omegas[i], 0.7, rack ? 30.0 : 4.0, &rp);
            test_rig rig;
            make_rig(&rig, rack, 0, 0.0, &rp);
            const gs_rig_input in = rig_speed_input(0.0, s.load);
            gs_rig_output out;
            for (int k = 0; k < 500; ++k)
                gs_rig_step(&rig.c, &rig.s, &in, &out);
            ASSERT_NEAR(rig.s.shaft_twist, s.phi_inf, TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_torque, -s.a * s.load, TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_port_torque, -s.a * s.load, TOL_ACC, 0.0);
            ASSERT_NEAR(out.follower_position, s.a * s.a * s.load / s.k, TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_angle, -s.phi_inf, TOL_ACC, 0.0);
        }
}

/* The sub-step count: the smallest n <= 16 with (dt/n)*omega_n <= 0.2. */
static void test_compliance_substeps(void **state)
{
    const double f_hz[] = {20.0, 50.0, 100.0, 1000.0, 30000.0};
    const int want[] = {1, 2, 4, 16, 16};
    (void)state;
    for (int i = 0; i < 5; ++i) {
        gs_rig_params rp;
        const shaft_case s = shaft_setup(0, 2.0 * TEST_PI * f_hz[i], 0.1, 1.0, &rp);
        test_rig rig;
        gs_rig_info info;
        make_rig(&rig, 0, 0, 0.0, &rp);
        gs_rig_get_info(&rig.c, &info);
        assert_int_equal(info.compliance_substeps, want[i]);
        ASSERT_NEAR(info.compliance_h_omega_n, 1e-3 / want[i] * s.omega_n, TOL_REL * 10.0, 0.0);
        assert_int_equal(info.contact_substeps, 1);
    }
    /* without compliance */
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_info info;
    make_rig(&rig, 0, 0, 0.0, &rp);
    gs_rig_get_info(&rig.c, &info);
    assert_int_equal(info.compliance_substeps, 1);
    assert_true(is_zero((double)info.compliance_h_omega_n));
}

/* A lightly damped shaft after a load step rings at omega_d and decays at
 * zeta*omega_n: the first two periods follow the closed form, the zero
 * crossings give the frequency, the energy over damped periods the decay. */
static void test_compliance_step_response(void **state)
{
    enum { N = 400 };
    const double dt = 1e-3, zeta = 0.05;
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        /* omega_d = 2*pi*50: a damped period is 20 steps */
        const double omega_n = 2.0 * TEST_PI * 50.0 / sqrt(1.0 - zeta * zeta);
        gs_rig_params rp;
        const shaft_case s = shaft_setup(rack, omega_n, zeta, rack ? 30.0 : 4.0, &rp);
        const double omega_d = s.omega_n * sqrt(1.0 - zeta * zeta), sigma = zeta * s.omega_n;
        test_rig rig;
        make_rig(&rig, rack, 0, 0.0, &rp);
        const gs_rig_input in = rig_speed_input(0.0, s.load);
        static double dev[N + 1], energy[N + 1];
        gs_rig_output out;
        dev[0] = -s.phi_inf;
        energy[0] = shaft_energy(&s, &rig.s);
        for (int k = 1; k <= N; ++k) {
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            assert_block_balance(&out);
            const double t = k * dt;
            const double phi = (double)rig.s.shaft_twist;
            const double closed =
                s.phi_inf *
                (1.0 - exp(-sigma * t) * (cos(omega_d * t) + zeta / sqrt(1.0 - zeta * zeta) * sin(omega_d * t)));
            if (k <= 40) ASSERT_NEAR(phi, closed, 0.0, 0.02 * fabs(s.phi_inf));
            dev[k] = phi - s.phi_inf;
            energy[k] = shaft_energy(&s, &rig.s);
        }
        /* frequency: mean spacing of the zero crossings of phi - phi_inf */
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
        /* decay: energy over 5 damped periods (100 steps), averaged over a period */
        double ratio = 0.0;
        for (int k = 100; k < 120; ++k)
            ratio += log(energy[k + 100] / energy[k]) / 20.0;
        const double sigma_est = -ratio / (2.0 * 0.1);
        print_message("%s: ring %.4f Hz (closed form %.4f), decay %.4f 1/s (closed form %.4f)\n",
                      rack ? "rack" : "gear", f_ring, omega_d / (2.0 * TEST_PI), sigma_est, sigma);
        ASSERT_NEAR(f_ring, omega_d / (2.0 * TEST_PI), 0.005, 0.0);
        ASSERT_NEAR(sigma_est, sigma, 0.02, 0.0);
    }
}

/* Drive at rest, no load: the undamped shaft keeps its energy (the midpoint
 * rule conserves it), also far stiffer than the step resolves; a damped one
 * loses energy in every step. The initial twist comes from a load that is
 * then taken off. */
static void test_compliance_energy(void **state)
{
    const double omegas[] = {2.0 * TEST_PI * 50.0, 2.0 * TEST_PI * 5000.0};
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int i = 0; i < 2; ++i)
            for (int damped = 0; damped <= 1; ++damped) {
                gs_rig_params rp;
                shaft_case s = shaft_setup(rack, omegas[i], damped ? 0.02 : 0.0, rack ? 30.0 : 4.0, &rp);
                test_rig rig;
                make_rig(&rig, rack, 0, 0.0, &rp);
                gs_rig_output out;
                const gs_rig_input loaded = rig_speed_input(0.0, s.load);
                const gs_rig_input free_in = rig_speed_input(0.0, 0.0);
                for (int k = 0; k < 7; ++k)
                    gs_rig_step(&rig.c, &rig.s, &loaded, &out);
                s.phi_inf = 0.0; /* unloaded from here on */
                const double e0 = shaft_energy(&s, &rig.s);
                double e_prev = e0;
                assert_true(e0 > 0.0);
                for (int k = 0; k < 2000; ++k) {
                    gs_rig_step(&rig.c, &rig.s, &free_in, &out);
                    const double e = shaft_energy(&s, &rig.s);
                    if (damped)
                        ASSERT_LE(e, e_prev, TOL_ENERGY * e0);
                    else
                        ASSERT_NEAR(e, e0, TOL_ACC, 0.0);
                    e_prev = e;
                }
                if (damped) /* 2 s at zeta = 0.02: exp(-2*zeta*omega_n*2) of it is left, or rounding */
                    ASSERT_LE(e_prev, e0 * exp(-2.0 * 0.02 * omegas[i] * 2.0) * 1.5, e0 * GS_EPS);
            }
}

/* The compliant shaft with the other terms, settled: the drive turns at a
 * constant speed, so the base gear turns with it and the shaft carries what
 * the rigid rig would: k*phi = -a*T_F with T_F = L - F(v_F)*sign(v_F) -
 * mu_F*v_F, F the Stribeck level at the follower speed v_F = a*w_d (the
 * friction of a free driven side is not smoothed). */
static void test_compliance_with_stribeck(void **state)
{
    /* mu_F above the hump's local fall -dF/dv (63 and 15 N*m*s/rad at these
     * speeds): slower, the sliding is unstable and the shaft goes into
     * stick-slip, as it physically does */
    const double coulomb = 1.0, breakaway = 3.0, v_s = 0.01, mu_f = 100.0;
    const double follower_speeds[] = {0.015, -0.02};
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int i = 0; i < 2; ++i) {
            gs_rig_params rp;
            const shaft_case s = shaft_setup(rack, 2.0 * TEST_PI * 40.0, 0.5, 0.8, &rp);
            rp.load_coulomb_friction = R(coulomb);
            rp.load_breakaway_friction = R(breakaway);
            rp.load_stribeck_speed = R(v_s);
            test_rig rig;
            make_rig(&rig, rack, 0, mu_f, &rp);
            const double w_d = follower_speeds[i] / s.a;
            gs_rig_output out;
            const gs_rig_input in = rig_speed_input(w_d, s.load);
            for (int k = 0; k < 1000; ++k) {
                gs_rig_step(&rig.c, &rig.s, &in, &out);
                assert_block_balance(&out);
                assert_true((double)out.loss_power >= 0.0);
            }
            const double v = follower_speeds[i];
            const double t_f = s.load - stribeck_level(coulomb, breakaway, v_s, v) * sgn(v) - mu_f * v;
            ASSERT_NEAR(out.follower_speed, v, TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_speed, w_d, TOL_ACC, 0.0);
            ASSERT_NEAR(rig.s.shaft_twist, -s.a * t_f / s.k, TOL_EXP + TOL_ACC, 0.0);
            ASSERT_NEAR(out.base_torque, -s.a * t_f, TOL_EXP + TOL_ACC, 0.0);
        }
}

/* ---- Torque ripple ---- */

typedef struct {
    double amp[GS_RIPPLE_HARMONICS], phase[GS_RIPPLE_HARMONICS];
    double mesh_amp[GS_RIPPLE_HARMONICS], mesh_phase[GS_RIPPLE_HARMONICS];
    int teeth;
} ripple_case;

static const ripple_case RIPPLE = {{0.3, 0.12}, {0.4, -2.0}, {0.05, 0.02}, {1.1, 3.0}, 17};

static void set_ripple(gs_rig_params *rp, const ripple_case *c)
{
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        rp->ripple_revolution_amplitude_Nm[i] = R(c->amp[i]);
        rp->ripple_revolution_phase_rad[i] = R(c->phase[i]);
        rp->ripple_mesh_amplitude_Nm[i] = R(c->mesh_amp[i]);
        rp->ripple_mesh_phase_rad[i] = R(c->mesh_phase[i]);
    }
    rp->ripple_mesh_teeth = c->teeth;
}

static double ripple_at(const ripple_case *c, double theta)
{
    double tau = 0.0;
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        tau += c->amp[i] * cos((i + 1) * theta + c->phase[i]);
        tau += c->mesh_amp[i] * cos((i + 1) * c->teeth * theta + c->mesh_phase[i]);
    }
    return tau;
}

/* Speed-driven rigs at constant speed, no losses and no load: the drive's
 * torque is the ripple at the step's mid angle (rigid), or its mean over the
 * contact sub-steps' mid angles (backlash, teeth apart); a thousand turns in. */
static void test_ripple_at_angles(void **state)
{
    const double speeds[] = {3.7, -250.0};
    (void)state;
    for (int rack = 0; rack <= 1; ++rack)
        for (int backlash = 0; backlash <= 1; ++backlash)
            for (int i = 0; i < 2; ++i) {
                const double dt = 1e-3, w = speeds[i];
                gs_rig_params rp = gs_rig_params_default();
                rp.contact_substeps = backlash ? 3 : 0;
                set_ripple(&rp, &RIPPLE);
                test_rig rig;
                make_rig(&rig, rack, backlash, 0.0, &rp);
                const gs_rig_input in = rig_speed_input(w, 0.0);
                gs_rig_output out;
                double theta = 0.0; /* the rig's angle at the start of the step */
                double worst = 0.0;
                for (int k = 0; k < 25000; ++k) {
                    gs_rig_step(&rig.c, &rig.s, &in, &out);
                    double want = 0.0;
                    if (backlash) {
                        const int n = 3;
                        for (int j = 0; j < n; ++j)
                            want += ripple_at(&RIPPLE, theta + (j + 0.5) * (dt / n) * w) / n;
                    } else {
                        want = ripple_at(&RIPPLE, theta + 0.5 * dt * w);
                    }
                    worst = dmax(worst, fabs((double)out.base_torque - want));
                    theta = (double)out.base_angle;
                }
                print_message("%s%s w = %g: |ripple - closed form| <= %.3g N*m at %.0f rad\n", rack ? "rack" : "gear",
                              backlash ? " backlash" : "", w, worst, theta);
                ASSERT_NEAR(theta, 25000 * dt * w, TOL_ACC, 0.0);
#ifdef GS_SINGLE_PRECISION
                /* float angle: its last bit times Z*2 harmonics */
                ASSERT_LE(worst, 0.0, 2.0 * 17.0 * 2.0 * 0.07 * fabs(theta) * GS_EPS + 1e-5);
#else
                ASSERT_LE(worst, 0.0, 1e-10);
#endif
            }
}

/* The ripple inside the compliant shaft (on the base gear), drive and load
 * at rest: the shaft holds the ripple at the gear's angle theta = -phi, so
 * k*phi = tau_r(-phi) (solved by fixed-point iteration: a contraction while
 * k exceeds the ripple's stiffness). */
static void test_ripple_in_compliant_shaft(void **state)
{
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        gs_rig_params rp;
        const shaft_case s = shaft_setup(rack, 2.0 * TEST_PI * 30.0, 0.6, 0.0, &rp);
        set_ripple(&rp, &RIPPLE);
        test_rig rig;
        make_rig(&rig, rack, 0, 0.0, &rp);
        gs_rig_output out;
        const gs_rig_input in = rig_speed_input(0.0, 0.0);
        for (int k = 0; k < 1000; ++k)
            gs_rig_step(&rig.c, &rig.s, &in, &out);
        double phi = 0.0;
        for (int it = 0; it < 100; ++it)
            phi = ripple_at(&RIPPLE, -phi) / s.k;
        print_message("%s: twist %.9g rad, closed form %.9g rad\n", rack ? "rack" : "gear", (double)rig.s.shaft_twist,
                      phi);
        assert_true(fabs(phi) > 1e-4);
        ASSERT_NEAR(rig.s.shaft_twist, phi, TOL_ACC, 0.0);
        ASSERT_NEAR(out.base_torque, s.k * phi, TOL_ACC, 0.0);
        ASSERT_NEAR(out.base_angle, -phi, TOL_ACC, 0.0);
    }
}

/* Torque-driven rigid rig, no losses, no motor torque: the ripple is a
 * potential torque, V(theta) = sum A_i/i*sin(i*theta + phi_i) + ..., so
 * J_eff*w^2/2 + V(theta) stays constant (to the step's accuracy, without a
 * drift) while the shaft turns through many revolutions. */
static double ripple_potential(const ripple_case *c, double theta)
{
    double v = 0.0;
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        v += c->amp[i] / (i + 1) * sin((i + 1) * theta + c->phase[i]);
        v += c->mesh_amp[i] / ((i + 1) * c->teeth) * sin((i + 1) * c->teeth * theta + c->mesh_phase[i]);
    }
    return v;
}

static void test_ripple_conservative(void **state)
{
    (void)state;
    for (int rack = 0; rack <= 1; ++rack) {
        const double a = follower_per_base(rack), j_b = 0.01, j_f = rack ? 4.0 : 0.05;
        const double j_eff = j_b + a * a * j_f, w0 = 20.0;
        gs_rig_params rp = gs_rig_params_default();
        rp.base_drive = GS_BASE_TORQUE_DRIVEN;
        rp.base_inertia_kg_m2 = R(j_b);
        rp.driven_inertia = R(j_f);
        rp.initial_base_speed_rad_s = R(w0);
        set_ripple(&rp, &RIPPLE);
        test_rig rig;
        make_rig(&rig, rack, 0, 0.0, &rp);
        const gs_rig_input in = rig_torque_input(0.0, 0.0);
        gs_rig_output out;
        const double e0 = 0.5 * j_eff * w0 * w0 + ripple_potential(&RIPPLE, 0.0);
        double worst = 0.0, w_min = w0, w_max = w0;
        for (int k = 0; k < 20000; ++k) {
            gs_rig_step(&rig.c, &rig.s, &in, &out);
            const double w = (double)out.base_speed;
            const double e = 0.5 * j_eff * w * w + ripple_potential(&RIPPLE, (double)out.base_angle);
            worst = dmax(worst, fabs(e - e0));
            w_min = w < w_min ? w : w_min;
            w_max = w > w_max ? w : w_max;
        }
        print_message("%s: energy within %.3g J of %.4g J, speed %.4f..%.4f rad/s\n", rack ? "rack" : "gear", worst, e0,
                      w_min, w_max);
        /* the ripple moves the speed, and over 20 s (60 turns) the energy
         * stays within 1.5 % of the potential's swing (about 0.75 J) and does
         * not drift (an earlier version that evaluated the ripple at the
         * predicted mid angle drifted by 0.1 J over 80 s) */
        assert_true(w_max - w_min > 0.1);
        ASSERT_LE(worst, 0.01, 0.0);
    }
}

/* ---- Validity rules: each names its parameter and leaves the rig as it was. */
typedef struct {
    const char *name;
    void (*apply)(gs_rig_params *rp);
    int backlash;
    gs_status want;
    const char *parameter;
} rule_case;

static void brk_below(gs_rig_params *rp)
{
    rp->load_coulomb_friction = R(2.0);
    rp->load_breakaway_friction = R(1.0);
}
static void brk_negative(gs_rig_params *rp)
{
    rp->load_breakaway_friction = R(-1.0);
}
static void brk_nan(gs_rig_params *rp)
{
    rp->load_breakaway_friction = R(NAN);
}
static void stribeck_zero(gs_rig_params *rp)
{
    rp->load_breakaway_friction = R(1.0);
    rp->load_stribeck_speed = R(0.0);
}
static void stribeck_off_zero(gs_rig_params *rp)
{
    rp->load_stribeck_speed = R(0.0);
}
/* positive, but its square's reciprocal overflows */
static void stribeck_tiny(gs_rig_params *rp)
{
    rp->load_breakaway_friction = R(1.0);
#ifdef GS_SINGLE_PRECISION
    rp->load_stribeck_speed = R(1e-20);
#else
    rp->load_stribeck_speed = R(1e-160);
#endif
}
static void k_negative(gs_rig_params *rp)
{
    rp->compliance_stiffness_Nm_rad = R(-1.0);
}
static void c_negative(gs_rig_params *rp)
{
    rp->compliance_damping_Nm_s_rad = R(-1.0);
}
static void k_inf(gs_rig_params *rp)
{
    rp->compliance_stiffness_Nm_rad = R(INFINITY);
}
static void k_no_inertia(gs_rig_params *rp)
{
    rp->compliance_stiffness_Nm_rad = R(100.0);
}
static void k_ok(gs_rig_params *rp)
{
    rp->compliance_stiffness_Nm_rad = R(100.0);
    rp->base_inertia_kg_m2 = R(0.01);
}
static void k_torque(gs_rig_params *rp)
{
    k_ok(rp);
    rp->base_drive = GS_BASE_TORQUE_DRIVEN;
}
static void ripple_amp_negative(gs_rig_params *rp)
{
    rp->ripple_revolution_amplitude_Nm[1] = R(-0.1);
}
static void ripple_phase_nan(gs_rig_params *rp)
{
    rp->ripple_revolution_phase_rad[0] = R(NAN);
}
static void mesh_amp_inf(gs_rig_params *rp)
{
    rp->ripple_mesh_amplitude_Nm[0] = R(INFINITY);
}
static void mesh_phase_inf(gs_rig_params *rp)
{
    rp->ripple_mesh_phase_rad[1] = R(-INFINITY);
}
static void mesh_no_teeth(gs_rig_params *rp)
{
    rp->ripple_mesh_amplitude_Nm[1] = R(0.1);
}
static void teeth_negative(gs_rig_params *rp)
{
    rp->ripple_mesh_teeth = -3;
}
static void rev_no_teeth(gs_rig_params *rp)
{
    rp->ripple_revolution_amplitude_Nm[0] = R(0.1);
}

static const rule_case RULES[] = {
    {"breakaway below Coulomb", brk_below, 0, GS_E_BREAKAWAY, "load_breakaway_friction"},
    {"breakaway < 0", brk_negative, 0, GS_E_NEGATIVE, "load_breakaway_friction"},
    {"breakaway NaN", brk_nan, 0, GS_E_NOT_FINITE, "load_breakaway_friction"},
    {"Stribeck speed 0", stribeck_zero, 0, GS_E_NOT_POSITIVE, "load_stribeck_speed"},
    {"Stribeck speed 0, no breakaway", stribeck_off_zero, 0, GS_OK, ""},
    {"Stribeck speed squared underflows", stribeck_tiny, 0, GS_E_MAGNITUDE, "load_stribeck_speed"},
    {"stiffness < 0", k_negative, 0, GS_E_NEGATIVE, "compliance_stiffness"},
    {"damping < 0", c_negative, 0, GS_E_NEGATIVE, "compliance_damping"},
    {"stiffness inf", k_inf, 0, GS_E_NOT_FINITE, "compliance_stiffness"},
    /* no base inertia: the spring acts at the mesh (tests/c/test_rig_regularised.c) */
    {"compliance without base inertia", k_no_inertia, 0, GS_OK, ""},
    {"compliance", k_ok, 0, GS_OK, ""},
    {"compliance, torque-driven", k_torque, 0, GS_E_COMBINATION, "compliance_stiffness"},
    {"compliance with backlash", k_ok, 1, GS_E_COMBINATION, "compliance_stiffness"},
    {"ripple amplitude < 0", ripple_amp_negative, 0, GS_E_NEGATIVE, "ripple_revolution_amplitude"},
    {"ripple phase NaN", ripple_phase_nan, 0, GS_E_NOT_FINITE, "ripple_revolution_phase"},
    {"mesh amplitude inf", mesh_amp_inf, 0, GS_E_NOT_FINITE, "ripple_mesh_amplitude"},
    {"mesh phase -inf", mesh_phase_inf, 0, GS_E_NOT_FINITE, "ripple_mesh_phase"},
    {"mesh harmonic without teeth", mesh_no_teeth, 0, GS_E_NOT_POSITIVE, "ripple_mesh_teeth"},
    {"teeth < 0", teeth_negative, 0, GS_E_NEGATIVE, "ripple_mesh_teeth"},
    {"revolution harmonic without teeth", rev_no_teeth, 0, GS_OK, ""},
};

static void test_validity_rules(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof RULES / sizeof RULES[0]; ++i)
        for (int rack = 0; rack <= 1; ++rack) {
            const rule_case *c = &RULES[i];
            gs_rig_params rp = gs_rig_params_default();
            c->apply(&rp);
            test_rig rig, before;
            memset(&rig, 0xA5, sizeof rig);
            before = rig;
            gs_error err;
            memset(&err, 0, sizeof err);
            const gs_status st = init_rig(&rig, rack, c->backlash, 0.0, &rp, &err);
            if (st != c->want || strcmp(err.parameter, c->parameter) != 0)
                fail_msg("%s (%s): status %d '%s', expected %d '%s'", c->name, rack ? "rack" : "gear", (int)st,
                         err.parameter, (int)c->want, c->parameter);
            if (st != GS_OK) assert_memory_equal(&rig, &before, sizeof rig);
        }
}

/* The new parameters' defaults leave every term off. */
static void test_defaults_off(void **state)
{
    const gs_rig_params rp = gs_rig_params_default();
    (void)state;
    assert_true(is_zero((double)rp.load_breakaway_friction));
    ASSERT_NEAR(rp.load_stribeck_speed, 0.01, TOL_REL, 0.0);
    assert_true(is_zero((double)rp.compliance_stiffness_Nm_rad));
    assert_true(is_zero((double)rp.compliance_damping_Nm_s_rad));
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        assert_true(is_zero((double)rp.ripple_revolution_amplitude_Nm[i]));
        assert_true(is_zero((double)rp.ripple_revolution_phase_rad[i]));
        assert_true(is_zero((double)rp.ripple_mesh_amplitude_Nm[i]));
        assert_true(is_zero((double)rp.ripple_mesh_phase_rad[i]));
    }
    assert_int_equal(rp.ripple_mesh_teeth, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stribeck_speed_driven_settled),
        cmocka_unit_test(test_stribeck_breakaway_threshold),
        cmocka_unit_test(test_stribeck_steady_speed_under_load),
        cmocka_unit_test(test_compliance_static_deflection),
        cmocka_unit_test(test_compliance_substeps),
        cmocka_unit_test(test_compliance_step_response),
        cmocka_unit_test(test_compliance_energy),
        cmocka_unit_test(test_compliance_with_stribeck),
        cmocka_unit_test(test_ripple_in_compliant_shaft),
        cmocka_unit_test(test_ripple_at_angles),
        cmocka_unit_test(test_ripple_conservative),
        cmocka_unit_test(test_validity_rules),
        cmocka_unit_test(test_defaults_off),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
