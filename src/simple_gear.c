/* simple_gear.c - Simple Gear parameters, validation and block step. */
#include <string.h>

#include "gearsim/simple_gear.h"
#include "blocks.h"
#include "gs_math.h"
#include "mesh.h"
#include "validate.h"

gs_backlash_params gs_backlash_params_default_(void)
{
    gs_backlash_params b;
    memset(&b, 0, sizeof b);
    b.enabled = 0;
    b.hard_stop_model = GS_HARD_STOP_SMOOTH;
    b.linear_backlash_m = GS_R(1e-3);
    b.base_radius_m = GS_R(0.1);
    b.transition_region_m = GS_R(1e-4);
    b.stiffness_N_m = GS_R(1e6);
    b.damping_N_s_m = GS_R(1e3);
    b.initial_position_m = GS_R(0.0);
    b.no_pull = 1;
    b.lock_enabled = 0;
    b.contact_speed_threshold_m_s = GS_R(1e-3);
    b.contact_release_force_N = GS_R(0.0);
    return b;
}

gs_simple_gear_params gs_simple_gear_params_default(void)
{
    gs_simple_gear_params p;
    memset(&p, 0, sizeof p);
    p.teeth_ratio = GS_R(2.0);
    p.output_shaft_rotates = GS_ROTATES_OPPOSITE;
    p.friction_model = GS_FRICTION_NONE;
    p.loss_smoothing = GS_SMOOTHING_PASSIVE;
    p.efficiency_const = GS_R(0.98);
    p.power_threshold_W = GS_R(1e-3);
    p.idle_torque_Nm = GS_R(0.01);
    p.nominal_output_torque_Nm = GS_R(1.0);
    p.efficiency_nominal = GS_R(0.95);
    p.speed_threshold_rad_s = GS_R(0.01);
    p.temperature_count = 3;
    p.temperature_vector_K[0] = GS_R(280.0);
    p.temperature_vector_K[1] = GS_R(300.0);
    p.temperature_vector_K[2] = GS_R(320.0);
    p.efficiency_vector[0] = GS_R(0.95);
    p.efficiency_vector[1] = GS_R(0.90);
    p.efficiency_vector[2] = GS_R(0.85);
    p.load_count = 3;
    p.load_vector_Nm[0] = GS_R(0.0);
    p.load_vector_Nm[1] = GS_R(50.0);
    p.load_vector_Nm[2] = GS_R(100.0);
    /* A plausible default map: efficiency falls with temperature, rises with load. */
    static const gs_real matrix[3][3] = {{GS_R(0.90), GS_R(0.95), GS_R(0.96)},
                                         {GS_R(0.85), GS_R(0.90), GS_R(0.92)},
                                         {GS_R(0.80), GS_R(0.85), GS_R(0.88)}};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            p.efficiency_matrix[i][j] = matrix[i][j];
        }
    }
    p.backlash = gs_backlash_params_default_();
    p.viscous_coefficients[0] = GS_R(0.0);
    p.viscous_coefficients[1] = GS_R(0.0);
    p.thermal_mass_J_K = GS_R(50.0);
    p.initial_temperature_K = GS_R(300.0);
    return p;
}

