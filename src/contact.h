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
/* Newton stops once its step is below NEWTON_TOLERANCE of the bracket scale
 * |u_free| + (bracket width): deterministic, and the worst case stays at
 * NEWTON_ITERATIONS evaluations. NEWTON_ASYMPTOTIC (about its square root)
 * marks steps small enough for Newton's quadratic error bound to hold. */
#ifdef GS_SINGLE_PRECISION
#define NEWTON_TOLERANCE  GS_R(1e-6)
#define NEWTON_ASYMPTOTIC GS_R(1e-3)
#else
#define NEWTON_TOLERANCE  GS_R(1e-13)
#define NEWTON_ASYMPTOTIC GS_R(3e-7)
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

/* Smooth law (4.5): the closing speed at the root, or at the passive end of
 * its bracket; *spring the spring force there. Decisions are taken on the
 * penetration delta = p0 + h*v, values in the closing speed v.
 *
 * Inside the transition region, with xi = delta/d and S(xi) =
 * xi^2*(3 - 2*xi), h*Phi/d = xi - xi_free + S(xi)*(kappa*xi - l), l =
 * lambda/d. Newton solves it in t = xi - a, with a = p0/d where the teeth
 * start in contact (t is then the penetration gained over the sub-step,
 * h*v/d, so that the force, which the impulse balance takes from
 * v_free - v, does not lose digits to p0 itself) and a = 0 where they start
 * apart: psi(t) = t - t_free + S(a + t)*(kappa*t + q), q = kappa*a - l. It
 * is kept inside its bracket (a step that leaves it, or a slope that is not
 * positive, bisects) and starts from guess. It stops at a step below the
 * tolerance, or earlier once Newton's own error bound for the step just
 * computed, |psi''|*step^2/(2*psi'), is below half the tolerance: that step
 * is then taken without evaluating again. The bound is used only for steps
 * already below sqrt(tolerance) of the bracket, where it is in its
 * asymptotic range (with v_free far above the bracket, a light rack at 4e4
 * m/s, a step judged against |v_free| passed off the root; fuzz finding).
 * Out of passes (a very stiff contact whose force is cubic in the
 * penetration near first touch, where Newton converges only linearly; fuzz
 * finding), the bracket end nearer v = 0, which is passive. */
