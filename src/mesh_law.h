/* mesh_law.h - what a step prepares of the meshing loss (internal): the
 * temperature's part (gs_loss_ctx_) and the law as a friction element at the
 * step's load (gs_mesh_friction_, physics.md 11), declared in mesh.h.
 *
 * Inline bodies, so that gs_rig_step, which runs both every step on a law
 * that changes with the temperature or the load, keeps its registers across
 * them (the 2-D table's rig: 36 instructions a step on x86-64, 22 on the
 * Cortex-M4F, against the calls); every other caller takes the out-of-line
 * entries of mesh_loss.c, which wrap these. */
#ifndef GS_MESH_LAW_H
#define GS_MESH_LAW_H

#include "mesh.h"
#include "gs_math.h"
#include "table.h"

/* The 2-D table's efficiency at the base load `load` (N*m), at the
 * temperature of the step (ctx): the two load columns around `load`,
 * each linear in temperature, then linear in load. */
static GS_ALWAYS_INLINE gs_real gs_mesh_eta_at_load(const gs_mesh_ *m, const gs_loss_ctx_ *ctx, gs_real load)
{
    const gs_table2_ *t = &m->table.eta_of_T_load;
    int lo = 0;
    int hi = 0;
    gs_real w = GS_R(0.0);
    gs_interp_bracket(t->y, t->ny, load, &lo, &hi, &w);
    const gs_real *z_lo = t->z[ctx->t_lo];
    const gs_real *z_hi = t->z[ctx->t_hi];
    const gs_real eta_lo = z_lo[lo] + ctx->t_w * (z_hi[lo] - z_lo[lo]);
    const gs_real eta_hi = z_lo[hi] + ctx->t_w * (z_hi[hi] - z_lo[hi]);
    return eta_lo + w * (eta_hi - eta_lo);
}

static GS_ALWAYS_INLINE void gs_mesh_loss_prepare_inline(const gs_mesh_ *m, gs_real temperature, gs_loss_ctx_ *ctx)
{
    gs_real eta = m->eta;
    if (m->friction == GS_FRICTION_NONE) {
        ctx->loss_forward = ctx->loss_backward = GS_R(0.0); /* no law reads them */
        return;
    }
    switch (m->friction) {
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        eta = gs_interp1(m->table.eta_of_T.x, m->table.eta_of_T.y, m->table.eta_of_T.n, temperature);
        break;
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY: {
        /* Bilinear = linear in temperature per load column, then in load
         * (gs_mesh_eta_at_load). The temperature bracket and weight are found once
         * per step; the law reads no loss factors. */
        const gs_table2_ *t = &m->table.eta_of_T_load;
        gs_interp_bracket(t->x, t->nx, temperature, &ctx->t_lo, &ctx->t_hi, &ctx->t_w);
        ctx->loss_forward = ctx->loss_backward = GS_R(0.0);
        return;
    }
    case GS_FRICTION_NONE:
    case GS_FRICTION_CONSTANT_EFFICIENCY:
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY:
        break;
    }
    ctx->loss_forward = GS_R(1.0) - eta;
    ctx->loss_backward = GS_R(1.0) / eta - GS_R(1.0);
}

static GS_ALWAYS_INLINE void gs_mesh_friction_law_inline(const gs_mesh_ *m, const gs_loss_ctx_ *ctx,
                                                         gs_real load_estimate, gs_mesh_friction_ *law)
{
    law->c0 = GS_R(0.0);
    law->lossy = 1;
    switch (m->friction) {
    case GS_FRICTION_NONE:
        law->k_fd = law->k_bd = law->q_fd = law->q_bd = GS_R(0.0);
        law->lossy = 0;
        return;
    case GS_FRICTION_CONSTANT_EFFICIENCY:
    case GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY:
        /* L_fd = 1 - eta, L_bd = 1/eta - 1; on the tooth torque the roles
         * swap: k_fd/(1 - k_fd) = L_bd, k_bd/(1 + k_bd) = L_fd */
        law->k_fd = ctx->loss_forward;
        law->k_bd = ctx->loss_backward;
        law->q_fd = ctx->loss_backward;
        law->q_bd = ctx->loss_forward;
        return;
    case GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY: {
        const gs_real k = m->load_slope;
        law->c0 = m->coulomb_idle;
        law->k_fd = law->k_bd = k;
        gs_mesh_friction_bounds(law);
        return;
    }
    case GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY: {
        /* k = 1/eta - 1: k/(1 - k) = (1 - eta)/(2*eta - 1), k/(1 + k) = 1 - eta */
        const gs_real load = gs_abs(load_estimate) * m->base_load_scale;
        const gs_real eta = gs_mesh_eta_at_load(m, ctx, load);
        const gs_real two_eta_1 = GS_R(2.0) * eta - GS_R(1.0);
        law->k_fd = law->k_bd = GS_R(1.0) / eta - GS_R(1.0);
        law->q_fd = two_eta_1 > GS_R(0.0) ? (GS_R(1.0) - eta) / two_eta_1 : GS_R(-1.0);
        law->q_bd = GS_R(1.0) - eta;
        return;
    }
    }
}

#endif /* GS_MESH_LAW_H */
