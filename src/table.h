/* table.h - clamped linear interpolation (internal). Breakpoints are
 * validated strictly increasing at init, so the step only searches. */
#ifndef GS_TABLE_H
#define GS_TABLE_H

#include "gearsim/types.h"

/* y(x) by linear interpolation over n breakpoints; the end values hold
 * outside [x[0], x[n-1]] (physics.md 2.4). Cost: O(n), n <= GS_TABLE_MAX. */
gs_real gs_interp1(const gs_real *x, const gs_real *y, int n, gs_real at);

#endif /* GS_TABLE_H */
