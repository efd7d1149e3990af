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
/* Newton also stops once its step is below this fraction of the bracket
 * scale |u_free| + c*|f0|: deterministic, and the worst case stays at
 * NEWTON_ITERATIONS evaluations. */
#ifdef GS_SINGLE_PRECISION
#define NEWTON_TOLERANCE GS_R(1e-6)
#else
#define NEWTON_TOLERANCE GS_R(1e-13)
#endif

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
            /* cubic step S = xi^2 (3 - 2 xi): zero force and slope at first contact */
            scale = xi_raw * xi_raw * (GS_R(3.0) - GS_R(2.0) * xi_raw);
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

gs_real gs_contact_solve(gs_mesh_ *m, gs_real x, gs_real u_free, gs_real h, gs_real inv_mass,
                         gs_real *force, gs_real *f_spring)
{
    const gs_real c = h * inv_mass;
    gs_real dfdu;
    if (m->lock_enabled && m->locked) {
        const gs_real required = u_free / c;
        if (lock_holds(m, x, required)) {
            (void)contact_force_d(m, x, GS_R(0.0), h, &dfdu, f_spring);
            *force = required;
            return GS_R(0.0);
        }
        m->locked = 0;
    }
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
    if (m->lock_enabled && gs_abs(x + h * u) >= m->half_gap && gs_abs(u) < m->lock_speed) {
        m->locked = 1;
    }
    return u;
}
