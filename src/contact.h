/* contact.h - the backward-Euler contact solve of the backlash (internal;
 * physics.md 4.3-4.5, docs/model.md).
 *
 * Why implicit: with stiffness up to 1e8 N/m on a 1e-4 kg*m^2 shaft the
 * contact frequency is ~1e5 rad/s, far beyond an explicit 1 ms step. Backward
 * Euler on the contact is unconditionally stable and, because the spring
 * potential is convex and the damping force opposes the closing speed, it can
 * only dissipate: f_spring(x1)*(x1 - x0) >= E(x1) - E(x0).
 *
 * The solve is static inline so that the rig's sub-step loop, its only user,
 * keeps its state in registers around it (one definition, here). */
#ifndef GS_CONTACT_H
#define GS_CONTACT_H

#include "mesh.h"
#include "gs_math.h"

#define NEWTON_ITERATIONS 12
/* The smooth law's root is taken where its residual is within
 * NEWTON_TOLERANCE of the force and the closing motion (smooth_accepts);
 * NEWTON_ROUNDING, eight rounding units, is the least step that moves a
 * point off the root across its rounding. */
#ifdef GS_SINGLE_PRECISION
#define NEWTON_TOLERANCE GS_R(1e-5)
#define NEWTON_ROUNDING  GS_R(1e-6)
#else
#define NEWTON_TOLERANCE GS_R(1e-7)
#define NEWTON_ROUNDING  GS_R(2e-15)
#endif

/* The smooth law's cubic step S(xi) = xi^2 (3 - 2 xi) over the transition
 * region (physics.md 4.5): zero force and slope at first contact. */
static inline gs_real smooth_step(gs_real xi)
{
    return xi * xi * (GS_R(3.0) - GS_R(2.0) * xi);
}

/* Locked teeth move together (u = 0) until the force needed to keep them
 * together would pull by more than the release threshold (physics.md 4). */
static inline int lock_holds(const gs_mesh_ *m, gs_real x, gs_real required_force)
{
    const gs_real pull = x > GS_R(0.0) ? -required_force : required_force;
    return !(pull > m->lock_release_force);
}

/* ---- The backward-Euler contact: closed forms and a short Newton.
 *
 * On the side s where the free motion ends (x + h*u_free beyond s*b/2),
 * everything is written in side-normalised variables: closing speed
 * v = s*u, the penetration at the end of the sub-step delta = p0 + h*v with
 * p0 = s*x - b/2, force f_s = s*f. Backward Euler asks for the root of
 * Phi(v) = v - v_free + c*f_s(delta, v) (c = h/m_eff), written below in the
 * penetration: h*Phi = delta - delta_free + c*h*f_s with delta_free =
 * p0 + h*v_free, where c*h*f_s = kappa*delta - lambda on a damped affine
 * piece (kappa = c*(K*h + D), lambda = c*D*p0).
 *
 * Any end speed v between 0 and the root, on the side where Phi has the sign
 * of -v, is passive with the force from the impulse balance (v_free - v)/c:
 * every law's damping part (pulling or not) has the sign of v, so the
 * balance's part beyond the spring has it too. The solve therefore ends on
 * the root, or on the end of its bracket nearer v = 0:
 *  - the full laws are affine in each piece (damped; undamped rebound for
 *    v < 0): the root is closed-form, or the stop's edge where the law jumps
 *    there (damping switched on at first contact: the force inside the jump
 *    that stops the closing motion at the edge is taken), or, clipped,
 *    v_free where the law does not push;
 *  - the smooth law is affine beyond the transition region d and a quartic
 *    in xi = delta/d inside it, solved by Newton kept inside its bracket.
 *    With the no-pull clip the residual increases and the root is unique
 *    above the speed where K*delta + D*v = 0. Without it the law pulls while
 *    the teeth separate and the residual can fall there: the bracket is then
 *    taken on one side of v = 0, where Phi(0) (the spring alone) says the
 *    root lies, and Newton bisects where its slope is not positive. */

/* The smooth law's ramp S(delta/d) inside the transition region, 1 beyond
 * it and for the full laws (side-normalised penetration delta > 0). */
