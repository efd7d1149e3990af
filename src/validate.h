/* validate.h - parameter checks shared by every init (internal).
 * Each returns GS_OK or the failing status, and fills err (may be NULL). */
#ifndef GS_VALIDATE_H
#define GS_VALIDATE_H

#include "gearsim/types.h"

gs_status gs_fail(gs_error *err, gs_status status, const char *parameter);
void gs_error_clear(gs_error *err);
gs_status gs_check_finite(gs_error *err, gs_real value, const char *parameter);
gs_status gs_check_positive(gs_error *err, gs_real value, const char *parameter);
/* > 0 and 1/value finite: for parameters the model divides by. */
gs_status gs_check_invertible(gs_error *err, gs_real value, const char *parameter);
gs_status gs_check_nonnegative(gs_error *err, gs_real value, const char *parameter);
gs_status gs_check_efficiency(gs_error *err, gs_real value, const char *parameter);
/* Breakpoints: 2 <= n <= GS_TABLE_MAX, finite, strictly increasing, and
 * >= 0 when nonnegative is set. */
gs_status gs_check_breakpoints(gs_error *err, const gs_real *x, int n, int nonnegative, const char *parameter);
/* The temperature-dependent efficiency law: temperature_vector breakpoints,
 * efficiency_vector data, power_threshold (physics.md 2.4, 6). */
gs_status gs_check_temperature_efficiency(gs_error *err, const gs_real *temperature, const gs_real *eta, int n,
                                          gs_real power_threshold);
/* Efficiency data: count must equal expected_n, each entry in (0, 1]. */
gs_status gs_check_efficiencies(gs_error *err, const gs_real *eta, int n, int expected_n, const char *parameter);

#endif /* GS_VALIDATE_H */