static gs_status check_friction(const gs_simple_gear_params *p, gs_error *err)
{
    gs_status s = GS_OK;
    switch (p->friction_model) {
    case GS_FRICTION_NONE:
        break;
    case GS_FRICTION_CONSTANT_EFFICIENCY:
        if ((s = gs_check_efficiency(err, p->efficiency_const, "efficiency_const")) != GS_OK) {
            return s;
        }
        s = gs_check_invertible(err, p->power_threshold_W, "power_threshold");
        break;
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY: {
        if ((s = gs_check_nonnegative(err, p->idle_torque_Nm, "idle_torque")) != GS_OK ||
            (s = gs_check_positive(err, p->nominal_output_torque_Nm, "nominal_output_torque")) != GS_OK ||
            (s = gs_check_finite(err, p->efficiency_nominal, "efficiency_nominal")) != GS_OK) {
            return s;
        }
        if (!(p->efficiency_nominal > GS_R(0.0) && p->efficiency_nominal < GS_R(1.0))) {
            return gs_fail(err, GS_E_NOMINAL_EFFICIENCY, "efficiency_nominal");
        }
        const gs_real k = GS_R(1.0) / p->efficiency_nominal - GS_R(1.0) -
                          p->teeth_ratio * p->idle_torque_Nm / p->nominal_output_torque_Nm;
        if (k < GS_R(0.0)) {
            return gs_fail(err, GS_E_IDLE_TORQUE_TOO_LARGE, "idle_torque");
        }
        s = gs_check_invertible(err, p->speed_threshold_rad_s, "speed_threshold");
        break;
    }
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        s = gs_check_temperature_efficiency(err, p->temperature_vector_K, p->efficiency_vector, p->temperature_count,
                                            p->power_threshold_W);
        break;
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY:
        if ((s = gs_check_breakpoints(err, p->temperature_vector_K, p->temperature_count, 0, "temperature_vector")) !=
                GS_OK ||
            (s = gs_check_breakpoints(err, p->load_vector_Nm, p->load_count, 1, "load_vector")) != GS_OK) {
            return s;
        }
        for (int i = 0; i < p->temperature_count; ++i) {
            if ((s = gs_check_efficiencies(err, p->efficiency_matrix[i], p->load_count, p->load_count,
                                           "efficiency_matrix")) != GS_OK) {
                return s;
            }
        }
        s = gs_check_invertible(err, p->speed_threshold_rad_s, "speed_threshold");
        break;
    default:
        s = gs_fail(err, GS_E_OPTION, "friction_model");
        break;
    }
    return s;
}

gs_status gs_simple_gear_mesh(gs_mesh_ *mesh, const gs_simple_gear_params *p, gs_error *err)
{
    if (p == NULL || mesh == NULL) {
        return gs_fail(err, GS_E_NULL, p == NULL ? "params" : "gear");
    }
    gs_status s;
    if ((s = gs_check_invertible(err, p->teeth_ratio, "teeth_ratio")) != GS_OK) {
        return s;
    }
    gs_real direction;
    switch (p->output_shaft_rotates) {
    case GS_ROTATES_SAME:
        direction = GS_R(1.0);
        break;
    case GS_ROTATES_OPPOSITE:
        direction = GS_R(-1.0);
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "output_shaft_rotates");
    }
    switch (p->loss_smoothing) {
    case GS_SMOOTHING_PASSIVE:
    case GS_SMOOTHING_SIMSCAPE:
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "loss_smoothing");
    }
    if ((s = check_friction(p, err)) != GS_OK) {
        return s;
    }
    for (int i = 0; i < 2; ++i) {
        if ((s = gs_check_nonnegative(err, p->viscous_coefficients[i], "viscous_coefficients")) != GS_OK) {
            return s;
        }
    }
    gs_mesh_ m;
    memset(&m, 0, sizeof m);
    const gs_real g = p->teeth_ratio;
    m.inv_ratio = direction / g;
    m.direction = direction;
    m.mu_base = p->viscous_coefficients[0];
    m.mu_follower = p->viscous_coefficients[1];
    m.friction = p->friction_model;
    m.smoothing = p->loss_smoothing;
    m.eta = p->friction_model == GS_FRICTION_CONSTANT_EFFICIENCY ? p->efficiency_const : GS_R(1.0);
    m.inv_power_threshold = p->power_threshold_W > GS_R(0.0) ? GS_R(1.0) / p->power_threshold_W : GS_R(0.0);
    m.base_load_scale = GS_R(1.0) / g;
    if (p->friction_model == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY) {
        m.coulomb_idle = g * p->idle_torque_Nm;
        m.load_slope =
            GS_R(1.0) / p->efficiency_nominal - GS_R(1.0) - g * p->idle_torque_Nm / p->nominal_output_torque_Nm;
    }
    if (p->friction_model == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY ||
        p->friction_model == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY) {
        m.inv_speed_threshold = GS_R(1.0) / p->speed_threshold_rad_s;
    }
    if (p->friction_model == GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY) {
        gs_mesh_set_temperature_table(&m, p->temperature_vector_K, p->efficiency_vector, p->temperature_count);
    }
    if (p->friction_model == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY) {
        m.table.eta_of_T_load.nx = p->temperature_count;
        m.table.eta_of_T_load.ny = p->load_count;
        for (int i = 0; i < p->temperature_count; ++i) {
            m.table.eta_of_T_load.x[i] = p->temperature_vector_K[i];
            for (int j = 0; j < p->load_count; ++j) {
                m.table.eta_of_T_load.z[i][j] = p->efficiency_matrix[i][j];
            }
        }
        for (int j = 0; j < p->load_count; ++j) {
            m.table.eta_of_T_load.y[j] = p->load_vector_Nm[j];
        }
    }
    if ((s = gs_mesh_set_thermal(&m, p->thermal_mass_J_K, p->initial_temperature_K, err)) != GS_OK) {
        return s;
    }
    if (p->backlash.enabled && (s = gs_check_positive(err, p->backlash.base_radius_m, "base_radius")) != GS_OK) {
        return s;
    }
    if ((s = gs_mesh_set_backlash(&m, &p->backlash, p->backlash.base_radius_m, g * p->backlash.base_radius_m, err)) !=
        GS_OK) {
        return s;
    }
    *mesh = m;
    gs_error_clear(err);
    return GS_OK;
}

