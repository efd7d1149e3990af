/*
 * test_friction.c - steady-state torques of every meshing-loss model in both
 * power-flow directions, the smoothing laws, and the viscous terms
 * (docs/physics.md sections 1-3 and 6).
 *
 * Every case runs through the block (gs_simple_gear_step / gs_rack_pinion_step,
 * one step) and through a speed-driven rig at constant speed (alpha = 0 after
 * the first step). Expected values are textbook relations written by hand,
 * with T_F = tau_F - mu_F*omega_F and T_B = tau_B - mu_B*omega_B:
 *
 *  efficiency models (none: eta = 1; constant; temperature table), operating
 *  point far above the power threshold (tanh(4p/p_th) = 1):
 *     base drives     (T_F*omega_F < 0):  |T_F| = eta*g*|T_B|, T_B*omega_B > 0
 *     follower drives (T_F*omega_F > 0):  |T_B| = eta*|T_F|/g, T_B*omega_B < 0
 *  Coulomb models (load-dependent 2.3-2.6, temperature+load table 2.7),
 *  follower speed far above omega_th:
 *     tau_C = g*tau_idle + k*|T_F|   or   |T_F|*(1/eta - 1)
 *     base drives:      |T_B| = (|T_F| + tau_C)/g  (= |T_F|/(eta*g))
 *     follower drives:  |T_B| = (|T_F| - tau_C)/g
 *  Mesh loss power = |T_F|*|omega_F|*(1/eta - 1), |T_F|*|omega_F|*(1 - eta)
 *  or tau_C*|omega_F|.
 */
#include "test_common.h"

typedef struct {
    int coulomb;  /* 0: efficiency law, 1: Coulomb law */
    double eta;   /* efficiency law */
    double tau_c; /* Coulomb law: follower-referred Coulomb torque, N*m */
} gear_law;

typedef struct {
    double TB;         /* expected T_B = tau_B - mu_B*omega_B */
    double mesh_power; /* expected tau_mesh*omega_F */
} gear_expect;

static gear_expect expect_gear(gear_law law, double TF, double wF, double wB, double g)
{
    gear_expect e;
    const int base_drives = TF * wF < 0.0;
    if (!law.coulomb) {
        if (base_drives) {
            e.TB = sgn(wB) * fabs(TF) / (law.eta * g);
            e.mesh_power = fabs(TF) * fabs(wF) * (1.0 / law.eta - 1.0);
        } else {
            e.TB = -sgn(wB) * law.eta * fabs(TF) / g;
            e.mesh_power = fabs(TF) * fabs(wF) * (1.0 - law.eta);
        }
    } else {
        if (base_drives)
            e.TB = sgn(wB) * (fabs(TF) + law.tau_c) / g;
        else
            e.TB = -sgn(wB) * (fabs(TF) - law.tau_c) / g;
        e.mesh_power = law.tau_c * fabs(wF);
    }
    return e;
}

/* One operating point through the block and the rig.
 * temp_K > 0: the temperature-dependent models read it as an input. */
