/* hard_stop.c - backlash contact (physics.md 4.3-4.5) and its backward-Euler
 * integration.
 *
 * Why implicit: with stiffness up to 1e8 N/m on a 1e-4 kg*m^2 shaft the
 * contact frequency is ~1e5 rad/s, far beyond an explicit 1 ms step. Backward
 * Euler on the contact is unconditionally stable and, because the spring
 * potential is convex and the damping force opposes the closing speed, it can
 * only dissipate: f_spring(x1)*(x1 - x0) >= E(x1) - E(x0). */
#include "mesh.h"
#include "gs_math.h"

#define NEWTON_ITERATIONS 12
/* Newton stops once its step is below NEWTON_TOLERANCE of the bracket scale
 * |u_free| + (bracket width): deterministic, and the worst case stays at
 * NEWTON_ITERATIONS evaluations. NEWTON_ASYMPTOTIC (about its square root)
 * marks steps small enough for Newton's quadratic error bound to hold. */
#ifdef GS_SINGLE_PRECISION
#define NEWTON_TOLERANCE GS_R(1e-6)
#define NEWTON_ASYMPTOTIC GS_R(1e-3)
#else
#define NEWTON_TOLERANCE GS_R(1e-13)
#define NEWTON_ASYMPTOTIC GS_R(3e-7)
#endif

/* The smooth law's cubic step S(xi) = xi^2 (3 - 2 xi) over the transition
 * region (physics.md 4.5): zero force and slope at first contact. */
static inline gs_real smooth_step(gs_real xi)
{
    return xi * xi * (GS_R(3.0) - GS_R(2.0) * xi);
}

/* Force and its derivative along u when x = x0 + h*u (dfdu = h*df/dx + df/dv). */
static gs_real contact_force_d(const gs_mesh_ *m, gs_real x, gs_real u, gs_real h,
                               gs_real *dfdu, gs_real *f_spring)
{
    gs_real delta;
    gs_real side;
    if (x > m->half_gap) {
        delta = x - m->half_gap;
        side = GS_R(1.0);
    } else if (x < -m->half_gap) {
        delta = x + m->half_gap;
        side = GS_R(-1.0);
    } else {
        *dfdu = GS_R(0.0);
        *f_spring = GS_R(0.0);
        return GS_R(0.0);
    }
    gs_real scale = GS_R(1.0);
    gs_real dscale_du = GS_R(0.0);
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        const gs_real xi_raw = gs_abs(delta) * m->inv_transition;
        if (xi_raw < GS_R(1.0)) {
            scale = smooth_step(xi_raw);
            dscale_du = GS_R(6.0) * xi_raw * (GS_R(1.0) - xi_raw) * m->inv_transition * h * side;
        }
    }
    gs_real damping = m->damping;
    if (m->hard_stop == GS_HARD_STOP_FULL_UNDAMPED && side * u < GS_R(0.0)) {
        damping = GS_R(0.0); /* undamped rebound: damping only while the teeth close */
    }
    const gs_real raw = m->stiffness * delta + damping * u;
    gs_real f = scale * raw;
    gs_real d = dscale_du * raw + scale * (m->stiffness * h + damping);
    if (m->no_pull && side * f < GS_R(0.0)) {
        f = GS_R(0.0);
        d = GS_R(0.0);
    }
    *f_spring = scale * m->stiffness * delta;
    *dfdu = d;
    return f;
}

gs_real gs_contact_force(const gs_mesh_ *m, gs_real x, gs_real u, gs_real *f_spring)
{
    gs_real unused;
    return contact_force_d(m, x, u, GS_R(0.0), &unused, f_spring);
}

gs_real gs_contact_energy(const gs_mesh_ *m, gs_real x)
{
    gs_real delta = GS_R(0.0);
    if (x > m->half_gap) {
        delta = x - m->half_gap;
    } else if (x < -m->half_gap) {
        delta = -m->half_gap - x;
    }
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        /* integral of S(s/d)*K*s ds: K*(3 s^4/(4 d^2) - 2 s^5/(5 d^3)) up to d, then linear spring */
        const gs_real d = GS_R(1.0) / m->inv_transition;
        const gs_real s = gs_min(delta, d);
        const gs_real s2 = s * s;
        const gs_real ramp = m->stiffness * s2 * s2 * m->inv_transition * m->inv_transition
                             * (GS_R(0.75) - GS_R(0.4) * s * m->inv_transition);
        if (delta > d) {
            return ramp + GS_R(0.5) * m->stiffness * (delta * delta - d * d);
        }
        return ramp;
    }
    return GS_R(0.5) * m->stiffness * delta * delta;
}