static inline gs_real transition_scale(const gs_mesh_ *m, gs_real delta)
{
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        const gs_real xi = delta * m->inv_transition;
        if (xi < GS_R(1.0)) {
            return smooth_step(xi);
        }
    }
    return GS_R(1.0);
}

/* Spring part of the force at penetration delta > 0 (side-normalised). */
static inline gs_real spring_force(const gs_mesh_ *m, gs_real delta)
{
    return m->stiffness * delta * transition_scale(m, delta);
}

/* The contact law at penetration delta > 0 and closing speed v,
 * side-normalised, clipped at zero with no_pull. */
static inline gs_real law_force(const gs_mesh_ *m, gs_real delta, gs_real v)
{
    gs_real damping = m->damping;
    if (m->hard_stop == GS_HARD_STOP_FULL_UNDAMPED && v < GS_R(0.0)) {
        damping = GS_R(0.0);
    }
    gs_real raw = m->stiffness * delta + damping * v;
    if (m->no_pull) {
        raw = gs_max(GS_R(0.0), raw);
    }
    return raw * transition_scale(m, delta);
}

/* Phi(0), where the teeth stand still relative to each other: the spring's
 * alone. */
static inline gs_real residual_at_rest(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free)
{
    return p0 > GS_R(0.0) ? cs->c * spring_force(m, p0) - v_free : -v_free;
}

/* The smooth law's residual inside the transition region (4.5), in the
 * scaled penetration. With xi = delta/d and S(xi) = xi^2*(3 - 2*xi),
 * h*Phi/d = xi - xi_free + S(xi)*(kappa*xi - l), l = lambda/d. It is solved
 * in t = xi - a, with a = p0/d where the teeth start in contact (t is then
 * the penetration gained over the sub-step, h*v/d, so that the force, which
 * the impulse balance takes from v_free - v, does not lose digits to p0
 * itself) and a = 0 where they start apart:
 *   psi(t) = t - t_free + S(a + t)*raw(t),  raw = kappa*t + q,  q = kappa*a - l,
 * raw being the law before the ramp (K*delta + D*v) scaled by c*h/d. */
typedef struct {
    gs_real a, t0;  /* xi = a + t; t = v*h/d + t0 */
    gs_real t_free; /* t at v_free */
    gs_real k, k_spring, q;
} smooth_problem;

typedef struct {
    gs_real t, xi, s, raw, psi;
} smooth_point;

static GS_ALWAYS_INLINE smooth_problem smooth_setup(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0,
                                                    gs_real v_free)
{
    smooth_problem p;
    const int in_contact = p0 > GS_R(0.0);
    const gs_real scaled_p0 = p0 * m->inv_transition;
    p.a = in_contact ? scaled_p0 : GS_R(0.0);
    p.t0 = in_contact ? GS_R(0.0) : scaled_p0;
    p.k = cs->kappa;
    p.k_spring = cs->kappa_spring;
    /* kappa*a - l: kappa_s*a in contact (l = (kappa - kappa_s)*a), -l apart */
    p.q = in_contact ? p.k_spring * p.a : -cs->c_damping * p.t0;
    p.t_free = v_free * cs->h_over_d + p.t0;
    return p;
}

static GS_ALWAYS_INLINE smooth_point smooth_at(const smooth_problem *p, gs_real t)
{
    smooth_point x;
    x.t = t;
    x.xi = p->a + t;
    x.s = smooth_step(x.xi);
    x.raw = p->k * t + p->q;
    x.psi = t - p->t_free + x.s * x.raw;
    return x;
}

/* Whether x ends the solve (near: its residual is within the tolerance):
 * its residual within NEWTON_TOLERANCE of the impulse-balance force
 * (t_free - t, scaled) and the closing motion (t - t0), and passive, that
 * force less the spring's (kappa_s*xi*S) having the sign of the closing
 * speed (docs/model.md: such a force does no negative work on the contact,
 * whatever the root's error). */
static GS_ALWAYS_INLINE int smooth_accepts(const smooth_problem *p, const smooth_point *x, int *near)
{
    const gs_real balance = p->t_free - x->t;
    const gs_real closing = x->t - p->t0;
    *near = gs_abs(x->psi) <= NEWTON_TOLERANCE * (gs_abs(balance) + gs_abs(closing));
    return *near && (balance - x->s * p->k_spring * x->xi) * closing >= GS_R(0.0);
}

