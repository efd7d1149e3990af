/* regularised_friction.c - the regularised friction of a freely moving driven
 * side (physics.md 11, rig load_friction_regularised).
 *
 * Why a damper: the set-valued Coulomb law holds a driven side at rest until
 * the applied torque exceeds F; the smooth law F*tanh(4 v/v_th) of the
 * speed-driven rigid rig lets it creep at v = (v_th/4)*atanh(T/F) instead.
 * Behind a compliant mesh or shaft the two differ where it matters most, at
 * each reversal: stuck, the spring winds up until it breaks the friction;
 * creeping, the friction acts as a damper F/(v_th/4) in series with the
 * spring. Written as c(v)*v with the secant c(v) = F*tanh(4 v/v_th)/v taken
 * at the start speed, the friction is a linear damper over the step: backward
 * Euler keeps it stable for any step and passive (it only opposes the end
 * speed), and in steady sliding it is the smooth law exactly. This is the
 * rigid mesh's form (the geared solve, where the damper joins the driven
 * side's implicit viscous term); with backlash the rig takes the law's value
 * at the start speed as a friction bound solved jointly with the contact
 * (src/rig_terms.c, gs_rig_creep_level). */
#include "regularised_friction.h"
#include "gs_math.h"

/* tanh(x)/x without a division by zero: the Taylor series 1 - x^2/3 +
 * 2 x^4/15 below 1e-3 (next term 17 x^6/315 < 6e-20), gs_tanh(x)/x above. */
static gs_real tanh_over_x(gs_real x)
{
    const gs_real a = gs_abs(x);
    if (a < GS_R(1e-3)) {
        const gs_real a2 = a * a;
        return GS_R(1.0) - a2 * (GS_R(1.0) / GS_R(3.0) - a2 * (GS_R(2.0) / GS_R(15.0)));
    }
    return gs_tanh(a) / a;
}

gs_real gs_creep_damping(gs_real level, gs_real w, gs_real inv_threshold)
{
    const gs_real k = GS_R(4.0) * inv_threshold;
    return level * k * tanh_over_x(k * w);
}