/* Locked teeth move together (u = 0) until the force needed to keep them
 * together would pull by more than the release threshold (physics.md 4). */
static int lock_holds(const gs_mesh_ *m, gs_real x, gs_real required_force)
{
    const gs_real pull = x > GS_R(0.0) ? -required_force : required_force;
    return !(pull > m->lock_release_force);
}

void gs_contact_prepare(const gs_mesh_ *m, gs_real h, gs_real inv_mass, gs_contact_step_ *cs)
{
    cs->h = h;
    cs->inv_h = GS_R(1.0) / h;
    cs->c = h * inv_mass;
    cs->inv_c = GS_R(1.0) / cs->c;
    cs->c_stiffness = cs->c * m->stiffness;
    cs->draw_dv = m->stiffness * h + m->damping;
    cs->inv_affine_damped = GS_R(1.0) / (GS_R(1.0) + cs->c * cs->draw_dv);
    cs->inv_affine_undamped = GS_R(1.0) / (GS_R(1.0) + cs->c * m->stiffness * h);
    cs->dxi_dv = h * m->inv_transition;
    cs->transition = m->inv_transition > GS_R(0.0) ? GS_R(1.0) / m->inv_transition : GS_R(0.0);
    cs->law_force_conditioned = cs->c * cs->draw_dv < GS_R(1.0);
}

/* ---- The no-pull contact (the default): closed forms and a short Newton.
 *
 * With the no-pull clip the force never pulls, so on the side s where the
 * free motion ends (x + h*u_free beyond s*b/2) everything can be written in
 * side-normalised variables: closing speed v = s*u, penetration
 * delta(v) = p0 + h*v with p0 = s*x - b/2, force f_s = s*f >= 0. The residual
 * Phi(v) = v - v_free + c*f_s(v) is then increasing with slope >= 1 wherever
 * it is continuous, Phi(v_edge) < 0 at v_edge = -p0/h (teeth just touching)
 * and Phi(v_free) >= 0: the root lies in [v_edge, v_free] and is unique.
 * The full laws are affine in each piece, so their root is closed-form; the
 * smooth law is affine beyond the transition region and needs Newton only
 * inside it. */

typedef struct {
    const gs_contact_step_ *cs;
    gs_real p0;     /* penetration at the start of the sub-step, m (< 0: apart) */
    gs_real v_free; /* closing speed of the free motion, m/s */
} closing_;

/* Root of v - v_free + c*(K*delta(v) + damping*v) = 0: an affine piece. */
static gs_real affine_root(const closing_ *q, gs_real inv_affine)
{
    return (q->v_free - q->cs->c_stiffness * q->p0) * inv_affine;
}

/* Full laws (4.3, 4.4): the affine piece's root if the teeth are in contact
 * there and it pushes; the stop's edge if the law jumps over zero there
 * (damping switched on at first contact); v_free if the clipped force is zero
 * at v_free (separating faster than the spring pushes). */
static gs_real full_root(const gs_mesh_ *m, const closing_ *q, int *on_edge)
{
    gs_real v = affine_root(q, q->cs->inv_affine_damped);
    if (m->hard_stop == GS_HARD_STOP_FULL_UNDAMPED && v < GS_R(0.0)) {
        /* Phi is continuous at v = 0 and Phi(0) > 0: the rebound piece's root */
        v = affine_root(q, q->cs->inv_affine_undamped);
    }
    const gs_real v_edge = -q->p0 * q->cs->inv_h;
    *on_edge = !(v > v_edge);
    if (*on_edge) {
        return v_edge;
    }
    return gs_min(v, q->v_free);
}

/* Smooth law (4.5) inside the transition region: f_s = S(xi)*max(0, K*delta + D*v),
 * xi = delta/d, S = xi^2 (3 - 2 xi). Newton kept inside [lo, hi] (a step that
 * leaves it bisects), started from v_guess. It stops at a step below the
 * tolerance, or earlier once Newton's own error bound for the step just
 * computed, |Phi''|*step^2/(2*Phi'), is below half the tolerance: that step
 * is then taken without evaluating the law again. The bound is used only for
 * steps already below sqrt(tolerance), where it is in its asymptotic range.
 * Without convergence in NEWTON_ITERATIONS passes, a passive bracket end. */
