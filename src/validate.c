/* validate.c - parameter checks shared by every init. */
#include "validate.h"
#include "gs_math.h"

gs_status gs_fail(gs_error *err, gs_status status, const char *parameter)
{
    if (err != NULL) {
        err->status = status;
        err->parameter = parameter;
        err->message = gs_status_str(status);
    }
    return status;
}

void gs_error_clear(gs_error *err)
{
    (void)gs_fail(err, GS_OK, "");
}

gs_status gs_check_finite(gs_error *err, gs_real value, const char *parameter)
{
    return gs_is_finite(value) ? GS_OK : gs_fail(err, GS_E_NOT_FINITE, parameter);
}

gs_status gs_check_positive(gs_error *err, gs_real value, const char *parameter)
{
    if (!gs_is_finite(value)) {
        return gs_fail(err, GS_E_NOT_FINITE, parameter);
    }
    return value > GS_R(0.0) ? GS_OK : gs_fail(err, GS_E_NOT_POSITIVE, parameter);
}

gs_status gs_check_invertible(gs_error *err, gs_real value, const char *parameter)
{
    const gs_status s = gs_check_positive(err, value, parameter);
    if (s != GS_OK) {
        return s;
    }
    return gs_is_finite(GS_R(1.0) / value) ? GS_OK : gs_fail(err, GS_E_MAGNITUDE, parameter);
}

gs_status gs_check_nonnegative(gs_error *err, gs_real value, const char *parameter)
{
    if (!gs_is_finite(value)) {
        return gs_fail(err, GS_E_NOT_FINITE, parameter);
    }
    return value >= GS_R(0.0) ? GS_OK : gs_fail(err, GS_E_NEGATIVE, parameter);
}

gs_status gs_check_efficiency(gs_error *err, gs_real value, const char *parameter)
{
    if (!gs_is_finite(value)) {
        return gs_fail(err, GS_E_NOT_FINITE, parameter);
    }
    if (!(value > GS_R(0.0) && value <= GS_R(1.0))) {
        return gs_fail(err, GS_E_EFFICIENCY_RANGE, parameter);
    }
    /* the laws use 1/eta: a subnormal efficiency would overflow it */
    return gs_is_finite(GS_R(1.0) / value) ? GS_OK : gs_fail(err, GS_E_MAGNITUDE, parameter);
}

gs_status gs_check_breakpoints(gs_error *err, const gs_real *x, int n, int nonnegative, const char *parameter)
{
    if (n < 2 || n > GS_TABLE_MAX) {
        return gs_fail(err, GS_E_TABLE_LENGTH, parameter);
    }
    for (int i = 0; i < n; ++i) {
        if (!gs_is_finite(x[i])) {
            return gs_fail(err, GS_E_NOT_FINITE, parameter);
        }
        if (nonnegative && x[i] < GS_R(0.0)) {
            return gs_fail(err, GS_E_NEGATIVE, parameter);
        }
        if (i > 0 && !(x[i] > x[i - 1])) {
            return gs_fail(err, GS_E_TABLE_NOT_INCREASING, parameter);
        }
    }
    return GS_OK;
}

gs_status gs_check_temperature_efficiency(gs_error *err, const gs_real *temperature, const gs_real *eta, int n,
                                          gs_real power_threshold)
{
    gs_status s;
    if ((s = gs_check_breakpoints(err, temperature, n, 0, "temperature_vector")) != GS_OK ||
        (s = gs_check_efficiencies(err, eta, n, n, "efficiency_vector")) != GS_OK) {
        return s;
    }
    return gs_check_invertible(err, power_threshold, "power_threshold");
}

gs_status gs_check_efficiencies(gs_error *err, const gs_real *eta, int n, int expected_n, const char *parameter)
{
    if (n != expected_n) {
        return gs_fail(err, GS_E_TABLE_SIZE_MISMATCH, parameter);
    }
    for (int i = 0; i < n; ++i) {
        const gs_status s = gs_check_efficiency(err, eta[i], parameter);
        if (s != GS_OK) {
            return s;
        }
    }
    return GS_OK;
}
