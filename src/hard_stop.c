/* hard_stop.c - the backlash contact laws (physics.md 4.3-4.5) and the
 * constants of the backward-Euler contact solve, which itself lives in
 * contact.h (the spring's energy and the scaled constants, used every step,
 * are inline in mesh.h; the smooth law's rare bracketed solve is in
 * rig_backlash.c, beside its caller). */
#include "contact.h"

/* Force and its derivative along u when x = x0 + h*u (dfdu = h*df/dx + df/dv). */
static gs_real contact_force_d(const gs_mesh_ *m, gs_real x, gs_real u, gs_real h, gs_real *dfdu, gs_real *f_spring)
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

void gs_contact_prepare(const gs_mesh_ *m, gs_real h, gs_real inv_mass, gs_contact_step_ *cs)
{
    cs->h = h;
    cs->inv_h = GS_R(1.0) / h;
    cs->c = h * inv_mass;
    cs->inv_c = GS_R(1.0) / cs->c;
    cs->c_stiffness = cs->c * m->stiffness;
    cs->c_damping = cs->c * m->damping;
    cs->kappa_spring = cs->c * m->stiffness * h;
    cs->h_over_d = h * m->inv_transition;
    cs->d_over_h = m->inv_transition > GS_R(0.0) ? GS_R(1.0) / cs->h_over_d : GS_R(0.0);
    cs->kappa = cs->c * (m->stiffness * h + m->damping);
    cs->inv_kappa = GS_R(1.0) / cs->kappa;
    cs->inv_affine_damped = GS_R(1.0) / (GS_R(1.0) + cs->kappa);
    cs->inv_affine_undamped = GS_R(1.0) / (GS_R(1.0) + cs->c * m->stiffness * h);
    cs->transition = m->inv_transition > GS_R(0.0) ? GS_R(1.0) / m->inv_transition : GS_R(0.0);
    cs->law_force_conditioned = cs->kappa < GS_R(1.0);
}