static gs_real smooth_transition_root(const gs_mesh_ *m, const closing_ *q, gs_real v_lo, gs_real v_hi,
                                      gs_real v_guess)
{
    gs_real lo = v_lo; /* Phi(lo) <= 0 <= Phi(hi), narrowed every pass */
    gs_real hi = v_hi;
    const gs_contact_step_ *cs = q->cs;
    const gs_real k = m->stiffness;
    const gs_real d_damp = m->damping;
    const gs_real inv_d = m->inv_transition;
    const gs_real scale_v = gs_abs(q->v_free) + (hi - lo);
    const gs_real tolerance = NEWTON_TOLERANCE * scale_v;
    /* the early stop judges a step against the bracket, not against |v_free|:
     * with v_free far above the bracket (a light rack at 4e4 m/s) a step of
     * 1e-3 m/s looked asymptotic and the bound passed it off the root (fuzz
     * finding) */
    const gs_real asymptotic = NEWTON_ASYMPTOTIC * (hi - lo);
    gs_real v = v_guess > lo && v_guess < hi ? v_guess : GS_R(0.5) * (lo + hi);
    for (int i = 0; i < NEWTON_ITERATIONS; ++i) {
        const gs_real delta = q->p0 + cs->h * v;
        const gs_real xi = gs_clamp(delta * inv_d, GS_R(0.0), GS_R(1.0));
        const gs_real raw = k * delta + d_damp * v;
        gs_real phi = v - q->v_free;
        gs_real slope = GS_R(1.0);
        gs_real ds = GS_R(0.0);
        if (raw > GS_R(0.0)) {
            const gs_real s = smooth_step(xi);
            ds = GS_R(6.0) * xi * (GS_R(1.0) - xi) * cs->dxi_dv;
            phi += cs->c * s * raw;
            slope += cs->c * (ds * raw + s * cs->draw_dv);
        }
        if (phi > GS_R(0.0)) {
            hi = v;
        } else if (phi < GS_R(0.0)) {
            lo = v;
        } else {
            return v;
        }
        const gs_real step = phi / slope;
        const gs_real next = v - step;
        const gs_real size = gs_abs(step);
        int converged = size <= tolerance;
        if (!converged && size <= asymptotic && raw > GS_R(0.0)) {
            const gs_real dds = (GS_R(6.0) - GS_R(12.0) * xi) * cs->dxi_dv * cs->dxi_dv;
            const gs_real curvature = cs->c * (dds * raw + GS_R(2.0) * ds * cs->draw_dv);
            converged = gs_abs(curvature) * size * size <= slope * tolerance;
        }
        if (converged && next >= lo && next <= hi) {
            return next;
        }
        v = next > lo && next < hi ? next : GS_R(0.5) * (lo + hi);
    }
    /* Out of passes (a very stiff contact whose force is cubic in the
     * penetration near first touch: Newton converges only linearly there).
     * Return the bracket end on the side of the motion: with the force taken
     * from the impulse balance, the closing end lo >= 0 gives a force at or
     * above the law's and the separating end hi <= 0 one at or below it, so
     * the contact damping never does negative work (fuzz finding). */
    if (lo < GS_R(0.0) && hi > GS_R(0.0)) {
        const gs_real raw0 = k * q->p0;
        gs_real phi0 = -q->v_free;
        if (raw0 > GS_R(0.0)) {
            phi0 += cs->c * smooth_step(gs_clamp(q->p0 * inv_d, GS_R(0.0), GS_R(1.0))) * raw0;
        }
        if (phi0 > GS_R(0.0)) {
            hi = GS_R(0.0);
        } else {
            lo = GS_R(0.0);
        }
    }
    return lo >= GS_R(0.0) ? lo : hi;
}

