/* rig_terms.c - the terms the rig's step paths share (rig_internal.h): the
 * driven side's Stribeck friction level, the regularised frictions and the
 * base shaft's torque ripple (physics.md 11), with the core's own cos/sin
 * (no libm). */
#include "rig_internal.h"
#include "gs_math.h"

/* cos and sin of any angle: one copy of the polynomials for init and step. */
GS_NOINLINE void gs_rig_cos_sin(gs_real angle, gs_real *c, gs_real *s)
{
    gs_cos_sin(gs_reduce_angle(angle), c, s);
}

/* Past (w_f/v_S)^2 = 40 the Stribeck hump is 4.2e-18 of its height and is
 * dropped. */
GS_NOINLINE gs_real gs_rig_stribeck_level(const rig_consts_ *r, gs_real w_f)
{
    const gs_real z = w_f * w_f * r->inv_stribeck_speed_sq;
    return z < GS_R(40.0) ? r->load_coulomb + r->stribeck_excess * gs_exp_neg(z) : r->load_coulomb;
}

gs_real gs_rig_creep_level(const rig_consts_ *r, gs_real w_f)
{
    return friction_level(r, w_f) * gs_abs(gs_tanh(GS_R(4.0) * w_f * r->inv_load_speed_threshold));
}

gs_mesh_friction_ gs_rig_regularised_law(const rig_consts_ *r, const gs_mesh_friction_ *law, gs_real t_f, gs_real w_f)
{
    const gs_mesh_ *m = &r->mesh;
    gs_mesh_friction_ out = *law;
    if (!law->lossy) {
        return out;
    }
    const int on_speed = m->friction == GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY ||
                         m->friction == GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    const gs_real x = on_speed ? w_f * m->inv_speed_threshold : t_f * w_f * m->inv_power_threshold;
    const gs_real strength = gs_abs(gs_tanh(GS_R(4.0) * x));
    out.c0 *= strength;
    out.k_fd *= strength;
    out.k_bd *= strength;
    gs_mesh_friction_bounds(&out);
    return out;
}

/* sum_i a_i*cos(i*x) - b_i*sin(i*x), i.e. sum_i A_i*cos(i*x + phi_i) (N*m).
 * The multiples come from the Chebyshev recurrence cos((i+1)x) = 2 cos x
 * cos(ix) - cos((i-1)x) (and the same for sin): one cos/sin pair per angle. */
static gs_real harmonics(const gs_real *a, const gs_real *b, gs_real angle)
{
    gs_real c1;
    gs_real s1;
    gs_rig_cos_sin(angle, &c1, &s1);
    gs_real c_prev = GS_R(1.0), s_prev = GS_R(0.0), c = c1, sn = s1;
    gs_real sum = GS_R(0.0);
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        sum += a[i] * c - b[i] * sn;
        const gs_real c_next = GS_R(2.0) * c1 * c - c_prev;
        const gs_real s_next = GS_R(2.0) * c1 * sn - s_prev;
        c_prev = c;
        s_prev = sn;
        c = c_next;
        sn = s_next;
    }
    return sum;
}

gs_real gs_rig_ripple_torque(const rig_consts_ *r, gs_real theta)
{
    /* Z*theta is formed from the reduced theta: Z is an integer, so the
     * phase survives where Z*theta itself would have lost it */
    const gs_real reduced = gs_reduce_angle(theta);
    gs_real tau = harmonics(r->ripple_rev_cos, r->ripple_rev_sin, reduced);
    if (r->mesh_teeth > 0) {
        tau += harmonics(r->ripple_mesh_cos, r->ripple_mesh_sin, (gs_real)r->mesh_teeth * reduced);
    }
    return tau;
}