static void check_gear_point(const gs_simple_gear_params *gp, double wB, double tauF, double temp_K, gear_expect e)
{
    const double g = (double)gp->teeth_ratio;
    const double s = gear_sign(gp->output_shaft_rotates);
    const double muB = (double)gp->viscous_coefficients[0];
    const double muF = (double)gp->viscous_coefficients[1];
    const double wF = s * wB / g;
    const double loss = e.mesh_power + muB * wB * wB + muF * wF * wF;
    const double tauB = muB * wB + e.TB;
    const double ptol = TOL_REL * (fabs(tauB * wB) + fabs(tauF * wF));
    test_gear gear;
    gs_gear_ports_in in;
    gs_gear_ports_out out;
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output ro;
    gs_rig_input ri;
    int k;

    INIT_GEAR(&gear, gp);
    memset(&in, 0, sizeof in);
    in.base_speed_rad_s = R(wB);
    in.follower_torque_Nm = R(tauF);
    in.temperature_K = R(temp_K > 0.0 ? temp_K : 300.0);
    in.use_temperature_input = temp_K > 0.0;
    gs_simple_gear_step(&gear.c, &gear.s, R(1e-3), &in, &out);
    ASSERT_NEAR(out.follower_speed_rad_s, wF, TOL_REL, 0.0);
    ASSERT_NEAR(out.base_torque_Nm, tauB, TOL_REL, 0.0);
    ASSERT_NEAR(out.mesh_loss_power_W, e.mesh_power, TOL_REL, 1e-12);
    ASSERT_NEAR(out.loss_power_W, loss, TOL_REL, 1e-12);
    /* the loss torque is follower-referred and has the sign of omega_F */
    ASSERT_NEAR((double)out.mesh_loss_torque_Nm * wF, e.mesh_power, TOL_REL, 1e-12);

    rp.driven_inertia = R(0.05);
    rp.temperature_source = temp_K > 0.0 ? GS_TEMPERATURE_FROM_INPUT : GS_TEMPERATURE_FROM_MODEL;
    INIT_GEAR_RIG(&rig, gp, &rp);
    ri = rig_speed_input(wB, tauF);
    if (temp_K > 0.0) ri.measured_temperature = R(temp_K);
    for (k = 0; k < 5; ++k)
        gs_rig_step(&rig.c, &rig.s, &ri, &ro);
    ASSERT_NEAR(ro.follower_speed, wF, TOL_REL, 0.0);
    ASSERT_NEAR(ro.follower_port_torque, tauF, TOL_REL, 0.0);
    ASSERT_NEAR(ro.base_port_torque, tauB, TOL_REL, 0.0);
    ASSERT_NEAR(ro.base_torque, tauB, TOL_REL, 0.0);
    ASSERT_NEAR(ro.mesh_loss_power, e.mesh_power, TOL_REL, 1e-12);
    ASSERT_NEAR(ro.loss_power, loss, TOL_REL, 1e-12);
    ASSERT_NEAR(ro.port_power, loss, 0.0, ptol + 1e-12);
    if (temp_K > 0.0) ASSERT_NEAR(ro.temperature, temp_K, TOL_REL, 0.0);
}

/* Both output_shaft_rotates options, both speed signs, both power-flow
 * directions, at |omega_F| = wF_mag and |T_F| = TF_mag. law_of(|T_F|) gives
 * the hand law. */
static void sweep_gear(gs_simple_gear_params gp, double wF_mag, double TF_mag, double temp_K, gear_law law)
{
    const gs_output_rotation rots[2] = {GS_ROTATES_SAME, GS_ROTATES_OPPOSITE};
    int ir, iw, flow;
    for (ir = 0; ir < 2; ++ir) {
        for (iw = 0; iw < 2; ++iw) {
            for (flow = 0; flow < 2; ++flow) {
                const double g = (double)gp.teeth_ratio;
                const double muF = (double)gp.viscous_coefficients[1];
                double s, wF, wB, TF, tauF;
                gp.output_shaft_rotates = rots[ir];
                s = gear_sign(rots[ir]);
                wF = (iw == 0 ? 1.0 : -1.0) * wF_mag;
                wB = s * g * wF;
                /* flow 0: base drives (load opposes the follower's motion) */
                TF = (flow == 0 ? -1.0 : 1.0) * sgn(wF) * TF_mag;
                tauF = TF + muF * wF;
                check_gear_point(&gp, wB, tauF, temp_K, expect_gear(law, TF, wF, wB, g));
            }
        }
    }
}

static gs_simple_gear_params base_gear(void)
{
    gs_simple_gear_params p = gs_simple_gear_params_default();
    p.teeth_ratio = R(2.5);
    return p;
}

static void test_no_losses(void **state)
{
    gs_simple_gear_params gp = base_gear();
    gear_law law = {0, 1.0, 0.0};
    (void)state;
    gp.friction_model = GS_FRICTION_NONE;
    sweep_gear(gp, 4.0, 6.0, 0.0, law);
}

static void test_constant_efficiency(void **state)
{
    gs_simple_gear_params gp = base_gear();
    gear_law law = {0, 0.0, 0.0};
    (void)state;
    gp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    gp.efficiency_const = R(0.93);
    gp.power_threshold_W = R(1e-3); /* p = 24 W >> p_th */
    law.eta = (double)gp.efficiency_const;
    sweep_gear(gp, 4.0, 6.0, 0.0, law);
    /* the Simscape smoothing variant has the same limits */
    gp.loss_smoothing = GS_SMOOTHING_SIMSCAPE;
    sweep_gear(gp, 4.0, 6.0, 0.0, law);
    /* eta = 1 is allowed and lossless */
    gp.loss_smoothing = GS_SMOOTHING_PASSIVE;
    gp.efficiency_const = R(1.0);
    law.eta = 1.0;
    sweep_gear(gp, 4.0, 6.0, 0.0, law);
}

