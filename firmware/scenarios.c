/* scenarios.c - scripted rig scenarios (see scenarios.h).
 *
 * Coverage: both blocks; speed- and torque-driven bases; rigid mesh and
 * backlash (the three hard-stop laws, the static lock); constant, load-,
 * temperature- and temperature-load-dependent (2-D table) efficiency; model
 * temperature with a heat path, and measured temperature as an input; the
 * rig's Stribeck friction, compliant base shaft and torque ripple. */
#include "scenarios.h"

#define STEPS 1000
#define DT    GS_R(1e-3)

static gs_real time_of(int k)
{
    return DT * (gs_real)(k + 1);
}

/* Fractional part of t/period, in [0, 1). */
static gs_real phase_of(gs_real t, gs_real period)
{
    const gs_real p = t / period;
    return p - (gs_real)(int)p;
}

/* Triangle wave in [-1, 1]. */
static gs_real tri(gs_real t, gs_real period)
{
    const gs_real p = phase_of(t, period);
    return p < GS_R(0.5) ? GS_R(4.0) * p - GS_R(1.0) : GS_R(3.0) - GS_R(4.0) * p;
}

/* A sine-like wave in [-1, 1] built from two parabolas (no libm). */
static gs_real wave(gs_real t, gs_real period)
{
    const gs_real p = phase_of(t, period);
    if (p < GS_R(0.5)) {
        return GS_R(16.0) * p * (GS_R(0.5) - p);
    }
    return -GS_R(16.0) * (p - GS_R(0.5)) * (GS_R(1.0) - p);
}

static void clear_input(gs_rig_input *in)
{
    in->base_speed = GS_R(0.0);
    in->base_torque = GS_R(0.0);
    in->load = GS_R(0.0);
    in->ambient_temperature = GS_R(293.15);
    in->measured_temperature = GS_R(300.0);
}

/* ---- 1. Simple Gear, constant efficiency, speed-driven: ramp, hold, reverse. */
static gs_status init_gear_const_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(3.0);
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.efficiency_const = GS_R(0.95);
    g.viscous_coefficients[0] = GS_R(1e-3);
    g.viscous_coefficients[1] = GS_R(2e-3);
    gs_rig_params r = gs_rig_params_default();
    r.base_inertia_kg_m2 = GS_R(1e-3);
    r.driven_inertia = GS_R(0.05);
    r.load_coulomb_friction = GS_R(0.5);
    r.load_coulomb_speed_threshold = GS_R(1e-2);
    r.load_offset = GS_R(0.2);
    r.heat_path = 1;
    r.accel_filter_time_constant_s = GS_R(5e-3);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_const_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    if (t < GS_R(0.3)) {
        in->base_speed = GS_R(100.0) * t / GS_R(0.3);
    } else if (t < GS_R(0.6)) {
        in->base_speed = GS_R(100.0);
    } else if (t < GS_R(0.9)) {
        in->base_speed = GS_R(100.0) - GS_R(500.0) * (t - GS_R(0.6));
    } else {
        in->base_speed = GS_R(-50.0);
    }
    in->load = GS_R(-6.0) + GS_R(2.0) * tri(t, GS_R(0.125));
}

/* ---- 2. Simple Gear, constant efficiency (Simscape smoothing), torque-driven. */
static gs_status init_gear_const_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(0.5);
    g.output_shaft_rotates = GS_ROTATES_SAME;
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.loss_smoothing = GS_SMOOTHING_SIMSCAPE;
    g.efficiency_const = GS_R(0.9);
    g.viscous_coefficients[0] = GS_R(5e-4);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(2e-3);
    r.initial_base_speed_rad_s = GS_R(5.0);
    r.driven_inertia = GS_R(0.02);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_const_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(0.3) + GS_R(2.0) * wave(t, GS_R(0.25));
    in->load = GS_R(-1.0);
}

/* ---- 3. Simple Gear, backlash (smooth hard stop), speed-driven oscillation. */
static gs_status init_gear_backlash_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(2.0);
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.efficiency_const = GS_R(0.97);
    g.backlash.enabled = 1;
    g.backlash.hard_stop_model = GS_HARD_STOP_SMOOTH;
    g.backlash.linear_backlash_m = GS_R(1e-3);
    g.backlash.base_radius_m = GS_R(0.05);
    g.backlash.transition_region_m = GS_R(1e-4);
    g.backlash.stiffness_N_m = GS_R(1e6);
    g.backlash.damping_N_s_m = GS_R(50.0);
    gs_rig_params r = gs_rig_params_default();
    r.driven_inertia = GS_R(1e-3);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_backlash_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_speed = GS_R(20.0) * wave(t, GS_R(0.2));
    in->load = GS_R(0.5) * tri(t, GS_R(0.35));
}

