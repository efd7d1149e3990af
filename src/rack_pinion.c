/* rack_pinion.c - Rack & Pinion parameters, validation and block step.
 * The rack is the mesh's follower with "radius" 1: omega_P = (s_R/r_P)*v_R. */
#include <string.h>

#include "gearsim/rack_pinion.h"
#include "blocks.h"
#include "gs_math.h"
#include "mesh.h"
#include "validate.h"

#define GS_TWO_PI GS_R(6.283185307179586)

gs_rack_pinion_params gs_rack_pinion_params_default(void)
{
    gs_rack_pinion_params p;
    memset(&p, 0, sizeof p);
    p.parameterization = GS_PARAMETERIZE_PINION_RADIUS;
    p.pinion_radius_m = GS_R(0.1);
    p.teeth_count = GS_R(20.0);
    p.spacing_m = GS_R(0.005);
    p.rack_directionality = GS_RACK_POSITIVE;
    p.friction_model = GS_FRICTION_NONE;
    p.loss_smoothing = GS_SMOOTHING_PASSIVE;
    p.efficiency_const = GS_R(0.8);
    p.temperature_count = 3;
    p.temperature_vector_K[0] = GS_R(280.0);
    p.temperature_vector_K[1] = GS_R(300.0);
    p.temperature_vector_K[2] = GS_R(320.0);
    p.efficiency_vector[0] = GS_R(0.95);
    p.efficiency_vector[1] = GS_R(0.90);
    p.efficiency_vector[2] = GS_R(0.85);
    p.power_threshold_W = GS_R(1e-3);
    p.pinion_viscous_coefficient = GS_R(0.0);
    p.rack_viscous_coefficient = GS_R(0.0);
    p.thermal_mass_J_K = GS_R(50.0);
    p.initial_temperature_K = GS_R(300.0);
    p.backlash = gs_backlash_params_default_();
    return p;
}

gs_real gs_rack_pinion_radius(const gs_rack_pinion_params *params)
{
    if (params->parameterization == GS_PARAMETERIZE_TOOTH_PARAMETERS) {
        return params->teeth_count * params->spacing_m / GS_TWO_PI; /* eq. 6.2 */
    }
    return params->pinion_radius_m;
}