static gs_real smooth_root(const gs_mesh_ *m, const closing_ *q, gs_real v_guess)
{
    const gs_contact_step_ *cs = q->cs;
    if (m->stiffness * (q->p0 + cs->h * q->v_free) + m->damping * q->v_free <= GS_R(0.0)) {
        return q->v_free; /* the clipped force is zero at v_free: Phi(v_free) = 0 */
    }
    const gs_real v_edge = -q->p0 * cs->inv_h;
    /* closing speed at which the penetration reaches the transition depth d */
    const gs_real v_full = (cs->transition - q->p0) * cs->inv_h;
    if (v_full < q->v_free) {
        const gs_real force_at_full = gs_max(GS_R(0.0), m->stiffness * cs->transition + m->damping * v_full);
        if (v_full - q->v_free + cs->c * force_at_full <= GS_R(0.0)) {
            /* the root is beyond d, on the affine piece (or at v_free if it is clipped) */
            return gs_clamp(affine_root(q, cs->inv_affine_damped), v_full, q->v_free);
        }
    }
    /* Below the speed where K*delta + D*v = 0 the clipped force is zero and
     * Phi(v) = v - v_free < 0: the root lies above it. Starting the bracket
     * there keeps the kink of the clip out of Newton's way; on a stiff
     * contact (kappa ~ 1e6) Newton stepped across it from the flat side and
     * bisection did not close the bracket in 12 passes (fuzz finding). */
    const gs_real v_kink = -m->stiffness * q->p0 / cs->draw_dv;
    return smooth_transition_root(m, q, gs_max(v_edge, v_kink), gs_min(v_full, q->v_free), v_guess);
}

/* The smooth law's ramp S(delta/d) inside the transition region, 1 beyond
 * it and for the full laws (side-normalised penetration delta > 0). */
static gs_real transition_scale(const gs_mesh_ *m, gs_real delta)
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
static gs_real spring_force(const gs_mesh_ *m, gs_real delta)
{
    return m->stiffness * delta * transition_scale(m, delta);
}

/* The clipped contact law at penetration delta > 0 and closing speed v,
 * side-normalised (>= 0). */
static gs_real law_force(const gs_mesh_ *m, gs_real delta, gs_real v)
{
    gs_real damping = m->damping;
    if (m->hard_stop == GS_HARD_STOP_FULL_UNDAMPED && v < GS_R(0.0)) {
        damping = GS_R(0.0);
    }
    return gs_max(GS_R(0.0), m->stiffness * delta + damping * v) * transition_scale(m, delta);
}

static gs_real solve_no_pull(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real x, gs_real u_free,
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
    closing_ q;
    q.cs = cs;
    q.p0 = side * x - m->half_gap;
    q.v_free = side * u_free;
    gs_real v;
    int on_edge = 0; /* the root is the stop's edge, on a jump of a full law */
    if (m->hard_stop == GS_HARD_STOP_SMOOTH) {
        /* start from the last sub-step's force: it changes little between sub-steps */
        v = smooth_root(m, &q, q.v_free - cs->c * side * last_force);
    } else {
        v = full_root(m, &q, &on_edge);
    }
    const gs_real delta = q.p0 + cs->h * v;
    /* The force at the root: the impulse balance (v_free - v)/c, which keeps
     * the momentum exact, unless the root's residual makes it do negative
     * damping work against the spring, (f - f_spring)*v < 0, on a contact
     * with kappa = c*(K*h + D) < 1; then the law at v, whose damping part
     * S*D*v*v never does. That happens where c*f is below the rounding of
     * v_free (a heavy, finely geared follower: the balance gave f = 0
     * against a compressed spring, energy from nothing; fuzz finding). With
     * kappa >= 1 the law would multiply the root's error by kappa into the
     * momentum (fuzz finding), while the balance's damping error is the
     * root's error over c: the balance stays. On the stop's edge (a jump of
     * the law) only the balance picks the force inside the jump. */
    const gs_real spring = delta > GS_R(0.0) ? spring_force(m, delta) : GS_R(0.0);
    gs_real f_s = (q.v_free - v) * cs->inv_c;
    if (cs->law_force_conditioned && !on_edge && delta > GS_R(0.0) && (f_s - spring) * v < GS_R(0.0)) {
        f_s = law_force(m, delta, v);
    }
    *force = side * f_s;
    *f_spring = side * spring;
    return side * v;
}

/* ---- The general contact (no_pull off): the damped laws may pull, so Phi
 * need not be monotone; a bracketed Newton on the generic law. */
