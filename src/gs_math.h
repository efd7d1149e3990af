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
/* Keeps a single copy of a larger helper where GCC and Clang would inline
 * every call (flash on a microcontroller). */
#if defined(__GNUC__)
#define GS_NOINLINE __attribute__((noinline))
#else
#define GS_NOINLINE
#endif
/* Inlines a body into each of a few callers that fix some of its arguments
 * to constants, so that each copy drops the branches those decide (the
 * backlash step's drive and friction variants). */
#if defined(__GNUC__)
#define GS_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define GS_ALWAYS_INLINE inline
#endif

static inline gs_real gs_min(gs_real a, gs_real b)
{
    return a < b ? a : b;
}
static inline gs_real gs_max(gs_real a, gs_real b)
{
    return a > b ? a : b;
}
static inline gs_real gs_clamp(gs_real x, gs_real lo, gs_real hi)
{
    return gs_min(gs_max(x, lo), hi);
}
static inline gs_real gs_sign(gs_real x)
{
    return x > GS_R(0.0) ? GS_R(1.0) : (x < GS_R(0.0) ? GS_R(-1.0) : GS_R(0.0));
}
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
    gs_real p =
        GS_R(1.0) -
        y * (GS_R(1.0) -
             y * (GS_R(0.5) - y * (GS_R(1.0) / GS_R(6.0) -
                                   y * (GS_R(1.0) / GS_R(24.0) -
                                        y * (GS_R(1.0) / GS_R(120.0) -
                                             y * (GS_R(1.0) / GS_R(720.0) - y * (GS_R(1.0) / GS_R(5040.0))))))));
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
        r = a * (GS_R(135135.0) + a2 * (GS_R(17325.0) + a2 * (GS_R(378.0) + a2))) /
            (GS_R(135135.0) + a2 * (GS_R(62370.0) + a2 * (GS_R(3150.0) + a2 * GS_R(28.0))));
    } else if (a < GS_R(19.0)) {
        const gs_real e = gs_exp_neg(GS_R(2.0) * a);
        r = (GS_R(1.0) - e) / (GS_R(1.0) + e);
    } else {
        r = GS_R(1.0);
    }
    return x < GS_R(0.0) ? -r : r;
}

/* x - 2*pi*k, k the nearest integer to x/(2*pi): the angle in [-pi, pi]
 * (Cody-Waite: 2*pi in two parts, so the reduction adds about one rounding).
 * k is rounded by adding and subtracting 1.5*2^(mantissa bits), exact while
 * |x/(2*pi)| < 2^(mantissa bits - 1); beyond that an angle's last bit is worth
 * more than a turn and carries no phase, and 0 is returned. */
static inline gs_real gs_reduce_angle(gs_real x)
{
#ifdef GS_SINGLE_PRECISION
    const gs_real two_pi_hi = GS_R(6.28318548202514648);
    const gs_real two_pi_lo = GS_R(-1.74845553e-07);
    const gs_real round_magic = GS_R(12582912.0); /* 1.5*2^23 */
    const gs_real exact_limit = GS_R(4194304.0);  /* 2^22 */
#else
    const gs_real two_pi_hi = GS_R(6.283185307179586);
    const gs_real two_pi_lo = GS_R(2.4492935982947064e-16);
    const gs_real round_magic = GS_R(6755399441055744.0); /* 1.5*2^52 */
    const gs_real exact_limit = GS_R(2251799813685248.0); /* 2^51 */
#endif
    const gs_real turns = x * GS_R(0.15915494309189535);
    if (!(gs_abs(turns) < exact_limit)) {
        return GS_R(0.0);
    }
    const gs_real k = (turns + round_magic) - round_magic;
    return (x - k * two_pi_hi) - k * two_pi_lo;
}

/* cos and sin of an angle already in [-pi, pi] (gs_reduce_angle), without
 * libm: a quarter turn q is taken out so that |t| <= pi/4, where Taylor
 * polynomials to t^16 and t^15 (float: t^10 and t^11) are exact to about one
 * rounding. */
static inline void gs_cos_sin(gs_real angle, gs_real *c, gs_real *s)
{
#ifdef GS_SINGLE_PRECISION
    const gs_real half_pi_hi = GS_R(1.57079637050628662);
    const gs_real half_pi_lo = GS_R(-4.37113883e-08);
#else
    const gs_real half_pi_hi = GS_R(1.5707963267948966);
    const gs_real half_pi_lo = GS_R(6.123233995736766e-17);
#endif
    const gs_real quarters = angle * GS_R(0.63661977236758134);
    const int q = (int)(quarters + (quarters >= GS_R(0.0) ? GS_R(0.5) : GS_R(-0.5)));
    const gs_real t = (angle - (gs_real)q * half_pi_hi) - (gs_real)q * half_pi_lo;
    const gs_real t2 = t * t;
#ifdef GS_SINGLE_PRECISION
    /* to t^10 and t^11: the next terms are below 1.2e-10 */
    const gs_real cos_t =
        GS_R(1.0) - t2 * (GS_R(0.5) - t2 * (GS_R(1.0) / GS_R(24.0) - t2 * (GS_R(1.0) / GS_R(720.0) -
                                                                           t2 * (GS_R(1.0) / GS_R(40320.0) -
                                                                                 t2 * (GS_R(1.0) / GS_R(3628800.0))))));
    const gs_real sin_t =
        t * (GS_R(1.0) - t2 * (GS_R(1.0) / GS_R(6.0) -
                               t2 * (GS_R(1.0) / GS_R(120.0) -
                                     t2 * (GS_R(1.0) / GS_R(5040.0) -
                                           t2 * (GS_R(1.0) / GS_R(362880.0) - t2 * (GS_R(1.0) / GS_R(39916800.0)))))));
#else
    const gs_real cos_t =
        GS_R(1.0) -
        t2 * (GS_R(0.5) - t2 * (GS_R(1.0) / GS_R(24.0) -
                                t2 * (GS_R(1.0) / GS_R(720.0) -
                                      t2 * (GS_R(1.0) / GS_R(40320.0) -
                                            t2 * (GS_R(1.0) / GS_R(3628800.0) -
                                                  t2 * (GS_R(1.0) / GS_R(479001600.0) -
                                                        t2 * (GS_R(1.0) / GS_R(87178291200.0) -
                                                              t2 * (GS_R(1.0) / GS_R(20922789888000.0)))))))));
    const gs_real sin_t =
        t *
        (GS_R(1.0) -
         t2 * (GS_R(1.0) / GS_R(6.0) -
               t2 * (GS_R(1.0) / GS_R(120.0) -
                     t2 * (GS_R(1.0) / GS_R(5040.0) - t2 * (GS_R(1.0) / GS_R(362880.0) -
                                                            t2 * (GS_R(1.0) / GS_R(39916800.0) -
                                                                  t2 * (GS_R(1.0) / GS_R(6227020800.0) -
                                                                        t2 * (GS_R(1.0) / GS_R(1307674368000.0)))))))));
#endif
    switch ((q + 4) % 4) { /* q in [-2, 2] for |angle| <= pi */
    case 0:
        *c = cos_t;
        *s = sin_t;
        break;
    case 1:
        *c = -sin_t;
        *s = cos_t;
        break;
    case 2:
        *c = -cos_t;
        *s = -sin_t;
        break;
    default:
        *c = sin_t;
        *s = -cos_t;
        break;
    }
}

#endif /* GS_MATH_H */