/* ---- 4. Simple Gear, backlash (full damped, static lock), torque-driven. */
static gs_status init_gear_backlash_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(1.5);
    g.output_shaft_rotates = GS_ROTATES_SAME;
    g.backlash.enabled = 1;
    g.backlash.hard_stop_model = GS_HARD_STOP_FULL_DAMPED;
    g.backlash.linear_backlash_m = GS_R(5e-4);
    g.backlash.base_radius_m = GS_R(0.03);
    g.backlash.stiffness_N_m = GS_R(5e6);
    g.backlash.damping_N_s_m = GS_R(200.0);
    g.backlash.lock_enabled = 1;
    g.backlash.contact_speed_threshold_m_s = GS_R(1e-3);
    g.backlash.contact_release_force_N = GS_R(1.0);
    g.viscous_coefficients[1] = GS_R(1e-4);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(1e-3);
    r.driven_inertia = GS_R(2e-3);
    r.load_coulomb_friction = GS_R(0.05);
    r.contact_substeps = 8;
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_backlash_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = phase_of(t, GS_R(0.3)) < GS_R(0.5) ? GS_R(0.5) : GS_R(-0.5);
    in->load = GS_R(-0.1);
}

/* A 4 x 5 temperature-load efficiency table (rows: temperature). */
static void table2d(gs_simple_gear_params *g)
{
    static const gs_real temps[4] = {GS_R(270.0), GS_R(290.0), GS_R(310.0), GS_R(330.0)};
    static const gs_real loads[5] = {GS_R(0.0), GS_R(5.0), GS_R(10.0), GS_R(20.0), GS_R(40.0)};
    static const gs_real eta[4][5] = {{GS_R(0.80), GS_R(0.88), GS_R(0.92), GS_R(0.94), GS_R(0.95)},
                                      {GS_R(0.78), GS_R(0.86), GS_R(0.90), GS_R(0.93), GS_R(0.94)},
                                      {GS_R(0.75), GS_R(0.84), GS_R(0.88), GS_R(0.91), GS_R(0.93)},
                                      {GS_R(0.70), GS_R(0.80), GS_R(0.85), GS_R(0.89), GS_R(0.91)}};
    g->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    g->temperature_count = 4;
    g->load_count = 5;
    for (int i = 0; i < 4; ++i) {
        g->temperature_vector_K[i] = temps[i];
        for (int j = 0; j < 5; ++j) {
            g->efficiency_matrix[i][j] = eta[i][j];
        }
    }
    for (int j = 0; j < 5; ++j) {
        g->load_vector_Nm[j] = loads[j];
    }
    g->speed_threshold_rad_s = GS_R(0.05);
}

/* ---- 5. Simple Gear, 2-D table, speed-driven, model temperature with a heat path. */
static gs_status init_gear_table2d_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(4.0);
    table2d(&g);
    g.thermal_mass_J_K = GS_R(2.0);
    g.initial_temperature_K = GS_R(275.0);
    gs_rig_params r = gs_rig_params_default();
    r.driven_inertia = GS_R(0.1);
    r.heat_path = 1;
    r.thermal_resistance_K_W = GS_R(0.5);
    r.accel_filter_time_constant_s = GS_R(2e-3);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_table2d_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_speed = GS_R(60.0) * tri(t, GS_R(0.4));
    in->load = GS_R(-40.0) + GS_R(40.0) * wave(t, GS_R(0.15));
    in->ambient_temperature = GS_R(340.0);
}

/* ---- 6. Simple Gear, 2-D table, torque-driven, measured temperature input. */
static gs_status init_gear_table2d_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(2.5);
    table2d(&g);
    g.viscous_coefficients[0] = GS_R(1e-3);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(5e-3);
    r.driven_inertia = GS_R(0.08);
    r.temperature_source = GS_TEMPERATURE_FROM_INPUT;
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_table2d_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(4.0) * wave(t, GS_R(0.5)) + GS_R(0.5);
    in->load = GS_R(-2.0) * tri(t, GS_R(0.3));
    in->measured_temperature = GS_R(265.0) + GS_R(70.0) * t;
}

/* ---- 7. Simple Gear, load-dependent efficiency, torque-driven. */
static gs_status init_gear_load_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(5.0);
    g.friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    g.idle_torque_Nm = GS_R(0.002);
    g.nominal_output_torque_Nm = GS_R(2.0);
    g.efficiency_nominal = GS_R(0.9);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(1e-3);
    r.driven_inertia = GS_R(0.2);
    r.load_offset = GS_R(-0.5);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_load_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(0.4) * tri(t, GS_R(0.6)) + GS_R(0.1);
}

