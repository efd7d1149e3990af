/*
 * test_thermal.c - thermal mass and temperature-dependent efficiency tables
 * (docs/physics.md sections 2.4, 2.5, 5, 11).
 *
 *  adiabatic:     C*dT/dt = P_loss      -> T_N - T_0 = sum(P_loss*dt)/C
 *  heat path:     C*dT/dt = P_loss + (T_amb - T)/R_th -> T_ss = T_amb + P_loss*R_th
 *  block port:    C*dT/dt = P_loss + Q_H
 *  1-D table:     linear interpolation, end values held outside
 *  2-D table:     bilinear in (T, load = |T_F|/g), clamped at the edges
 * Efficiencies are observed through the steady-state base torque, base
 * driving: |T_B| = |T_F|/(eta*g), follower driving (Coulomb form of the 2-D
 * model, 2.7): |T_B| = (|T_F| - |T_F|*(1/eta - 1))/g.
 */
#include "test_common.h"

/* Speed-driven rig with the temperature taken from the input; returns the
 * steady-state base port torque at follower speed +4 rad/s and T_F. */
static double rig_base_torque_at(const gs_simple_gear_params *gp, double temp_K, double TF)
{
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    gs_rig_input in;
    const double g = (double)gp->teeth_ratio, s = gear_sign(gp->output_shaft_rotates);
    int k;
    rp.temperature_source = GS_TEMPERATURE_FROM_INPUT;
    INIT_GEAR_RIG(&rig, gp, &rp);
    in = rig_speed_input(s * g * 4.0, TF);
    in.measured_temperature = R(temp_K);
    for (k = 0; k < 4; ++k)
        gs_rig_step(&rig.c, &rig.s, &in, &out);
    ASSERT_NEAR(out.temperature, temp_K, TOL_REL, 0.0);
    return (double)out.base_port_torque;
}

static gs_simple_gear_params table_gear(void)
{
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gp.teeth_ratio = R(2.5);
    gp.output_shaft_rotates = GS_ROTATES_SAME;
    gp.friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    gp.power_threshold_W = R(1e-3);
    return gp;
}

/* 1-D table: each breakpoint is hit exactly, end values hold outside, linear
 * in between (non-uniform spacing). Both power-flow directions. */
static void test_temperature_table_points_and_clamp(void **state)
{
    static const double T[4] = {250.0, 270.0, 330.0, 400.0};
    static const double E[4] = {0.97, 0.92, 0.88, 0.6};
    gs_simple_gear_params gp = table_gear();
    const double g = 2.5, TF = 6.0;
    double probes[9][2];
    int i, n = 0;
    (void)state;
    gp.temperature_count = 4;
    for (i = 0; i < 4; ++i) {
        gp.temperature_vector_K[i] = R(T[i]);
        gp.efficiency_vector[i] = R(E[i]);
        probes[n][0] = T[i];
        probes[n][1] = (double)gp.efficiency_vector[i];
        ++n;
    }
    probes[n][0] = 200.0; /* clamp low */
    probes[n][1] = (double)gp.efficiency_vector[0];
    ++n;
    probes[n][0] = 500.0; /* clamp high */
    probes[n][1] = (double)gp.efficiency_vector[3];
    ++n;
    probes[n][0] = 300.0; /* halfway 270..330 */
    probes[n][1] = 0.5 * ((double)gp.efficiency_vector[1] + (double)gp.efficiency_vector[2]);
    ++n;
    probes[n][0] = 260.0; /* halfway 250..270 */
    probes[n][1] = 0.5 * ((double)gp.efficiency_vector[0] + (double)gp.efficiency_vector[1]);
    ++n;
    probes[n][0] = 382.5; /* 3/4 of 330..400 */
    probes[n][1] = 0.25 * (double)gp.efficiency_vector[2] + 0.75 * (double)gp.efficiency_vector[3];
    ++n;
    for (i = 0; i < n; ++i) {
        const double eta = probes[i][1];
        /* base drives: T_F opposes omega_F (> 0); s = +1 so T_B > 0 */
        ASSERT_NEAR(rig_base_torque_at(&gp, probes[i][0], -TF), TF / (eta * g), TOL_REL, 0.0);
        /* follower drives */
        ASSERT_NEAR(rig_base_torque_at(&gp, probes[i][0], TF), -eta * TF / g, TOL_REL, 0.0);
    }
}

