/* table.c - clamped linear interpolation. */
#include "table.h"

gs_real gs_interp1(const gs_real *x, const gs_real *y, int n, gs_real at)
{
    if (!(at > x[0])) {
        return y[0];
    }
    if (!(at < x[n - 1])) {
        return y[n - 1];
    }
    int i = 1;
    while (i < n - 1 && !(at < x[i])) {
        ++i;
    }
    /* x[i-1] <= at < x[i] */
    const gs_real w = (at - x[i - 1]) / (x[i] - x[i - 1]);
    return y[i - 1] + w * (y[i] - y[i - 1]);
}
