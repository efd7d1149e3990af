/* gs_math.h - small real-type helpers for the step path (internal).
 *
 * The step path calls no libm transcendental: gs_tanh below uses only
 * +, -, *, / so that, with -ffp-contract=off, a step gives the same bits on
 * every IEEE-754 target of the same precision (host and Cortex-M4F). */
#ifndef GS_MATH_H
#define GS_MATH_H

#include "gearsim/types.h"

/* |x|: a sign-bit clear (andpd, vabs.f32) with GCC and Clang, where the
 * ternary form compiles to a compare and branch; they differ only for -0. */
static inline gs_real gs_abs(gs_real x)
{
#if defined(__GNUC__)
#ifdef GS_SINGLE_PRECISION
    return __builtin_fabsf(x);
#else
    return __builtin_fabs(x);
#endif
#else
    return x < GS_R(0.0) ? -x : x;
#endif
}
static inline gs_real gs_min(gs_real a, gs_real b) { return a < b ? a : b; }
static inline gs_real gs_max(gs_real a, gs_real b) { return a > b ? a : b; }
static inline gs_real gs_clamp(gs_real x, gs_real lo, gs_real hi) { return gs_min(gs_max(x, lo), hi); }
static inline gs_real gs_sign(gs_real x) { return x > GS_R(0.0) ? GS_R(1.0) : (x < GS_R(0.0) ? GS_R(-1.0) : GS_R(0.0)); }
/* Finite test without libm: NaN fails both comparisons, infinities the bound. */
static inline int gs_is_finite(gs_real x)
{
#ifdef GS_SINGLE_PRECISION
    return x >= -GS_R(3.4028234e38) && x <= GS_R(3.4028234e38);
#else
    return x >= -GS_R(1.7976931348623157e308) && x <= GS_R(1.7976931348623157e308);
#endif
}

/* exp(-z) for z >= 0: exp(-z/1024) by a degree-7 Taylor polynomial, then
 * squared ten times. Relative error about 2e-13 for z <= 40 (double). */
static inline gs_real gs_exp_neg(gs_real z)
{
    const gs_real y = z * GS_R(0.0009765625);
    gs_real p = GS_R(1.0) - y * (GS_R(1.0) - y * (GS_R(0.5) - y * (GS_R(1.0) / GS_R(6.0)
                  - y * (GS_R(1.0) / GS_R(24.0) - y * (GS_R(1.0) / GS_R(120.0)
                  - y * (GS_R(1.0) / GS_R(720.0) - y * (GS_R(1.0) / GS_R(5040.0))))))));
    for (int i = 0; i < 10; ++i) {
        p = p * p;
    }
    return p;
}

/* tanh without libm: a [7/6] Pade approximant (the truncated Lambert
 * continued fraction) below 0.5, (1-e)/(1+e) with e = exp(-2|x|) up to 19,
 * where tanh rounds to 1 in double. Relative error < 1e-12. */
static inline gs_real gs_tanh(gs_real x)
{
    const gs_real a = gs_abs(x);
    gs_real r;
    if (a < GS_R(0.5)) {
        const gs_real a2 = a * a;
        r = a * (GS_R(135135.0) + a2 * (GS_R(17325.0) + a2 * (GS_R(378.0) + a2)))
            / (GS_R(135135.0) + a2 * (GS_R(62370.0) + a2 * (GS_R(3150.0) + a2 * GS_R(28.0))));
    } else if (a < GS_R(19.0)) {
        const gs_real e = gs_exp_neg(GS_R(2.0) * a);
        r = (GS_R(1.0) - e) / (GS_R(1.0) + e);
    } else {
        r = GS_R(1.0);
    }
    return x < GS_R(0.0) ? -r : r;
}

#endif /* GS_MATH_H */