/* Load-dependent efficiency: tau_C = g*tau_idle + k*|T_F| with
 * k = 1/eta_nom - 1 - g*tau_idle/tau_nom (2.5). */
static double k_of(const gs_simple_gear_params *gp)
{
    return 1.0 / (double)gp->efficiency_nominal - 1.0 -
           (double)gp->teeth_ratio * (double)gp->idle_torque_Nm / (double)gp->nominal_output_torque_Nm;
}

static void test_load_dependent_efficiency(void **state)
{
    gs_simple_gear_params gp = base_gear();
    gear_law law = {1, 0.0, 0.0};
    const double TF = 6.0;
    double g, k;
    (void)state;
    gp.friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    gp.idle_torque_Nm = R(0.05);
    gp.nominal_output_torque_Nm = R(10.0);
    gp.efficiency_nominal = R(0.9);
    gp.speed_threshold_rad_s = R(0.01); /* |omega_F| = 4 >> 0.01 */
    g = (double)gp.teeth_ratio;
    k = k_of(&gp);
    assert_true(k > 0.0);
    law.tau_c = g * (double)gp.idle_torque_Nm + k * TF;
    sweep_gear(gp, 4.0, TF, 0.0, law);

    /* equivalently through eq. 2.4: base drives => |T_B| = |T_F|/(eta(T_F)*g) */
    {
        const double eta = TF / (g * (double)gp.idle_torque_Nm + (k + 1.0) * TF);
        const double wF = 4.0, wB = -g * wF; /* default: opposite */
        gear_expect e;
        e.TB = sgn(wB) * TF / (eta * g);
        e.mesh_power = TF * wF * (1.0 / eta - 1.0);
        gp.output_shaft_rotates = GS_ROTATES_OPPOSITE;
        check_gear_point(&gp, wB, -TF, 0.0, e);
    }
}

/* The nominal point reproduces eta_nom exactly (2.5), and zero output load
 * needs exactly the idle torque on the base shaft (definition of tau_idle). */
static void test_load_dependent_nominal_and_idle(void **state)
{
    const double idles[3] = {0.0, 0.03, 0.2};
    int i, ir;
    (void)state;
    for (i = 0; i < 3; ++i) {
        for (ir = 0; ir < 2; ++ir) {
            gs_simple_gear_params gp = base_gear();
            gear_expect e;
            double g, tnom, enom, s, wF, wB;
            gp.friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
            gp.output_shaft_rotates = ir ? GS_ROTATES_SAME : GS_ROTATES_OPPOSITE;
            gp.idle_torque_Nm = R(idles[i]);
            gp.nominal_output_torque_Nm = R(8.0);
            gp.efficiency_nominal = R(0.85);
            gp.speed_threshold_rad_s = R(0.01);
            g = (double)gp.teeth_ratio;
            tnom = (double)gp.nominal_output_torque_Nm;
            enom = (double)gp.efficiency_nominal;
            s = gear_sign(gp.output_shaft_rotates);
            wF = 3.0;
            wB = s * g * wF;
            /* nominal output torque, base driving: |T_B| = tau_nom/(eta_nom*g) */
            e.TB = sgn(wB) * tnom / (enom * g);
            e.mesh_power = tnom * wF * (1.0 / enom - 1.0);
            check_gear_point(&gp, wB, -tnom, 0.0, e);
            /* no load: tau_B = tau_idle in the direction of the base speed */
            e.TB = sgn(wB) * (double)gp.idle_torque_Nm;
            e.mesh_power = g * (double)gp.idle_torque_Nm * wF;
            check_gear_point(&gp, wB, 0.0, 0.0, e);
            check_gear_point(&gp, -wB, 0.0, 0.0, (gear_expect){-e.TB, e.mesh_power});
        }
    }
}

/* Temperature-dependent efficiency (default table [280 300 320] K ->
 * [0.95 0.90 0.85]) read at a table point and between points. */
static void test_temperature_dependent_efficiency(void **state)
{
    gs_simple_gear_params gp = base_gear();
    gear_law law = {0, 0.0, 0.0};
    (void)state;
    gp.friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    gp.power_threshold_W = R(1e-3);
    law.eta = (double)gp.efficiency_vector[1];
    ASSERT_NEAR(law.eta, 0.90, 1e-6, 0.0);
    sweep_gear(gp, 4.0, 6.0, 300.0, law);
    /* 310 K: halfway between 0.90 and 0.85 */
    law.eta = 0.5 * ((double)gp.efficiency_vector[1] + (double)gp.efficiency_vector[2]);
    sweep_gear(gp, 4.0, 6.0, 310.0, law);
}

