/* table.h - clamped linear interpolation (internal). Breakpoints are
 * validated strictly increasing at init, so the step only searches. Inline:
 * the step path calls these once or twice per (sub-)step; the bracket
 * always, as GCC at -Os kept it out of line (a call and its spills: 35
 * instructions of a 2-D table step on the Cortex-M4F). */
#ifndef GS_TABLE_H
#define GS_TABLE_H

#include "gearsim/types.h"
#include "gs_math.h"

/* The bracket of `at`: y(at) = y[lo] + w*(y[hi] - y[lo]), or y[lo] with
 * lo == hi (w = 0) where `at` is clamped to an end. Cost: O(n), n <=
 * GS_TABLE_MAX. */
static GS_ALWAYS_INLINE void gs_interp_bracket(const gs_real *x, int n, gs_real at, int *lo, int *hi, gs_real *w)
{
    *w = GS_R(0.0);
    if (!(at > x[0])) {
        *lo = *hi = 0;
        return;
    }
    if (!(at < x[n - 1])) {
        *lo = *hi = n - 1;
        return;
    }
    int i = 1; /* x[0] < at < x[n - 1]: the search stops by n - 1 */
    while (!(at < x[i])) {
        ++i;
    }
    *lo = i - 1;
    *hi = i;
    *w = (at - x[i - 1]) / (x[i] - x[i - 1]);
}

/* y(x) by linear interpolation over n breakpoints; the end values hold
 * outside [x[0], x[n-1]] (physics.md 2.4). Same arithmetic as the bracket,
 * so interpolating several columns with one bracket gives the same bits. */
static inline gs_real gs_interp1(const gs_real *x, const gs_real *y, int n, gs_real at)
{
    int lo = 0;
    int hi = 0;
    gs_real w = GS_R(0.0);
    gs_interp_bracket(x, n, at, &lo, &hi, &w);
    return y[lo] + w * (y[hi] - y[lo]);
}

#endif /* GS_TABLE_H */