static gs_real solve_bracketed(const gs_mesh_ *m, const gs_contact_step_ *cs, gs_real x,
                               gs_real u_free, gs_real *force, gs_real *f_spring)
{
    const gs_real h = cs->h;
    const gs_real c = cs->c;
    gs_real dfdu;
    const gs_real f0 = contact_force_d(m, x + h * u_free, u_free, h, &dfdu, f_spring);
    gs_real u = u_free;
    *force = f0; /* teeth apart: no force; f_spring is that of u_free */
    if (f0 > GS_R(0.0) || f0 < GS_R(0.0)) {
        /* Phi(u) = u - u_free + c*f(u) is increasing when f is non-decreasing in
         * u; its root lies between u_free and u_free - c*f0. */
        gs_real lo = f0 > GS_R(0.0) ? u_free - c * f0 : u_free;
        gs_real hi = f0 > GS_R(0.0) ? u_free : u_free - c * f0;
        const gs_real tolerance = NEWTON_TOLERANCE * (gs_abs(u_free) + c * gs_abs(f0));
        gs_real f = f0; /* f, dfdu and f_spring are those at u */
        for (int i = 0; i < NEWTON_ITERATIONS; ++i) {
            const gs_real phi = u - u_free + c * f;
            if (phi > GS_R(0.0)) {
                hi = u;
            } else if (phi < GS_R(0.0)) {
                lo = u;
            } else {
                break; /* exact root */
            }
            /* Newton inside the bracket; a step onto or past its ends (a kink
             * or jump of the law between u and the root) bisects instead, so
             * the bracket shrinks every iteration. */
            const gs_real slope = GS_R(1.0) + c * dfdu;
            gs_real next = slope > GS_R(0.0) ? u - phi / slope : lo;
            const int converged = gs_abs(next - u) <= tolerance && next >= lo && next <= hi;
            if (!converged && !(next > lo && next < hi)) {
                next = GS_R(0.5) * (lo + hi);
            }
            u = next;
            f = contact_force_d(m, x + h * u, u, h, &dfdu, f_spring);
            if (converged) {
                break;
            }
        }
        /* The force consistent with the impulse balance. At a root it equals
         * f(u); where the contact law jumps (damping at first contact) Phi has no
         * root and this picks the force inside the jump that stops the closing
         * motion there, instead of the full jump value. */
        *force = (u_free - u) / c;
        if ((*force - *f_spring) * u < GS_R(0.0) && gs_abs(x) <= m->half_gap) {
            /* First contact: the root sits on a jump of the law (damping
             * switched on at the stop's edge); the bracket holds it only to its
             * final width, leaving a sliver of spring compression that the
             * force does not match (and a negative damping power). The exact
             * root is the stop's edge. */
            const gs_real edge = x + h * u > GS_R(0.0) ? m->half_gap : -m->half_gap;
            const gs_real u_edge = (edge - x) / h;
            if (u_edge >= lo && u_edge <= hi) {
                u = u_edge;
                *force = (u_free - u) / c;
                *f_spring = GS_R(0.0);
            }
        }
    }
    return u;
}

gs_real gs_contact_solve(const gs_mesh_ *m, gs_block_state *st, const gs_contact_step_ *cs, gs_real x,
                         gs_real u_free, gs_real *force, gs_real *f_spring)
{
    if (m->lock_enabled && st->contact_locked) {
        const gs_real required = u_free * cs->inv_c;
        if (lock_holds(m, x, required)) {
            gs_real dfdu;
            (void)contact_force_d(m, x, GS_R(0.0), cs->h, &dfdu, f_spring);
            *force = required;
            return GS_R(0.0);
        }
        st->contact_locked = 0;
    }
    const gs_real u = m->no_pull ? solve_no_pull(m, cs, x, u_free, st->contact_force, force, f_spring)
                                 : solve_bracketed(m, cs, x, u_free, force, f_spring);
    /* Lock a slow impact: at or beyond the stop, closing or stopped (u has
     * the sign of the side, or is zero), never while the teeth separate. */
    const gs_real x_end = x + cs->h * u;
    if (m->lock_enabled && gs_abs(x_end) >= m->half_gap && gs_abs(u) < m->lock_speed &&
        x_end * u >= GS_R(0.0)) {
        st->contact_locked = 1;
    }
    return u;
}
