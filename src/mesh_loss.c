/* mesh_loss.c - meshing-loss laws (physics.md 2.1-2.7, 6.4, 4.6).
 * The loss torque is follower-referred and has the sign of the follower speed
 * for the passive laws, so tau_mesh*omega_F >= 0.
 *
 * Two entry points: the rigid mesh knows the follower torque T_F after the
 * loss and evaluates the laws directly (gs_mesh_loss_torque); the backlash
 * contact knows only the loss-free tooth torque T_F0 and must satisfy
 * T_F = T_F0 + tau_mesh(T_F) (gs_mesh_loss_from_tooth, physics.md 4.6). */
#include "mesh.h"
#include "gs_math.h"
#include "mesh_law.h"

/* Loss factor c with tau_mesh = T*c of the power-smoothed efficiency laws
 * (2.1/2.2): loss_pos where the power T*w is positive, loss_neg where it is
 * negative, blended by t = tanh(4*T*w/p_th). */
static gs_real power_smoothed_factor(const gs_mesh_ *m, gs_real T, gs_real w, gs_real loss_pos, gs_real loss_neg)
{
    const gs_real t = gs_tanh(GS_R(4.0) * T * w * m->inv_power_threshold);
    if (m->smoothing == GS_SMOOTHING_SIMSCAPE) {
        return GS_R(0.5) * ((loss_pos + loss_neg) * t + loss_pos - loss_neg);
    }
    return t * (t >= GS_R(0.0) ? loss_pos : loss_neg);
}

/* On the follower torque T_F (rigid mesh): L_fd when the follower drives. */
static gs_real efficiency_loss_factor(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real T, gs_real w)
{
    return power_smoothed_factor(m, T, w, ctx->loss_forward, ctx->loss_backward);
}

/* Coulomb-type laws (2.6, 2.7): magnitude C0 + slope*|T|, smoothed on speed. */
static gs_real coulomb_slope(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real T)
{
    if (m->friction == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY) {
        return m->load_slope;
    }
    const gs_real load = gs_abs(T) * m->base_load_scale;
    return GS_R(1.0) / gs_mesh_eta_at_load(m, ctx, load) - GS_R(1.0);
}

gs_real gs_mesh_loss_torque(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real T, gs_real w)
{
    switch (m->friction) {
    case GS_FRICTION_NONE:
        return GS_R(0.0);
    case GS_FRICTION_CONSTANT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        return T * efficiency_loss_factor(m, ctx, T, w);
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY:
        return (m->coulomb_idle + coulomb_slope(m, ctx, T) * gs_abs(T)) *
               gs_tanh(GS_R(4.0) * w * m->inv_speed_threshold);
    }
    return GS_R(0.0);
}

/* Loss factor c0 with tau_mesh = T_F0*c0 of the power-smoothed efficiency
 * laws, written on the tooth torque T_F0. Solving T_F = T_F0 + tau_mesh(T_F)
 * with the saturated law gives T_F = eta*T_F0 when the base drives (c0 = -L_fd)
 * and T_F = T_F0/eta when the follower drives (c0 = +L_bd): the roles of the
 * two loss factors swap. The power-flow sign of T_F0*w is that of T_F*w. */
static gs_real tooth_loss_factor(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real t_f0, gs_real w)
{
    return power_smoothed_factor(m, t_f0, w, ctx->loss_backward, ctx->loss_forward);
}

gs_real gs_mesh_loss_from_tooth(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real t_f0, gs_real w,
                                gs_real load_estimate)
{
    switch (m->friction) {
    case GS_FRICTION_NONE:
        return GS_R(0.0);
    case GS_FRICTION_CONSTANT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        return t_f0 * tooth_loss_factor(m, ctx, t_f0, w);
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY: {
        /* T_F = T_F0 + (C0 + k|T_F|)*th is linear on each sign branch of T_F;
         * the branch is that of a = T_F0 + C0*th (the map is increasing while
         * k*|th| < 1). */
        const gs_real th = gs_tanh(GS_R(4.0) * w * m->inv_speed_threshold);
        const gs_real k = coulomb_slope(m, ctx, load_estimate);
        const gs_real a = t_f0 + m->coulomb_idle * th;
        const gs_real sigma_k = a >= GS_R(0.0) ? k : -k;
        const gs_real den = GS_R(1.0) - sigma_k * th;
        if (!(den > GS_R(0.0))) {
            /* self-locking (k*|th| >= 1, back-driven): no sliding solution;
             * the loss at the tooth torque, passive; the rig's friction
             * projection stops the follower */
            return (m->coulomb_idle + k * gs_abs(t_f0)) * th;
        }
        /* tau = T_F - T_F0 = th*(C0 + sigma*k*T_F0)/den, which has the sign of th */
        return th * (m->coulomb_idle + sigma_k * t_f0) / den;
    }
    }
    return GS_R(0.0);
}

/* The out-of-line entries of mesh_law.h (every caller but gs_rig_step). */
void gs_mesh_loss_prepare(const gs_mesh_ *m, gs_real temperature, gs_loss_ctx_ *ctx)
{
    gs_mesh_loss_prepare_inline(m, temperature, ctx);
}

void gs_mesh_friction_law(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real load_estimate, gs_mesh_friction_ *law)
{
    gs_mesh_friction_law_inline(m, ctx, load_estimate, law);
}