GS_STATIC_ASSERT_(simple_gear_consts_size, sizeof(gs_simple_gear_consts) >= sizeof(gs_mesh_));

/* The opaque public block is a view of the internal constants. */
static const gs_mesh_ *gear_mesh(const gs_simple_gear_consts *consts)
{
    return (const gs_mesh_ *)(const void *)consts;
}

gs_status gs_simple_gear_init(gs_simple_gear_consts *consts, gs_block_state *state, const gs_simple_gear_params *params,
                              gs_error *err)
{
    if (consts == NULL || state == NULL) {
        return gs_fail(err, GS_E_NULL, consts == NULL ? "consts" : "state");
    }
    gs_mesh_ *m = (gs_mesh_ *)(void *)consts;
    const gs_status s = gs_simple_gear_mesh(m, params, err);
    if (s == GS_OK) {
        gs_mesh_reset(m, state);
    }
    return s;
}

void gs_simple_gear_reset(const gs_simple_gear_consts *consts, gs_block_state *state)
{
    gs_mesh_reset(gear_mesh(consts), state);
}

void gs_simple_gear_step(const gs_simple_gear_consts *consts, gs_block_state *state, gs_real dt_s,
                         const gs_gear_ports_in *in, gs_gear_ports_out *out)
{
    const gs_mesh_in_ mi = {in->base_speed_rad_s, in->follower_speed_rad_s, in->follower_torque_Nm,
                            in->heat_flow_W,      in->temperature_K,        in->use_temperature_input};
    gs_mesh_out_ mo;
    gs_mesh_block_step(gear_mesh(consts), state, dt_s, &mi, &mo);
    out->base_torque_Nm = mo.base_torque;
    out->follower_torque_Nm = mo.follower_torque;
    out->follower_speed_rad_s = mo.follower_speed;
    out->mesh_loss_torque_Nm = mo.loss_torque;
    out->mesh_loss_power_W = mo.mesh_loss_power;
    out->loss_power_W = mo.loss_power;
    out->temperature_K = mo.temperature;
    out->backlash_position_m = mo.position;
    out->contact_force_N = mo.contact_force;
}