/* Temperature- and load-dependent table at a grid point: load = |T_F|/g. */
static void set_2d_table(gs_simple_gear_params *gp)
{
    static const double T[2] = {280.0, 320.0};
    static const double L[3] = {0.0, 50.0, 100.0};
    static const double E[2][3] = {{0.90, 0.95, 0.97}, {0.80, 0.88, 0.96}};
    int i, j;
    gp->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    gp->temperature_count = 2;
    gp->load_count = 3;
    for (i = 0; i < 2; ++i)
        gp->temperature_vector_K[i] = R(T[i]);
    for (j = 0; j < 3; ++j)
        gp->load_vector_Nm[j] = R(L[j]);
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 3; ++j)
            gp->efficiency_matrix[i][j] = R(E[i][j]);
    gp->speed_threshold_rad_s = R(0.01);
}

static void test_temperature_load_dependent_efficiency(void **state)
{
    gs_simple_gear_params gp = base_gear();
    gear_law law = {1, 0.0, 0.0};
    double g, TF, eta;
    (void)state;
    set_2d_table(&gp);
    g = (double)gp.teeth_ratio;
    /* T = 280 K, base load 50 N*m -> eta = E[0][1] */
    TF = 50.0 * g;
    eta = (double)gp.efficiency_matrix[0][1];
    law.tau_c = TF * (1.0 / eta - 1.0);
    sweep_gear(gp, 4.0, TF, 280.0, law);
    /* T = 320 K, base load 100 N*m -> eta = E[1][2] */
    TF = 100.0 * g;
    eta = (double)gp.efficiency_matrix[1][2];
    law.tau_c = TF * (1.0 / eta - 1.0);
    sweep_gear(gp, 4.0, TF, 320.0, law);
}

/* Smoothing laws evaluated inside the threshold, tanh computed here:
 * passive (2.2) tau_mesh = T_F*t*(t >= 0 ? 1-eta : 1/eta-1),
 * Simscape (2.1) tau_mesh = T_F/2*((L_fd+L_bd)*t + L_fd - L_bd),
 * load-dependent (2.6) tau_mesh = tau_C*tanh(4*omega_F/omega_th);
 * then tau_B = s*(tau_mesh - T_F)/g (1.2). */
static void test_smoothing_inside_threshold(void **state)
{
    const double ps[4] = {0.25, -0.25, 0.0025, -0.0025};
    int smoothing, i;
    (void)state;
    for (smoothing = 0; smoothing < 2; ++smoothing) {
        for (i = 0; i < 4; ++i) {
            gs_simple_gear_params gp = base_gear();
            double eta, pth, g, s, wF, wB, TF, t, Lfd, Lbd, tm;
            gear_expect e;
            gp.teeth_ratio = R(2.0);
            gp.output_shaft_rotates = GS_ROTATES_SAME;
            gp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
            gp.loss_smoothing = smoothing ? GS_SMOOTHING_SIMSCAPE : GS_SMOOTHING_PASSIVE;
            gp.efficiency_const = R(0.8);
            gp.power_threshold_W = R(1.0);
            eta = (double)gp.efficiency_const;
            pth = (double)gp.power_threshold_W;
            g = 2.0;
            s = 1.0;
            wF = 2.0;
            wB = s * g * wF;
            TF = ps[i] / wF; /* p = T_F*omega_F = ps[i] */
            t = tanh(4.0 * TF * wF / pth);
            Lfd = 1.0 - eta;
            Lbd = 1.0 / eta - 1.0;
            if (smoothing)
                tm = 0.5 * TF * ((Lfd + Lbd) * t + Lfd - Lbd);
            else
                tm = TF * t * (t >= 0.0 ? Lfd : Lbd);
            e.TB = s * (tm - TF) / g;
            e.mesh_power = tm * wF;
            if (!smoothing) assert_true(e.mesh_power >= 0.0);
            check_gear_point(&gp, wB, TF, 0.0, e);
        }
    }
    {
        /* load-dependent: omega_F = omega_th/8 -> factor tanh(0.5) */
        const double TFs[3] = {0.0, 3.0, -3.0};
        for (i = 0; i < 3; ++i) {
            gs_simple_gear_params gp = base_gear();
            double g, wth, wF, wB, tauc, tm;
            gear_expect e;
            gp.output_shaft_rotates = GS_ROTATES_OPPOSITE;
            gp.friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
            gp.idle_torque_Nm = R(0.05);
            gp.nominal_output_torque_Nm = R(10.0);
            gp.efficiency_nominal = R(0.9);
            gp.speed_threshold_rad_s = R(0.5);
            g = (double)gp.teeth_ratio;
            wth = (double)gp.speed_threshold_rad_s;
            wF = wth / 8.0;
            wB = -g * wF;
            tauc = g * (double)gp.idle_torque_Nm + k_of(&gp) * fabs(TFs[i]);
            tm = tauc * tanh(4.0 * wF / wth);
            e.TB = -1.0 * (tm - TFs[i]) / g;
            e.mesh_power = tm * wF;
            check_gear_point(&gp, wB, TFs[i], 0.0, e);
        }
    }
}

