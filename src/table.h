/* table.h - clamped linear interpolation (internal). Breakpoints are
 * validated strictly increasing at init, so the step only searches. */
#ifndef GS_TABLE_H
#define GS_TABLE_H

#include "gearsim/types.h"

/* y(x) by linear interpolation over n breakpoints; the end values hold
 * outside [x[0], x[n-1]] (physics.md 2.4). Cost: O(n), n <= GS_TABLE_MAX. */
gs_real gs_interp1(const gs_real *x, const gs_real *y, int n, gs_real at);

/* The bracket of `at`: y(at) = y[lo] + w*(y[hi] - y[lo]), or y[lo] with
 * lo == hi where `at` is clamped to an end. Same arithmetic as gs_interp1, so
 * interpolating several columns with one bracket gives the same bits. */
void gs_interp_bracket(const gs_real *x, int n, gs_real at, int *lo, int *hi, gs_real *w);

#endif /* GS_TABLE_H */