/* The rack's temperature table. */
static void rack_table(gs_rack_pinion_params *p)
{
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    p->temperature_count = 4;
    p->temperature_vector_K[0] = GS_R(270.0);
    p->temperature_vector_K[1] = GS_R(295.0);
    p->temperature_vector_K[2] = GS_R(320.0);
    p->temperature_vector_K[3] = GS_R(350.0);
    p->efficiency_vector[0] = GS_R(0.93);
    p->efficiency_vector[1] = GS_R(0.90);
    p->efficiency_vector[2] = GS_R(0.86);
    p->efficiency_vector[3] = GS_R(0.80);
}

/* ---- 8. Rack & Pinion, temperature table, speed-driven, heat path. */
static gs_status init_rack_temp_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_rack_pinion_params p = gs_rack_pinion_params_default();
    p.parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS;
    rack_table(&p);
    p.thermal_mass_J_K = GS_R(1.5);
    p.rack_viscous_coefficient = GS_R(2.0);
    gs_rig_params r = gs_rig_params_default();
    r.driven_inertia = GS_R(10.0);
    r.load_coulomb_friction = GS_R(20.0);
    r.heat_path = 1;
    r.thermal_resistance_K_W = GS_R(1.0);
    r.accel_filter_time_constant_s = GS_R(1e-2);
    return gs_rig_init_rack(consts, state, &p, &r, err);
}

static void input_rack_temp_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_speed = t < GS_R(0.5) ? GS_R(40.0) * t : GS_R(20.0) - GS_R(80.0) * (t - GS_R(0.5));
    in->load = GS_R(-50.0) + GS_R(30.0) * tri(t, GS_R(0.2));
}

/* ---- 9. Rack & Pinion, temperature table, torque-driven, negative direction. */
static gs_status init_rack_temp_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_rack_pinion_params p = gs_rack_pinion_params_default();
    p.pinion_radius_m = GS_R(0.02);
    p.rack_directionality = GS_RACK_NEGATIVE;
    rack_table(&p);
    p.thermal_mass_J_K = GS_R(0.5);
    p.initial_temperature_K = GS_R(290.0);
    p.pinion_viscous_coefficient = GS_R(1e-4);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(1e-4);
    r.driven_inertia = GS_R(2.0);
    r.load_offset = GS_R(5.0);
    return gs_rig_init_rack(consts, state, &p, &r, err);
}

static void input_rack_temp_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(1.5) * wave(t, GS_R(0.4)) - GS_R(0.2);
    in->load = GS_R(-30.0) * tri(t, GS_R(0.25));
}

/* ---- 10. Rack & Pinion, backlash (full undamped), torque-driven, constant efficiency. */
static gs_status init_rack_backlash_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_rack_pinion_params p = gs_rack_pinion_params_default();
    p.pinion_radius_m = GS_R(0.015);
    p.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    p.efficiency_const = GS_R(0.85);
    p.backlash.enabled = 1;
    p.backlash.hard_stop_model = GS_HARD_STOP_FULL_UNDAMPED;
    p.backlash.linear_backlash_m = GS_R(2e-4);
    p.backlash.initial_position_m = GS_R(5e-5);
    p.backlash.stiffness_N_m = GS_R(1e7);
    p.backlash.damping_N_s_m = GS_R(300.0);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(2e-4);
    r.driven_inertia = GS_R(1.0);
    r.load_coulomb_friction = GS_R(3.0);
    r.load_coulomb_speed_threshold = GS_R(1e-2);
    return gs_rig_init_rack(consts, state, &p, &r, err);
}

static void input_rack_backlash_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(0.3) * wave(t, GS_R(0.1));
    in->load = GS_R(-4.0) * tri(t, GS_R(0.45));
}

/* ---- 11. Simple Gear, compliant base shaft (about 60 Hz) with Stribeck
 * friction and torque ripple, speed-driven: speed steps that ring. */
static void ripple_on(gs_rig_params *r, int teeth)
{
    r->ripple_revolution_amplitude_Nm[0] = GS_R(0.05);
    r->ripple_revolution_phase_rad[0] = GS_R(0.7);
    r->ripple_revolution_amplitude_Nm[1] = GS_R(0.02);
    r->ripple_revolution_phase_rad[1] = GS_R(-1.3);
    r->ripple_mesh_amplitude_Nm[0] = GS_R(0.01);
    r->ripple_mesh_phase_rad[0] = GS_R(2.5);
    r->ripple_mesh_amplitude_Nm[1] = GS_R(0.004);
    r->ripple_mesh_teeth = teeth;
}