/* Rack: same table rules, observed through the pinion torque. */
static void test_rack_temperature_table(void **state)
{
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    const double temps[5] = {280.0, 300.0, 320.0, 260.0, 345.0};
    const double etas[5] = {0.95, 0.90, 0.85, 0.95, 0.85};
    const double F = 50.0, w = 7.5;
    int i, k;
    (void)state;
    pp.pinion_radius_m = R(0.04);
    pp.friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    for (i = 0; i < 5; ++i) {
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig;
        gs_rig_output out;
        gs_rig_input in = rig_speed_input(w, -F); /* pinion drives */
        double eta = etas[i], r = (double)pp.pinion_radius_m;
        int j;
        for (j = 0; j < 3; ++j) /* the table as stored in gs_real */
            if (fabs(etas[i] - (double)pp.efficiency_vector[j]) < 1e-6) eta = (double)pp.efficiency_vector[j];
        rp.temperature_source = GS_TEMPERATURE_FROM_INPUT;
        in.measured_temperature = R(temps[i]);
        INIT_RACK_RIG(&rig, &pp, &rp);
        for (k = 0; k < 4; ++k)
            gs_rig_step(&rig.c, &rig.s, &in, &out);
        ASSERT_NEAR(out.base_port_torque, r * F / eta, TOL_REL, 0.0);
    }
}

/* 2-D table, bilinear: T = [280 320], load = [0 50 100] (base N*m),
 * E = [[0.90 0.95 0.97], [0.80 0.88 0.96]]. */
static void test_temperature_load_table_bilinear(void **state)
{
    static const double Tv[2] = {280.0, 320.0};
    static const double Lv[3] = {0.0, 50.0, 100.0};
    static const double Ev[2][3] = {{0.90, 0.95, 0.97}, {0.80, 0.88, 0.96}};
    gs_simple_gear_params gp = table_gear();
    double E[2][3];
    const double g = 2.5;
    int i, j;
    (void)state;
    gp.friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    gp.speed_threshold_rad_s = R(0.01);
    gp.temperature_count = 2;
    gp.load_count = 3;
    for (i = 0; i < 2; ++i)
        gp.temperature_vector_K[i] = R(Tv[i]);
    for (j = 0; j < 3; ++j)
        gp.load_vector_Nm[j] = R(Lv[j]);
    for (i = 0; i < 2; ++i)
        for (j = 0; j < 3; ++j) {
            gp.efficiency_matrix[i][j] = R(Ev[i][j]);
            E[i][j] = (double)gp.efficiency_matrix[i][j];
        }
    {
        struct {
            double T, load, eta;
        } probes[6];
        int n = 0;
        /* cell centre: mean of the four corners */
        probes[n].T = 300.0;
        probes[n].load = 75.0;
        probes[n].eta = 0.25 * (E[0][1] + E[0][2] + E[1][1] + E[1][2]);
        ++n;
        /* off-centre: a = 1/4 along T, b = 1/5 along load in cell [50, 100] */
        probes[n].T = 290.0;
        probes[n].load = 60.0;
        probes[n].eta = 0.75 * (0.8 * E[0][1] + 0.2 * E[0][2]) + 0.25 * (0.8 * E[1][1] + 0.2 * E[1][2]);
        ++n;
        /* grid point */
        probes[n].T = 320.0;
        probes[n].load = 50.0;
        probes[n].eta = E[1][1];
        ++n;
        /* clamped on both axes */
        probes[n].T = 350.0;
        probes[n].load = 150.0;
        probes[n].eta = E[1][2];
        ++n;
        /* clamped in T, interpolated in load (midpoint 0..50) */
        probes[n].T = 250.0;
        probes[n].load = 25.0;
        probes[n].eta = 0.5 * (E[0][0] + E[0][1]);
        ++n;
        /* on a T edge midpoint of load cell */
        probes[n].T = 280.0;
        probes[n].load = 75.0;
        probes[n].eta = 0.5 * (E[0][1] + E[0][2]);
        ++n;
        for (i = 0; i < n; ++i) {
            const double TF = probes[i].load * g; /* load = |T_F|/g */
            const double eta = probes[i].eta;
            ASSERT_NEAR(rig_base_torque_at(&gp, probes[i].T, -TF), TF / (eta * g), TOL_REL, 0.0);
            ASSERT_NEAR(rig_base_torque_at(&gp, probes[i].T, TF), -(TF - TF * (1.0 / eta - 1.0)) / g, TOL_REL, 0.0);
        }
    }
}

/* Adiabatic rig: the temperature rise is the integral of the loss power over
 * the thermal mass. The rig reports the temperature at the end of the step
 * (rig.h: temperature is an end value; docs/model.md), so the losses of step
 * k use the thermal state reported by step k-1 (T0 for the first step). */
