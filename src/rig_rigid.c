/* rig_rigid.c - the rig's rigid mesh (rig_internal.h): a speed-driven base
 * in causal form A, and the geared solve of a free base gear, which steps a
 * torque-driven base over dt and the compliant shaft's base gear
 * (rig_compliance.c) over its sub-steps. */
#include "rig_internal.h"
#include "gs_math.h"
#include "regularised_friction.h"

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

/* A base gear geared rigidly to the driven side, over a (sub-)step h from
 * base speed w, by backward Euler, with the meshing loss and the load's
 * Coulomb friction set-valued (physics.md 11, "Lossy meshes hold").
 *
 * Base-referred (a = omega_F/omega_B), the step's momentum balance is
 *   (M_b + M_f)*w' = y0 + x0 - h*|a|*(tau_mesh*sigma_F + F_C*sigma_F)
 * with y0 = J_B*w + h*drive (the base side), x0 = a*(J_F*a*w + h*push) (the
 * driven side), M_b = J_B + h*(mu_B + drive_slope), M_f = a^2*(J_F + h*mu_F).
 * Sliding in a direction sigma, the loss of physics.md 2 at full strength is
 * linear in T_F on each side of the power flow, so the balance is the minimum
 * (sigma = +1) or maximum (sigma = -1) of two affine functions of w', one per
 * power-flow direction: lambda*(x0 - sigma*hF) + y0 - sigma*hC0 -
 * (lambda*M_f + M_b)*w' with lambda = 1 - k_fd (the follower drives) or
 * 1 + k_bd (the base drives). Both decrease with w' (the first unless the
 * gear self-locks, lambda*M_f + M_b <= 0, when it never crosses zero). So:
 * the rig moves forward when both are positive at w' = 0, to the smaller
 * root; backward when both are negative, to the larger; otherwise neither
 * side can drive the other and it stays at rest. The two cases exclude each
 * other, and at rest some friction within the bounds holds it. No iteration,
 * no linearisation: the loss never moves the rig against its push. */
geared_end gs_rig_geared_solve(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real h, gs_real inv_h,
                               const geared_base_ *base, gs_real w, gs_real drive, gs_real push)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real a_abs = gs_abs(a);
    const gs_real w_f = a * w;
    const gs_real level = friction_level(r, w_f);
    /* Regularised, the load's friction is a damper (the secant of the smooth
     * law at the start speed, regularised_friction.h) on the end speed, an
     * addition to mu_F, and no set-valued bound. */
    gs_real follower_visc = r->geared_follower_visc;
    gs_real follower_mass = r->geared_follower_mass;
    gs_real bound = level;
    gs_real creep = GS_R(0.0);
    if (r->friction_regularised) {
        creep = gs_creep_damping(level, w_f, r->inv_load_speed_threshold);
        follower_visc += a * a * creep;
        follower_mass += h * a * a * creep;
        bound = GS_R(0.0);
    }
    /* In increments dw = w' - w, so that the momenta J*w, large against a
     * step's change, do not round the speed (float drifted by 1e-7 per step):
     * each piece is n + sigma-terms = (lambda*M_f + M_b)*dw with
     * n = lambda*(h*a*push - h*a^2*mu_F*w) + h*drive - h*(mu_B + slope)*w. */
    const gs_real hf = h * a_abs * bound;
    const gs_real hc = h * a_abs * law->c0;
    const gs_real follower = h * (a * push - follower_visc * w);
    const gs_real own = h * (drive - base->visc * w);
    const gs_real l_fd = GS_R(1.0) - law->k_fd;
    const gs_real l_bd = GS_R(1.0) + law->k_bd;
    const gs_real den_fd = l_fd * follower_mass + base->mass;
    const gs_real den_bd = l_bd * follower_mass + base->mass;
    gs_real w_end = GS_R(0.0);
    gs_real n_fd = l_fd * (follower - hf) + own - hc;
    gs_real n_bd = l_bd * (follower - hf) + own - hc;
    /* at w' = 0 (dw = -w) each piece is n + den*w */
    if (n_fd + den_fd * w > GS_R(0.0) && n_bd + den_bd * w > GS_R(0.0)) {
        gs_real dw = n_bd / den_bd;
        if (den_fd > GS_R(0.0)) {
            dw = gs_min(dw, n_fd / den_fd);
        }
        w_end = gs_max(w + dw, GS_R(0.0));
    } else {
        n_fd = l_fd * (follower + hf) + own + hc;
        n_bd = l_bd * (follower + hf) + own + hc;
        if (n_fd + den_fd * w < GS_R(0.0) && n_bd + den_bd * w < GS_R(0.0)) {
            gs_real dw = n_bd / den_bd;
            if (den_fd > GS_R(0.0)) {
                dw = gs_max(dw, n_fd / den_fd);
            }
            w_end = gs_min(w + dw, GS_R(0.0));
        }
    }
    const gs_real y0 = r->base_inertia * w + h * drive;
    geared_end e;
    e.w = w_end;
    const gs_real w_f_end = a * w_end;
    /* T_F without the Coulomb torque: push - mu_F*w_F' - J_F*(w_F' - w_F)/h */
    const gs_real t_f_free = push - m->mu_follower * w_f_end - r->driven_inertia * (w_f_end - w_f) * inv_h;
    if (w_f_end > GS_R(0.0) || w_f_end < GS_R(0.0)) {
        e.coulomb = r->friction_regularised ? creep * w_f_end : (w_f_end > GS_R(0.0) ? level : -level);
        e.t_f = t_f_free - e.coulomb;
        e.tau_mesh = gs_mesh_friction_torque(law, e.t_f, w_f_end);
    } else {
        /* At rest: T_B = y0/h holds the base; what a loss-free mesh would
         * need from the Coulomb friction to hold the driven side, the
         * Coulomb friction takes up to its level and the mesh the rest. */
        const gs_real hold = t_f_free + y0 * inv_h / a;
        e.coulomb = gs_clamp(hold, -bound, bound);
        e.t_f = t_f_free - e.coulomb;
        e.tau_mesh = hold - e.coulomb;
    }
    return e;
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