static inline gs_real smooth_root(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real p0, gs_real v_free,
                                  gs_real guess, gs_real *spring)
{
    const gs_real d = cs->transition;
    const gs_real delta_free = p0 + cs->h * v_free;
    const gs_real lambda = cs->c_damping * p0; /* h*Phi = delta - delta_free + kappa*delta - lambda, affine */
    gs_real lo = -p0 * cs->inv_h;              /* the teeth just touching */
    gs_real hi = v_free;
    if (m->no_pull) {
        if (cs->kappa * delta_free <= lambda) {
            /* the clipped force is zero at the free motion's end */
            *spring = spring_force(m, delta_free);
            return v_free;
        }
        /* Below the speed where K*delta + D*v = 0 the clipped force is zero
         * and Phi < 0: the root lies above it. Starting the bracket there
         * keeps the kink of the clip out of Newton's way; on a stiff contact
         * (kappa ~ 1e6) Newton stepped across it from the flat side and
         * bisection did not close the bracket in 12 passes (fuzz finding). */
        lo = gs_max(lo, -cs->c_stiffness * p0 * cs->inv_kappa);
    } else {
        /* the law pulls while the teeth separate: keep to one side of v = 0 */
        const gs_real at_rest = residual_at_rest(m, cs, p0, v_free);
        if (!(at_rest < GS_R(0.0) || at_rest > GS_R(0.0))) {
            *spring = spring_force(m, p0);
            return GS_R(0.0);
        }
        if (at_rest < GS_R(0.0)) {
            lo = gs_max(lo, GS_R(0.0));
        } else {
            hi = GS_R(0.0);
        }
    }
    /* closing speed at which the penetration reaches the transition depth d */
    const gs_real v_full = (d - p0) * cs->inv_h;
    if (hi > v_full) {
        /* beyond d the law is affine: the root there if h*Phi(d) <= 0 */
        if (lo >= v_full || d - delta_free + cs->kappa * d - lambda <= GS_R(0.0)) {
            const gs_real v = gs_clamp((v_free - cs->c_stiffness * p0) * cs->inv_affine_damped, gs_max(v_full, lo), hi);
            *spring = m->stiffness * (p0 + cs->h * v);
            return v;
        }
        hi = v_full;
    }
    /* Newton in t (see above) */
    const gs_real to_t = cs->h_over_d;
    const int in_contact = p0 > GS_R(0.0);
    const gs_real t0 = in_contact ? GS_R(0.0) : p0 * m->inv_transition; /* t = v*h/d + t0 */
    const gs_real a = in_contact ? p0 * m->inv_transition : GS_R(0.0);
    const gs_real k = cs->kappa;
    /* kappa*a - l: kappa_s*a in contact (l = (kappa - kappa_s)*a), -l apart */
    const gs_real q = in_contact ? cs->kappa_spring * a : -cs->c_damping * t0;
    const gs_real t_free = v_free * to_t + t0;
    const gs_real tolerance = NEWTON_TOLERANCE * (gs_abs(v_free) + (hi - lo)) * to_t;
    gs_real t_lo = lo * to_t + t0; /* psi(t_lo) <= 0 <= psi(t_hi), narrowed every pass */
    gs_real t_hi = hi * to_t + t0;
    const gs_real asymptotic = NEWTON_ASYMPTOTIC * (t_hi - t_lo);
    gs_real t = guess * to_t + t0;
    if (!(t > t_lo && t < t_hi)) {
        t = GS_R(0.5) * (t_lo + t_hi);
    }
    for (int i = 0; i < NEWTON_ITERATIONS; ++i) {
        const gs_real xi = a + t;
        const gs_real s = xi * xi * (GS_R(3.0) - GS_R(2.0) * xi);
        const gs_real ds = GS_R(6.0) * xi * (GS_R(1.0) - xi);
        const gs_real raw = k * t + q;
        const gs_real psi = t - t_free + s * raw;
        if (psi > GS_R(0.0)) {
            t_hi = t;
        } else if (psi < GS_R(0.0)) {
            t_lo = t;
        } else {
            *spring = m->stiffness * d * xi * s;
            return (t - t0) * cs->d_over_h;
        }
        const gs_real slope = GS_R(1.0) + ds * raw + s * k;
        if (!(slope > GS_R(0.0))) { /* the pulling law can make psi fall: bisect */
            t = GS_R(0.5) * (t_lo + t_hi);
            continue;
        }
        const gs_real step = psi / slope;
        const gs_real next = t - step;
        const gs_real size = gs_abs(step);
        int converged = size <= tolerance;
        if (!converged && size <= asymptotic) {
            const gs_real curvature = (GS_R(6.0) - GS_R(12.0) * xi) * raw + GS_R(2.0) * ds * k;
            converged = gs_abs(curvature) * size * size <= slope * tolerance;
        }
        if (converged && next >= t_lo && next <= t_hi) {
            const gs_real xi_root = a + next;
            *spring = m->stiffness * d * xi_root * smooth_step(xi_root);
            return (next - t0) * cs->d_over_h;
        }
        t = next > t_lo && next < t_hi ? next : GS_R(0.5) * (t_lo + t_hi);
    }
    /* out of passes: the bracket end nearer v = 0, passive */
    lo = (t_lo - t0) * cs->d_over_h;
    hi = (t_hi - t0) * cs->d_over_h;
    if (lo < GS_R(0.0) && hi > GS_R(0.0)) {
        if (residual_at_rest(m, cs, p0, v_free) > GS_R(0.0)) {
            hi = GS_R(0.0);
        } else {
            lo = GS_R(0.0);
        }
    }
    const gs_real v = lo >= GS_R(0.0) ? lo : hi;
    const gs_real delta = p0 + cs->h * v;
    *spring = delta > GS_R(0.0) ? spring_force(m, delta) : GS_R(0.0);
    return v;
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
     * the balance picks the force inside the jump. */
    gs_real f_s = (v_free - v) * cs->inv_c;
    if (cs->law_force_conditioned && !on_edge && delta > GS_R(0.0) && (f_s - spring) * v < GS_R(0.0)) {
        f_s = law_force(m, delta, v);
    }
    *force = side * f_s;
    *f_spring = side * spring;
    return side * v;
}

static inline gs_real gs_contact_solve(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real x, gs_real u_free,
                                       gs_real last_force, int *locked, gs_real *force, gs_real *f_spring)
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