gs_status gs_rack_pinion_mesh(gs_mesh_ *mesh, const gs_rack_pinion_params *p, gs_error *err)
{
    if (p == NULL || mesh == NULL) {
        return gs_fail(err, GS_E_NULL, p == NULL ? "params" : "rack_pinion");
    }
    gs_status s;
    switch (p->parameterization) {
    case GS_PARAMETERIZE_PINION_RADIUS:
        s = gs_check_invertible(err, p->pinion_radius_m, "pinion_radius");
        break;
    case GS_PARAMETERIZE_TOOTH_PARAMETERS:
        if ((s = gs_check_invertible(err, p->teeth_count, "teeth_count")) == GS_OK) {
            s = gs_check_positive(err, p->spacing_m, "spacing");
        }
        break;
    default:
        s = gs_fail(err, GS_E_OPTION, "parameterization");
        break;
    }
    if (s != GS_OK) {
        return s;
    }
    gs_real direction;
    switch (p->rack_directionality) {
    case GS_RACK_POSITIVE:
        direction = GS_R(1.0);
        break;
    case GS_RACK_NEGATIVE:
        direction = GS_R(-1.0);
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "rack_directionality");
    }
    switch (p->loss_smoothing) {
    case GS_SMOOTHING_PASSIVE:
    case GS_SMOOTHING_SIMSCAPE:
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "loss_smoothing");
    }
    switch (p->friction_model) {
    case GS_FRICTION_NONE:
        break;
    case GS_FRICTION_CONSTANT_EFFICIENCY:
        if ((s = gs_check_efficiency(err, p->efficiency_const, "efficiency_const")) != GS_OK ||
            (s = gs_check_invertible(err, p->power_threshold_W, "power_threshold")) != GS_OK) {
            return s;
        }
        break;
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        if ((s = gs_check_temperature_efficiency(err, p->temperature_vector_K, p->efficiency_vector,
                                                 p->temperature_count, p->power_threshold_W)) != GS_OK) {
            return s;
        }
        break;
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY:
    default:
        return gs_fail(err, GS_E_OPTION, "friction_model");
    }
    if ((s = gs_check_nonnegative(err, p->pinion_viscous_coefficient, "pinion_viscous_coefficient")) != GS_OK ||
        (s = gs_check_nonnegative(err, p->rack_viscous_coefficient, "rack_viscous_coefficient")) != GS_OK) {
        return s;
    }
    const gs_real radius = gs_rack_pinion_radius(p);
    if ((s = gs_check_invertible(
             err, radius, p->parameterization == GS_PARAMETERIZE_TOOTH_PARAMETERS ? "spacing" : "pinion_radius")) !=
        GS_OK) {
        return s;
    }
    gs_mesh_ m;
    memset(&m, 0, sizeof m);
    m.inv_ratio = direction * radius;
    m.direction = direction;
    m.mu_base = p->pinion_viscous_coefficient;
    m.mu_follower = p->rack_viscous_coefficient;
    m.friction = p->friction_model;
    m.smoothing = p->loss_smoothing;
    m.eta = p->friction_model == GS_FRICTION_CONSTANT_EFFICIENCY ? p->efficiency_const : GS_R(1.0);
    m.inv_power_threshold = GS_R(1.0) / p->power_threshold_W;
    m.base_load_scale = radius;
    if (p->friction_model == GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY) {
        gs_mesh_set_temperature_table(&m, p->temperature_vector_K, p->efficiency_vector, p->temperature_count);
    }
    if ((s = gs_mesh_set_thermal(&m, p->thermal_mass_J_K, p->initial_temperature_K, err)) != GS_OK ||
        (s = gs_mesh_set_backlash(&m, &p->backlash, radius, GS_R(1.0), err)) != GS_OK) {
        return s;
    }
    *mesh = m;
    gs_error_clear(err);
    return GS_OK;
}

GS_STATIC_ASSERT_(rack_pinion_consts_size, sizeof(gs_rack_pinion_consts) >= sizeof(gs_mesh_));

/* The opaque public block is a view of the internal constants. */
static const gs_mesh_ *rack_mesh(const gs_rack_pinion_consts *consts)
{
    return (const gs_mesh_ *)(const void *)consts;
}

gs_status gs_rack_pinion_init(gs_rack_pinion_consts *consts, gs_block_state *state, const gs_rack_pinion_params *params,
                              gs_error *err)
{
    if (consts == NULL || state == NULL) {
        return gs_fail(err, GS_E_NULL, consts == NULL ? "consts" : "state");
    }
    gs_mesh_ *m = (gs_mesh_ *)(void *)consts;
    const gs_status s = gs_rack_pinion_mesh(m, params, err);
    if (s == GS_OK) {
        gs_mesh_reset(m, state);
    }
    return s;
}

void gs_rack_pinion_reset(const gs_rack_pinion_consts *consts, gs_block_state *state)
{
    gs_mesh_reset(rack_mesh(consts), state);
}

void gs_rack_pinion_step(const gs_rack_pinion_consts *consts, gs_block_state *state, gs_real dt_s,
                         const gs_rack_ports_in *in, gs_rack_ports_out *out)
{
    const gs_mesh_in_ mi = {in->pinion_speed_rad_s, in->rack_velocity_m_s, in->rack_force_N,
                            in->heat_flow_W,        in->temperature_K,     in->use_temperature_input};
    gs_mesh_out_ mo;
    gs_mesh_block_step(rack_mesh(consts), state, dt_s, &mi, &mo);
    out->pinion_torque_Nm = mo.base_torque;
    out->rack_force_N = mo.follower_torque;
    out->rack_velocity_m_s = mo.follower_speed;
    out->mesh_loss_force_N = mo.loss_torque;
    out->mesh_loss_power_W = mo.mesh_loss_power;
    out->loss_power_W = mo.loss_power;
    out->temperature_K = mo.temperature;
    out->backlash_position_m = mo.position;
    out->contact_force_N = mo.contact_force;
}