static void test_adiabatic_temperature_rise(void **state)
{
    gs_simple_gear_params gp = table_gear();
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double g = 2.5, wF = 8.0, TF = 5.0;
    double C, T0, dt, energy = 0.0, prevT;
    int k;
    (void)state;
    gp.thermal_mass_J_K = R(2.0);
    gp.initial_temperature_K = R(300.0);
    rp.dt_s = R(0.01);
    rp.heat_path = 0;
    INIT_GEAR_RIG(&rig, &gp, &rp);
    C = (double)gp.thermal_mass_J_K;
    T0 = (double)gp.initial_temperature_K;
    dt = (double)rp.dt_s;
    prevT = T0;
    for (k = 0; k < 200; ++k) {
        const gs_rig_input in = rig_speed_input(g * wF, -TF); /* base drives */
        /* eta at the state the step starts from, default table 300..320 K */
        const double eta = 0.90 + (0.85 - 0.90) * (prevT - 300.0) / 20.0;
        const double P = TF * wF * (1.0 / eta - 1.0);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
        ASSERT_NEAR(out.loss_power, P, 10.0 * TOL_REL, 0.0);
        /* explicit Euler of C*dT/dt = P_loss */
        ASSERT_NEAR(out.temperature, prevT + (double)out.loss_power * dt / C, 0.0,
                    TOL_REL * 10.0 + 0.5 * GS_EPS * 512.0);
        prevT = (double)out.temperature;
        energy += (double)out.loss_power * dt;
    }
    /* the whole rise: integral of P_loss*dt over C */
    ASSERT_NEAR(out.temperature, T0 + energy / C, 0.0, TOL_ACC + 200 * 0.5 * GS_EPS * 512.0);
    assert_true(energy / C > 3.0); /* the scenario heats noticeably */
}

/* Heat path, constant efficiency (flat table): T_ss = T_amb + P_loss*R_th with
 * P_loss = |T_F|*|omega_F|*(1/eta - 1). */
static void test_heat_path_steady_state(void **state)
{
    gs_simple_gear_params gp = table_gear();
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double g = 2.5, wF = 8.0, TF = 5.0, Tamb = 293.0;
    double eta, P, Rth;
    int k;
    (void)state;
    gp.temperature_count = 2;
    gp.temperature_vector_K[0] = R(280.0);
    gp.temperature_vector_K[1] = R(320.0);
    gp.efficiency_vector[0] = R(0.9);
    gp.efficiency_vector[1] = R(0.9);
    gp.thermal_mass_J_K = R(1.0);
    gp.initial_temperature_K = R(300.0);
    rp.dt_s = R(0.01);
    rp.heat_path = 1;
    rp.thermal_resistance_K_W = R(0.5);
    INIT_GEAR_RIG(&rig, &gp, &rp);
    eta = (double)gp.efficiency_vector[0];
    Rth = (double)rp.thermal_resistance_K_W;
    P = TF * wF * (1.0 / eta - 1.0);
    for (k = 0; k < 3000; ++k) { /* 30 s = 60 time constants */
        gs_rig_input in = rig_speed_input(-g * wF, TF);
        in.ambient_temperature = R(Tamb);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
    }
    ASSERT_NEAR(out.loss_power, P, TOL_REL, 0.0);
    /* slack: the Euler update stalls once |dT| < ulp(T)/2, i.e. within
     * R*C*ulp/dt of the fixed point (negligible in double) */
    ASSERT_NEAR(out.temperature, Tamb + P * Rth, 0.0,
                TOL_ACC + 2.0 * Rth * (double)gp.thermal_mass_J_K * GS_EPS * 512.0 / (double)rp.dt_s);
}

/* Heat path with the default table: the steady state solves
 * T = T_amb + R_th*P(eta(T)); solved here by fixed-point iteration. */
static void test_heat_path_steady_state_temperature_feedback(void **state)
{
    gs_simple_gear_params gp = table_gear();
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output out;
    const double g = 2.5, wF = 8.0, TF = 5.0, Tamb = 300.0;
    double Rth, T = Tamb;
    int k;
    (void)state;
    gp.thermal_mass_J_K = R(1.0);
    gp.initial_temperature_K = R(300.0);
    rp.dt_s = R(0.01);
    rp.heat_path = 1;
    rp.thermal_resistance_K_W = R(2.0);
    INIT_GEAR_RIG(&rig, &gp, &rp);
    Rth = (double)rp.thermal_resistance_K_W;
    for (k = 0; k < 200; ++k) {
        const double eta = 0.90 + (0.85 - 0.90) * (T - 300.0) / 20.0;
        T = Tamb + Rth * TF * wF * (1.0 / eta - 1.0);
    }
    assert_true(T > 300.0 && T < 320.0); /* inside the table's second segment */
    for (k = 0; k < 8000; ++k) {
        gs_rig_input in = rig_speed_input(g * wF, -TF);
        in.ambient_temperature = R(Tamb);
        gs_rig_step(&rig.c, &rig.s, &in, &out);
    }
    {
        /* slack: Euler stall band R*C*ulp/dt (negligible in double) */
        const double tol = TOL_ACC + 4.0 * Rth * (double)gp.thermal_mass_J_K * GS_EPS * 512.0 / (double)rp.dt_s;
        ASSERT_NEAR(out.temperature, T, 0.0, tol);
        /* self-consistency of the balance at the end: T = T_amb + P*R_th */
        ASSERT_NEAR(out.temperature, Tamb + (double)out.loss_power * Rth, 0.0, tol);
    }
}