/* psi's slope at x, and in *step the next step from x: Halley's where its
 * correction to Newton's is moderate, Newton's otherwise. Where x is within
 * the tolerance but active (past the root, away from v = 0), as far again
 * past the root towards v = 0, and at least across psi's rounding. */
static GS_ALWAYS_INLINE gs_real smooth_step_from(const smooth_problem *p, const smooth_point *x, int near,
                                                 gs_real *step)
{
    const gs_real ds = GS_R(6.0) * x->xi * (GS_R(1.0) - x->xi);
    const gs_real slope = GS_R(1.0) + ds * x->raw + x->s * p->k;
    *step = x->psi / slope;
    if (near) {
        const gs_real across = NEWTON_ROUNDING * (gs_abs(x->t) + gs_abs(p->t_free)) / slope;
        *step += *step + (x->psi > GS_R(0.0) ? across : -across);
    } else {
        const gs_real curvature = (GS_R(6.0) - GS_R(12.0) * x->xi) * x->raw + GS_R(2.0) * ds * p->k;
        const gs_real denominator = slope - GS_R(0.5) * curvature * *step;
        if (denominator > GS_R(0.5) * slope) {
            *step = x->psi / denominator;
        }
    }
    return slope;
}

/* The closing speed and spring force at an accepted point. */
static GS_ALWAYS_INLINE gs_real smooth_end(const gs_mesh_ *m, const gs_contact_step_ *cs, const smooth_problem *p,
                                           const smooth_point *x, gs_real *spring)
{
    *spring = m->stiffness * cs->transition * x->xi * x->s;
    return (x->t - p->t0) * cs->d_over_h;
}

/* smooth_root's bracketed solve: the closed forms where the no-pull clip or
 * the affine piece beyond d holds the root, else Halley kept inside the
 * bracket (a step that leaves it, or a slope that is not positive, bisects)
 * until a point is accepted (smooth_accepts). Out of passes (a very stiff
 * contact whose force is cubic in the penetration near first touch, where
 * the iteration converges only linearly; fuzz finding), the bracket end
 * nearer v = 0, which is passive. Out of line (rig_backlash.c): the rare
 * case, kept out of the sub-step's registers. */
gs_real gs_smooth_root_bracketed(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free,
                                 gs_real guess, gs_real *spring);

/* Smooth law (4.5): the closing speed at the root, or at a passive point
 * within the tolerance of it, or at the passive end of its bracket; *spring
 * the spring force there. With the no-pull clip (Phi then increases: one
 * root) and a start inside the transition region, first one Halley step from
 * guess: where it lands inside the region with the law pushing, and is
 * accepted, it is the answer (93 to 98 % of the solves on the benchmark's
 * backlash rigs; inline, so that the caller's registers survive the common
 * case).
 * Otherwise, or from a start beyond the region (a contact loaded past d,
 * where the affine piece's closed form is the likelier answer), the
 * bracketed solve. */
static inline gs_real smooth_root(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free,
                                  gs_real guess, gs_real *spring)
{
    if (m->no_pull) {
        const smooth_problem p = smooth_setup(m, cs, p0, v_free);
        const smooth_point start = smooth_at(&p, guess * cs->h_over_d + p.t0);
        /* a start beyond the region (a contact loaded past d): the closed
         * form of the bracketed solve is the likelier answer */
        if (start.xi < GS_R(1.0)) {
            gs_real step;
            const gs_real slope = smooth_step_from(&p, &start, 0, &step);
            const smooth_point x = smooth_at(&p, start.t - step);
            int near;
            /* Phi is the quartic only in the region, pushing */
            if (x.xi > GS_R(0.0) && x.xi <= GS_R(1.0) && x.raw >= GS_R(0.0) && slope > GS_R(0.0) &&
                smooth_accepts(&p, &x, &near)) {
                return smooth_end(m, cs, &p, &x, spring);
            }
        }
    }
    return gs_smooth_root_bracketed(m, cs, p0, v_free, guess, spring);
}

/* Full laws (4.3, 4.4): the closing speed; *on_edge where the root is the
 * stop's edge on a jump of the law. */
