/* rig_geared.h - the geared solve of a free base gear (internal; rig_internal.h):
 * the torque-driven rigid rig's step and the compliant shaft's sub-step.
 * Static inline, like contact.h, so that the compliant sub-step loop keeps
 * its state in registers around it (one definition, here). */
#ifndef GS_RIG_GEARED_H
#define GS_RIG_GEARED_H

#include "rig_internal.h"
#include "gs_math.h"
#include "regularised_friction.h"

/* What the geared solve leaves at the end of a (sub-)step. */
typedef struct {
    gs_real w;        /* base speed at the end */
    gs_real t_f;      /* net follower torque T_F */
    gs_real tau_mesh; /* the meshing loss, follower-referred */
    gs_real coulomb;  /* the load's Coulomb torque that acted (against the follower's motion) */
} geared_end;

/* The law's and the friction bound's terms over a (sub-)step, h_a = h*|a|:
 * one expression for the solve and for init, which fixes them where they
 * are fixed (geared_fixed), so both give the same bits. */
static inline geared_law_ gs_rig_geared_law(const gs_mesh_friction_ *law, gs_real h_a, gs_real bound)
{
    geared_law_ g;
    g.l_fd = GS_R(1.0) - law->k_fd;
    g.l_bd = GS_R(1.0) + law->k_bd;
    g.hc = h_a * law->c0;
    g.hf = h_a * bound;
    return g;
}

/* A power-flow piece's mass lambda*M_f + M_b (lambda: l_fd or l_bd). */
static inline gs_real gs_rig_geared_piece_mass(gs_real lambda, gs_real follower_mass, const geared_base_ *base)
{
    return lambda * follower_mass + base->mass;
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
 * no linearisation: the loss never moves the rig against its push.
 *
 * inv_h = 1/h; drive is the explicit torque on the base gear, base its mass
 * and implicit slope (geared_base or geared_base_end), push the driven
 * side's load and offset. */
static inline geared_end gs_rig_geared_solve(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real h,
                                             gs_real inv_h, const geared_base_ *base, gs_real w, gs_real drive,
                                             gs_real push)
{
    const gs_mesh_ *m = &r->mesh;
    const gs_real a = m->inv_ratio;
    const gs_real a_abs = gs_abs(a);
    const gs_real w_f = a * w;
    /* In increments dw = w' - w, so that the momenta J*w, large against a
     * step's change, do not round the speed (float drifted by 1e-7 per step):
     * each piece is n + sigma-terms = (lambda*M_f + M_b)*dw with
     * n = lambda*(h*a*push - h*a^2*mu_F*w) + h*drive - h*(mu_B + slope)*w,
     * hf = h*|a|*bound and hc = h*|a|*c0. */
    gs_real level, bound, den_fd, den_bd;
    geared_law_ g;
    gs_real follower_visc = r->geared_follower_visc;
    gs_real creep = GS_R(0.0);
    if (r->geared_fixed) { /* law is r->loss_law, h the solve's at init */
        level = bound = r->load_coulomb;
        g = r->geared_law;
        den_fd = base->den_fd;
        den_bd = base->den_bd;
    } else {
        level = friction_level(r, w_f);
        /* Regularised, the load's friction is a damper (the secant of the
         * smooth law at the start speed, regularised_friction.h) on the end
         * speed, an addition to mu_F, and no set-valued bound. */
        gs_real follower_mass = r->geared_follower_mass;
        bound = level;
        if (r->friction_regularised) {
            creep = gs_creep_damping(level, w_f, r->inv_load_speed_threshold);
            follower_visc += a * a * creep;
            follower_mass += h * a * a * creep;
            bound = GS_R(0.0);
        }
        g = gs_rig_geared_law(law, h * a_abs, bound);
        den_fd = gs_rig_geared_piece_mass(g.l_fd, follower_mass, base);
        den_bd = gs_rig_geared_piece_mass(g.l_bd, follower_mass, base);
    }
    const gs_real l_fd = g.l_fd, l_bd = g.l_bd, hc = g.hc, hf = g.hf;
    const gs_real follower = h * (a * push - follower_visc * w);
    const gs_real own = h * (drive - base->visc * w);
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

#endif /* GS_RIG_GEARED_H */
