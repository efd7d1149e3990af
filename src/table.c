/* table.c - clamped linear interpolation. */
#include "table.h"

void gs_interp_bracket(const gs_real *x, int n, gs_real at, int *lo, int *hi, gs_real *w)
{
    if (!(at > x[0])) {
        *lo = *hi = 0;
        return;
    }
    if (!(at < x[n - 1])) {
        *lo = *hi = n - 1;
        return;
    }
    int i = 1;
    while (i < n - 1 && !(at < x[i])) {
        ++i;
    }
    *lo = i - 1;
    *hi = i;
    *w = (at - x[i - 1]) / (x[i] - x[i - 1]);
}

gs_real gs_interp1(const gs_real *x, const gs_real *y, int n, gs_real at)
{
    int lo = 0;
    int hi = 0;
    gs_real w = GS_R(0.0);
    gs_interp_bracket(x, n, at, &lo, &hi, &w);
    return lo == hi ? y[lo] : y[lo] + w * (y[hi] - y[lo]);
}