static inline gs_real full_root(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free, int *on_edge)
{
    gs_real v = (v_free - cs->c_stiffness * p0) * cs->inv_affine_damped;
    if (m->hard_stop == GS_HARD_STOP_FULL_UNDAMPED && v < GS_R(0.0)) {
        /* Phi is continuous at v = 0 and Phi(0) > 0: the rebound piece's root */
        v = (v_free - cs->c_stiffness * p0) * cs->inv_affine_undamped;
    }
    const gs_real v_edge = -p0 * cs->inv_h;
    *on_edge = !(v > v_edge);
    if (*on_edge) {
        return v_edge;
    }
    return m->no_pull ? gs_min(v, v_free) : v; /* clipped: v_free where the law does not push */
}

static inline gs_real solve_contact(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real x, gs_real u_free,
                                    gs_real last_force, gs_real *force, gs_real *f_spring)
{
    const gs_real x_free = x + cs->h * u_free;
    gs_real side;
    if (x_free > m->half_gap) {
        side = GS_R(1.0);
    } else if (x_free < -m->half_gap) {
        side = GS_R(-1.0);
    } else {
        *force = GS_R(0.0); /* teeth apart at the end of the free motion */
        *f_spring = GS_R(0.0);
        return u_free;
    }
    const gs_real p0 = side * x - m->half_gap;
    const gs_real v_free = side * u_free;
    gs_real v;
    gs_real spring;
    int on_edge = 0; /* the root is the stop's edge, on a jump of a full law */
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        /* start from the last sub-step's force: it changes little between sub-steps */
        v = smooth_root(m, cs, p0, v_free, v_free - cs->c * side * last_force, &spring);
    } else {
        v = full_root(m, cs, p0, v_free, &on_edge);
        spring = m->stiffness * gs_max(GS_R(0.0), p0 + cs->h * v);
    }
    const gs_real delta = p0 + cs->h * v;
    /* The force at the root: the impulse balance (v_free - v)/c, which keeps
     * the momentum exact, unless the root's residual makes it do negative
     * damping work against the spring, (f - f_spring)*v < 0, on a contact
     * with kappa = c*(K*h + D) < 1; then the law at v, whose damping part
     * never does. That happens where c*f is below the rounding of v_free (a
     * heavy, finely geared follower: the balance gave f = 0 against a
     * compressed spring, energy from nothing; fuzz finding). With kappa >= 1
     * the law would multiply the root's error by kappa into the momentum
     * (fuzz finding), while the balance's damping error is the root's error
     * over c: the balance stays. On the stop's edge (a jump of the law) only
     * the balance picks the force inside the jump. (The smooth law's solve
     * makes the same check on its own point before it takes it, on the
     * scaled penetration; where that scaling rounds the balance away, this
     * one still holds.) */
    gs_real f_s = (v_free - v) * cs->inv_c;
    if (cs->law_force_conditioned && !on_edge && delta > GS_R(0.0) && (f_s - spring) * v < GS_R(0.0)) {
        f_s = law_force(m, delta, v);
    }
    *force = side * f_s;
    *f_spring = side * spring;
    return side * v;
}

static GS_ALWAYS_INLINE gs_real gs_contact_solve(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real x,
                                                 gs_real u_free, gs_real last_force, int *locked, gs_real *force,
                                                 gs_real *f_spring)
{
    if (*locked) {
        const gs_real required = u_free * cs->inv_c;
        if (lock_holds(m, x, required)) {
            (void)gs_contact_force(m, x, GS_R(0.0), f_spring);
            *force = required;
            return GS_R(0.0);
        }
        *locked = 0;
    }
    const gs_real u = solve_contact(m, cs, x, u_free, last_force, force, f_spring);
    /* Lock a slow impact: at or beyond the stop, closing or stopped (u has
     * the sign of the side, or is zero), never while the teeth separate. */
    const gs_real x_end = x + cs->h * u;
    if (m->lock_enabled && gs_abs(x_end) >= m->half_gap && gs_abs(u) < m->lock_speed && x_end * u >= GS_R(0.0)) {
        *locked = 1;
    }
    return u;
}

#endif /* GS_CONTACT_H */