/* Viscous terms: tau_B includes mu_B*omega_B; T_F = tau_F - mu_F*omega_F;
 * dissipation mu_B*omega_B^2 + mu_F*omega_F^2 (section 3). */
static void test_viscous_terms(void **state)
{
    gear_law law = {0, 1.0, 0.0};
    (void)state;
    {
        gs_simple_gear_params gp = base_gear();
        gp.friction_model = GS_FRICTION_NONE;
        gp.viscous_coefficients[0] = R(0.03);
        gp.viscous_coefficients[1] = R(0.07);
        sweep_gear(gp, 4.0, 6.0, 0.0, law);
        /* no load at all: the drive supplies the viscous losses only,
         * tau_B = mu_B*omega_B + mu_F*omega_F/(s*g) */
        {
            const double g = 2.5, s = -1.0, wB = 10.0, wF = s * wB / g;
            gear_expect e;
            e.TB = 0.07 * wF / (s * g);
            e.mesh_power = 0.0;
            check_gear_point(&gp, wB, 0.0, 0.0, e);
        }
    }
    {
        gs_simple_gear_params gp = base_gear();
        gp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
        gp.efficiency_const = R(0.9);
        gp.viscous_coefficients[0] = R(0.02);
        gp.viscous_coefficients[1] = R(0.05);
        law.eta = (double)gp.efficiency_const;
        sweep_gear(gp, 4.0, 6.0, 0.0, law);
    }
}

/* ---- Rack & Pinion: T_P = tau_P - mu_P*omega_P, Tn = F_R - mu_R*v_R,
 * pinion drives (Tn*v_R < 0): |Tn| = eta*|T_P|/r_P,
 * rack drives:                |T_P| = eta*r_P*|Tn|. */
static void check_rack_point(const gs_rack_pinion_params *pp, double wP, double FR, double temp_K, double eta)
{
    const double r = gs_rack_pinion_radius(pp);
    const double sR = rack_sign(pp->rack_directionality);
    const double muP = (double)pp->pinion_viscous_coefficient;
    const double muR = (double)pp->rack_viscous_coefficient;
    const double v = sR * r * wP;
    const double Tn = FR - muR * v;
    const int pinion_drives = Tn * v < 0.0;
    const double TP = pinion_drives ? sgn(wP) * r * fabs(Tn) / eta : -sgn(wP) * eta * r * fabs(Tn);
    const double mesh = fabs(Tn) * fabs(v) * (pinion_drives ? (1.0 / eta - 1.0) : (1.0 - eta));
    const double loss = mesh + muP * wP * wP + muR * v * v;
    const double tauP = muP * wP + TP;
    test_rack blk;
    gs_rack_ports_in in;
    gs_rack_ports_out out;
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_input ri;
    gs_rig_output ro;
    int k;

    INIT_RACK(&blk, pp);
    memset(&in, 0, sizeof in);
    in.pinion_speed_rad_s = R(wP);
    in.rack_force_N = R(FR);
    in.temperature_K = R(temp_K > 0.0 ? temp_K : 300.0);
    in.use_temperature_input = temp_K > 0.0;
    gs_rack_pinion_step(&blk.c, &blk.s, R(1e-3), &in, &out);
    ASSERT_NEAR(out.rack_velocity_m_s, v, TOL_REL, 0.0);
    ASSERT_NEAR(out.pinion_torque_Nm, tauP, TOL_REL, 0.0);
    ASSERT_NEAR(out.mesh_loss_power_W, mesh, TOL_REL, 1e-12);
    ASSERT_NEAR(out.loss_power_W, loss, TOL_REL, 1e-12);
    /* F_Coul has the sign of v_R */
    ASSERT_NEAR((double)out.mesh_loss_force_N * v, mesh, TOL_REL, 1e-12);

    rp.driven_inertia = R(2.0);
    rp.temperature_source = temp_K > 0.0 ? GS_TEMPERATURE_FROM_INPUT : GS_TEMPERATURE_FROM_MODEL;
    INIT_RACK_RIG(&rig, pp, &rp);
    ri = rig_speed_input(wP, FR);
    if (temp_K > 0.0) ri.measured_temperature = R(temp_K);
    for (k = 0; k < 5; ++k)
        gs_rig_step(&rig.c, &rig.s, &ri, &ro);
    ASSERT_NEAR(ro.follower_speed, v, TOL_REL, 0.0);
    ASSERT_NEAR(ro.follower_port_torque, FR, TOL_REL, 0.0);
    ASSERT_NEAR(ro.base_port_torque, tauP, TOL_REL, 0.0);
    ASSERT_NEAR(ro.mesh_loss_power, mesh, TOL_REL, 1e-12);
    ASSERT_NEAR(ro.loss_power, loss, TOL_REL, 1e-12);
    ASSERT_NEAR(ro.port_power, loss, 0.0, TOL_REL * (fabs(tauP * wP) + fabs(FR * v)) + 1e-12);
}