/* Block-level thermal port: C*dT/dt = P_loss + Q_H (explicit Euler), and the
 * losses of the first step use the initial temperature. */
static void test_block_heat_flow(void **state)
{
    gs_simple_gear_params gp = table_gear();
    test_gear gear;
    gs_gear_ports_in in;
    gs_gear_ports_out out;
    int k;
    (void)state;
    gp.thermal_mass_J_K = R(5.0);
    gp.initial_temperature_K = R(300.0);
    INIT_GEAR(&gear, &gp);
    memset(&in, 0, sizeof in);
    in.heat_flow_W = R(10.0);
    for (k = 1; k <= 10; ++k) {
        gs_simple_gear_step(&gear.c, &gear.s, R(0.1), &in, &out);
        ASSERT_NEAR(out.loss_power_W, 0.0, 0.0, 1e-12);
        ASSERT_NEAR(out.temperature_K, 300.0 + 10.0 * 0.1 * k / 5.0, TOL_REL, 0.0);
    }
    /* reset returns to the initial temperature */
    gs_simple_gear_reset(&gear.c, &gear.s);
    in.heat_flow_W = R(0.0);
    gs_simple_gear_step(&gear.c, &gear.s, R(0.1), &in, &out);
    ASSERT_NEAR(out.temperature_K, 300.0, TOL_REL, 0.0);

    /* initial temperature 320 K -> eta = 0.85 on the first step; the step's
     * loss then heats the mass: dT = P*dt/C */
    gp.initial_temperature_K = R(320.0);
    INIT_GEAR(&gear, &gp);
    in.base_speed_rad_s = R(2.5 * 4.0);
    in.follower_torque_Nm = R(-6.0);
    gs_simple_gear_step(&gear.c, &gear.s, R(0.1), &in, &out);
    {
        const double eta = (double)gp.efficiency_vector[2];
        const double P = 6.0 * 4.0 * (1.0 / eta - 1.0);
        ASSERT_NEAR(out.base_torque_Nm, 6.0 / (eta * 2.5), TOL_REL, 0.0);
        ASSERT_NEAR(out.loss_power_W, P, TOL_REL, 0.0);
        ASSERT_NEAR(out.temperature_K, 320.0 + P * 0.1 / 5.0, TOL_REL, 0.0);
    }
}

/* Rack block thermal port and rack rig adiabatic rise. */
static void test_rack_thermal(void **state)
{
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    test_rack blk;
    gs_rack_ports_in in;
    gs_rack_ports_out out;
    gs_rig_params rp = gs_rig_params_default();
    test_rig rig;
    gs_rig_output ro;
    double energy = 0.0;
    int k;
    (void)state;
    pp.friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    pp.thermal_mass_J_K = R(4.0);
    INIT_RACK(&blk, &pp);
    memset(&in, 0, sizeof in);
    in.heat_flow_W = R(-8.0);
    for (k = 1; k <= 5; ++k) {
        gs_rack_pinion_step(&blk.c, &blk.s, R(0.05), &in, &out);
        ASSERT_NEAR(out.temperature_K, 300.0 - 8.0 * 0.05 * k / 4.0, TOL_REL, 0.0);
    }

    rp.dt_s = R(0.01);
    INIT_RACK_RIG(&rig, &pp, &rp);
    for (k = 0; k < 300; ++k) {
        const gs_rig_input ri = rig_speed_input(20.0, -30.0);
        gs_rig_step(&rig.c, &rig.s, &ri, &ro);
        energy += (double)ro.loss_power * (double)rp.dt_s;
    }
    {
        const gs_rig_input ri = rig_speed_input(0.0, 0.0);
        gs_rig_step(&rig.c, &rig.s, &ri, &ro);
        ASSERT_NEAR(ro.temperature, 300.0 + energy / 4.0, 0.0, TOL_ACC + 301 * 0.5 * GS_EPS * 512.0);
        assert_true(energy / 4.0 > 1.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_temperature_table_points_and_clamp),
        cmocka_unit_test(test_rack_temperature_table),
        cmocka_unit_test(test_temperature_load_table_bilinear),
        cmocka_unit_test(test_adiabatic_temperature_rise),
        cmocka_unit_test(test_heat_path_steady_state),
        cmocka_unit_test(test_heat_path_steady_state_temperature_feedback),
        cmocka_unit_test(test_block_heat_flow),
        cmocka_unit_test(test_rack_thermal),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