static gs_status init_gear_compliant_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.teeth_ratio = GS_R(3.0);
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.efficiency_const = GS_R(0.95);
    g.viscous_coefficients[1] = GS_R(0.05);
    gs_rig_params r = gs_rig_params_default();
    r.base_inertia_kg_m2 = GS_R(2e-3);
    r.driven_inertia = GS_R(0.05);
    r.compliance_stiffness_Nm_rad = GS_R(600.0);
    r.compliance_damping_Nm_s_rad = GS_R(0.05);
    r.load_coulomb_friction = GS_R(0.2);
    r.load_breakaway_friction = GS_R(0.6);
    r.load_stribeck_speed = GS_R(0.5);
    ripple_on(&r, 17);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_compliant_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_speed = t < GS_R(0.3) ? GS_R(0.0) : (t < GS_R(0.6) ? GS_R(20.0) : GS_R(-8.0));
    in->load = GS_R(-0.8) * tri(t, GS_R(0.35));
}

/* ---- 12. Rack & Pinion, Stribeck friction and ripple, torque-driven: the
 * rack sticks, breaks away, slides and stops. */
static gs_status init_rack_stribeck_torque(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_rack_pinion_params p = gs_rack_pinion_params_default();
    p.pinion_radius_m = GS_R(0.02);
    p.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    p.efficiency_const = GS_R(0.9);
    p.rack_viscous_coefficient = GS_R(20.0);
    gs_rig_params r = gs_rig_params_default();
    r.base_drive = GS_BASE_TORQUE_DRIVEN;
    r.base_inertia_kg_m2 = GS_R(1e-4);
    r.driven_inertia = GS_R(2.0);
    r.load_coulomb_friction = GS_R(10.0);
    r.load_breakaway_friction = GS_R(30.0);
    r.load_stribeck_speed = GS_R(0.013);
    ripple_on(&r, 20);
    return gs_rig_init_rack(consts, state, &p, &r, err);
}

static void input_rack_stribeck_torque(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_torque = GS_R(0.9) * wave(t, GS_R(0.5));
    in->load = GS_R(-5.0) * tri(t, GS_R(0.3));
}

/* ---- 13. Simple Gear, backlash (smooth) with Stribeck friction and ripple,
 * speed-driven. */
static gs_status init_gear_backlash_stribeck_speed(gs_rig_consts *consts, gs_rig_state *state, gs_error *err)
{
    gs_simple_gear_params g = gs_simple_gear_params_default();
    g.friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    g.backlash.enabled = 1;
    g.backlash.linear_backlash_m = GS_R(5e-4);
    gs_rig_params r = gs_rig_params_default();
    r.driven_inertia = GS_R(0.02);
    r.load_coulomb_friction = GS_R(0.1);
    r.load_breakaway_friction = GS_R(0.35);
    r.load_stribeck_speed = GS_R(0.2);
    ripple_on(&r, 23);
    return gs_rig_init_gear(consts, state, &g, &r, err);
}

static void input_gear_backlash_stribeck_speed(int k, gs_rig_input *in)
{
    const gs_real t = time_of(k);
    clear_input(in);
    in->base_speed = GS_R(3.0) * wave(t, GS_R(0.6));
    in->load = GS_R(0.3) * tri(t, GS_R(0.2));
}

const fw_scenario fw_scenarios[] = {
    {"gear_const_speed", init_gear_const_speed, input_gear_const_speed, STEPS},
    {"gear_const_torque", init_gear_const_torque, input_gear_const_torque, STEPS},
    {"gear_backlash_speed", init_gear_backlash_speed, input_gear_backlash_speed, STEPS},
    {"gear_backlash_torque", init_gear_backlash_torque, input_gear_backlash_torque, STEPS},
    {"gear_table2d_speed", init_gear_table2d_speed, input_gear_table2d_speed, STEPS},
    {"gear_table2d_torque", init_gear_table2d_torque, input_gear_table2d_torque, STEPS},
    {"gear_load_torque", init_gear_load_torque, input_gear_load_torque, STEPS},
    {"rack_temp_speed", init_rack_temp_speed, input_rack_temp_speed, STEPS},
    {"rack_temp_torque", init_rack_temp_torque, input_rack_temp_torque, STEPS},
    {"rack_backlash_torque", init_rack_backlash_torque, input_rack_backlash_torque, STEPS},
    {"gear_compliant_speed", init_gear_compliant_speed, input_gear_compliant_speed, STEPS},
    {"rack_stribeck_torque", init_rack_stribeck_torque, input_rack_stribeck_torque, STEPS},
    {"gear_backlash_stribeck_speed", init_gear_backlash_stribeck_speed, input_gear_backlash_stribeck_speed, STEPS},
};

const int fw_scenario_count = (int)(sizeof fw_scenarios / sizeof fw_scenarios[0]);
