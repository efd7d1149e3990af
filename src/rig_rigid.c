/* rig_rigid.c - the rig's rigid mesh (rig_internal.h): a speed-driven base
 * in causal form A, and the geared solve of a free base gear, which steps a
 * torque-driven base over dt and the compliant shaft's base gear
 * (rig_compliance.c) over its sub-steps. */
#include "rig_internal.h"
#include "gs_math.h"
#include "rig_geared.h"

/* External torque on the driven side of the speed-driven rigid rig: load,
 * offset and Coulomb (and Stribeck) friction smoothed on the imposed speed. */
static gs_real driven_external(const rig_consts_ *r, gs_real load, gs_real w_f)
{
    return load + r->load_offset - friction_level(r, w_f) * gs_tanh(GS_R(4.0) * w_f * r->inv_load_speed_threshold);
}

void gs_rig_rigid_speed_driven(const rig_consts_ *r, gs_rig_state *st, const gs_loss_ctx_ *ctx, const gs_rig_input *in,
                               gs_real w_prev, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    /* the step's mean speed under the samples' linear ramp, or this sample */
    const gs_real w_b = r->speed_ramp ? GS_R(0.5) * (w_prev + in->base_speed) : in->base_speed;
    const gs_real alpha_b = st->base_acceleration;
    const gs_real w_f = m->inv_ratio * w_b;
    const gs_real a_f = m->inv_ratio * alpha_b;
    const gs_real tau_f = driven_external(r, in->load, w_f) - r->driven_inertia * a_f;
    const gs_real t_f = tau_f - m->mu_follower * w_f;
    const gs_real tau_mesh = gs_mesh_loss_torque(m, ctx, t_f, w_f);
    const gs_real tau_b = m->mu_base * w_b + m->inv_ratio * (tau_mesh - t_f);
    st->block.follower_torque = t_f;
    st->base_speed = w_b;
    st->follower_speed = w_f;
    out->base_torque = tau_b + r->base_inertia * alpha_b;
    if (r->ripple) { /* at the step's mid angle: the mean over the step to second order */
        out->base_torque += gs_rig_ripple_torque(r, st->base_angle + GS_R(0.5) * r->dt * w_b);
    }
    out->base_port_torque = tau_b;
    out->follower_port_torque = tau_f;
    out->follower_acceleration = a_f;
    out->mesh_loss_power = tau_mesh * w_f;
    out->loss_power = out->mesh_loss_power + m->mu_base * w_b * w_b + m->mu_follower * w_f * w_f;
    out->port_power = tau_b * w_b + tau_f * w_f;
}

void gs_rig_rigid_torque_driven(const rig_consts_ *r, gs_rig_state *st, const gs_mesh_friction_ *law,
                                const gs_rig_input *in, gs_rig_output *out)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real w = st->base_speed;
    gs_real drive = in->base_torque;
    if (r->ripple) {
        /* at the start angle: with the angle advanced by the end speed this is
         * symplectic Euler, so the ripple's potential energy does not drift */
        drive -= gs_rig_ripple_torque(r, st->base_angle);
    }
    gs_mesh_friction_ law_now;
    const gs_mesh_friction_ *law_k = gs_rig_step_law(r, law, st->block.follower_torque, a * w, &law_now);
    const geared_end e =
        gs_rig_geared_solve(r, law_k, r->dt, r->inv_dt, &r->geared_base, w, drive, in->load + r->load_offset);
    const gs_real w_f = a * e.w;
    const gs_real tau_b = m->mu_base * e.w + a * (e.tau_mesh - e.t_f);
    const gs_real tau_f = e.t_f + m->mu_follower * w_f;
    st->block.follower_torque = e.t_f;
    st->base_speed = e.w;
    st->follower_speed = w_f;
    out->base_torque = in->base_torque;
    out->base_port_torque = tau_b;
    out->follower_port_torque = tau_f;
    out->follower_acceleration = a * (e.w - w) * r->inv_dt;
    out->mesh_loss_power = e.tau_mesh * w_f;
    out->loss_power = out->mesh_loss_power + m->mu_base * e.w * e.w + m->mu_follower * w_f * w_f;
    out->port_power = tau_b * e.w + tau_f * w_f;
}
