/* mesh.c - set-up, thermal mass and block-level step of the shared mesh. */
#include "mesh.h"
#include "gs_math.h"
#include "validate.h"

/* The published size of gs_simple_gear_consts and gs_rack_pinion_consts. */
GS_CONSTS_REALS_CHECK_(GS_BLOCK_CONSTS_REALS, gs_mesh_);

gs_status gs_mesh_set_backlash(gs_mesh_ *m, const gs_backlash_params *p, gs_real base_radius, gs_real follower_radius,
                               gs_error *err)
{
    m->backlash = p->enabled ? 1 : 0;
    m->base_radius = base_radius;
    m->follower_radius = follower_radius;
    if (!m->backlash) {
        return GS_OK;
    }
    gs_status s;
    switch (p->hard_stop_model) {
    case GS_HARD_STOP_SMOOTH:
    case GS_HARD_STOP_FULL_UNDAMPED:
    case GS_HARD_STOP_FULL_DAMPED:
        break;
    default:
        return gs_fail(err, GS_E_OPTION, "hard_stop_model");
    }
    if ((s = gs_check_positive(err, p->linear_backlash_m, "linear_backlash")) != GS_OK ||
        (s = gs_check_positive(err, p->stiffness_N_m, "stiffness")) != GS_OK ||
        (s = gs_check_nonnegative(err, p->damping_N_s_m, "damping")) != GS_OK ||
        (s = gs_check_finite(err, p->initial_position_m, "initial_backlash_position")) != GS_OK) {
        return s;
    }
    if (p->hard_stop_model == GS_HARD_STOP_SMOOTH) {
        if (!gs_is_finite(p->transition_region_m)) {
            return gs_fail(err, GS_E_NOT_FINITE, "transition_region");
        }
        if (!(p->transition_region_m > GS_R(0.0))) {
            return gs_fail(err, GS_E_TRANSITION_REGION, "transition_region");
        }
        if ((s = gs_check_invertible(err, p->transition_region_m, "transition_region")) != GS_OK) {
            return s;
        }
    }
    const gs_real half_gap = GS_R(0.5) * p->linear_backlash_m;
    if (p->initial_position_m < -half_gap || p->initial_position_m > half_gap) {
        return gs_fail(err, GS_E_BACKLASH_POSITION, "initial_backlash_position");
    }
    if (p->lock_enabled) {
        if ((s = gs_check_positive(err, p->contact_speed_threshold_m_s, "contact_speed_threshold")) != GS_OK ||
            (s = gs_check_nonnegative(err, p->contact_release_force_N, "contact_release_force")) != GS_OK) {
            return s;
        }
    }
    m->hard_stop = p->hard_stop_model;
    m->half_gap = half_gap;
    m->inv_transition = p->hard_stop_model == GS_HARD_STOP_SMOOTH ? GS_R(1.0) / p->transition_region_m : GS_R(0.0);
    m->stiffness = p->stiffness_N_m;
    m->damping = p->damping_N_s_m;
    m->initial_position = p->initial_position_m;
    m->no_pull = p->no_pull ? 1 : 0;
    m->lock_enabled = p->lock_enabled ? 1 : 0;
    m->lock_speed = p->contact_speed_threshold_m_s;
    m->lock_release_force = p->contact_release_force_N;
    return GS_OK;
}

gs_status gs_mesh_set_thermal(gs_mesh_ *m, gs_real thermal_mass, gs_real initial_temperature, gs_error *err)
{
    m->thermal_enabled = (m->friction == GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY ||
                          m->friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY);
    gs_status s;
    if (m->thermal_enabled) {
        if ((s = gs_check_invertible(err, thermal_mass, "thermal_mass")) != GS_OK ||
            (s = gs_check_positive(err, initial_temperature, "initial_temperature")) != GS_OK) {
            return s;
        }
    } else if (!gs_is_finite(initial_temperature) || !(initial_temperature > GS_R(0.0))) {
        /* reported as the block's temperature even without a thermal port */
        return gs_check_positive(err, initial_temperature, "initial_temperature");
    }
    m->thermal_mass = thermal_mass;
    m->initial_temperature = initial_temperature;
    return GS_OK;
}

void gs_mesh_set_temperature_table(gs_mesh_ *m, const gs_real *temperature, const gs_real *eta, int n)
{
    m->table.eta_of_T.n = n;
    for (int i = 0; i < n; ++i) {
        m->table.eta_of_T.x[i] = temperature[i];
        m->table.eta_of_T.y[i] = eta[i];
    }
}

void gs_mesh_reset(const gs_mesh_ *m, gs_block_state *st)
{
    st->temperature = m->initial_temperature;
    st->backlash_position = m->backlash ? m->initial_position : GS_R(0.0);
    st->contact_force = GS_R(0.0);
    st->follower_torque = GS_R(0.0);
    st->contact_locked = 0;
}

void gs_mesh_block_step(const gs_mesh_ *m, gs_block_state *st, gs_real dt, const gs_mesh_in_ *in, gs_mesh_out_ *out)
{
    gs_loss_ctx_ ctx;
    const gs_real temperature = in->use_temperature ? in->temperature : st->temperature;
    gs_mesh_loss_prepare(m, temperature, &ctx);
    const gs_real w_b = in->base_speed;
    gs_real w_f, tau_b, tau_f, tau_mesh, f = GS_R(0.0), f_spring = GS_R(0.0), u = GS_R(0.0);
    if (!m->backlash) {
        /* form A: omega_F from the kinematics, T_F from the follower torque */
        w_f = m->inv_ratio * w_b;
        const gs_real t_f = in->follower_torque - m->mu_follower * w_f;
        tau_mesh = gs_mesh_loss_torque(m, &ctx, t_f, w_f);
        tau_b = m->mu_base * w_b + m->inv_ratio * (tau_mesh - t_f);
        tau_f = in->follower_torque;
    } else {
        /* form C: both speeds in, torques from the contact (4.6) */
        w_f = in->follower_speed;
        u = m->base_radius * w_b - m->direction * m->follower_radius * w_f;
        f = gs_contact_force(m, st->backlash_position, u, &f_spring);
        const gs_real t_f0 = -m->direction * m->follower_radius * f;
        tau_mesh = gs_mesh_loss_from_tooth(m, &ctx, t_f0, w_f, st->follower_torque);
        st->follower_torque = t_f0 + tau_mesh;
        tau_b = m->base_radius * f + m->mu_base * w_b;
        tau_f = t_f0 + tau_mesh + m->mu_follower * w_f;
        st->backlash_position += dt * u;
        st->contact_force = f;
    }
    const gs_real p_mesh = tau_mesh * w_f;
    const gs_real p_loss = p_mesh + m->mu_base * w_b * w_b + m->mu_follower * w_f * w_f + (f - f_spring) * u;
    if (in->use_temperature) {
        st->temperature = in->temperature;
    } else {
        gs_real gain_K_W;
        gs_real den;
        gs_mesh_thermal_constants(m, dt, GS_R(0.0), &gain_K_W, &den); /* no ambient path */
        gs_mesh_thermal_step(m, st, gain_K_W, den, p_loss + in->heat_flow, GS_R(0.0));
    }
    out->base_torque = tau_b;
    out->follower_torque = tau_f;
    out->follower_speed = w_f;
    out->loss_torque = tau_mesh;
    out->mesh_loss_power = p_mesh;
    out->loss_power = p_loss;
    out->temperature = st->temperature;
    out->position = st->backlash_position;
    out->contact_force = f;
}