static void sweep_rack(gs_rack_pinion_params pp, double temp_K, double eta)
{
    const gs_rack_direction dirs[2] = {GS_RACK_POSITIVE, GS_RACK_NEGATIVE};
    int id, iw, flow;
    for (id = 0; id < 2; ++id) {
        for (iw = 0; iw < 2; ++iw) {
            for (flow = 0; flow < 2; ++flow) {
                double r, v, wP, Tn;
                pp.rack_directionality = dirs[id];
                r = gs_rack_pinion_radius(&pp);
                wP = (iw == 0 ? 7.5 : -7.5);
                v = rack_sign(dirs[id]) * r * wP;
                Tn = (flow == 0 ? -1.0 : 1.0) * sgn(v) * 50.0; /* flow 0: pinion drives */
                check_rack_point(&pp, wP, Tn + (double)pp.rack_viscous_coefficient * v, temp_K, eta);
            }
        }
    }
}

static void test_rack_friction(void **state)
{
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    (void)state;
    pp.pinion_radius_m = R(0.04);
    pp.friction_model = GS_FRICTION_NONE;
    sweep_rack(pp, 0.0, 1.0);
    pp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    pp.efficiency_const = R(0.85);
    pp.power_threshold_W = R(1e-3); /* |p| = 15 W */
    sweep_rack(pp, 0.0, (double)pp.efficiency_const);
    /* viscous terms on both sides */
    pp.pinion_viscous_coefficient = R(0.02);
    pp.rack_viscous_coefficient = R(3.0);
    sweep_rack(pp, 0.0, (double)pp.efficiency_const);
    pp.pinion_viscous_coefficient = R(0.0);
    pp.rack_viscous_coefficient = R(0.0);
    /* temperature table [280 300 320] -> [0.95 0.90 0.85] */
    pp.friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    sweep_rack(pp, 320.0, (double)pp.efficiency_vector[2]);
    sweep_rack(pp, 290.0, 0.5 * ((double)pp.efficiency_vector[0] + (double)pp.efficiency_vector[1]));
    /* tooth parameterization goes through the same law with r = N*x/(2*pi) */
    pp.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    pp.parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS;
    pp.teeth_count = R(24.0);
    pp.spacing_m = R(0.01);
    sweep_rack(pp, 0.0, (double)pp.efficiency_const);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_losses),
        cmocka_unit_test(test_constant_efficiency),
        cmocka_unit_test(test_load_dependent_efficiency),
        cmocka_unit_test(test_load_dependent_nominal_and_idle),
        cmocka_unit_test(test_temperature_dependent_efficiency),
        cmocka_unit_test(test_temperature_load_dependent_efficiency),
        cmocka_unit_test(test_smoothing_inside_threshold),
        cmocka_unit_test(test_viscous_terms),
        cmocka_unit_test(test_rack_friction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
