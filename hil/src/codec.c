/*
 * Hand-written codec over the tables hil/dbc_tables.py generates from the
 * DBC: little-endian (Intel) integer signals in classic frames. Scaling and
 * rounding follow cantools (physical = raw * scale + offset; raw = round half
 * to even of (physical - offset) / scale), so the bytes equal cantools'
 * strict encoding of the same clamped value; tests/python/hil checks it
 * frame for frame.
 */
#include <math.h>
#include <string.h>

#include "gearsim/hil.h"

static uint64_t frame_bits(const uint8_t *data)
{
    uint64_t bits = 0;
    for (unsigned i = 0; i < GS_HIL_MAX_DATA; ++i) {
        bits |= (uint64_t)data[i] << (8u * i);
    }
    return bits;
}

static uint64_t length_mask(unsigned length)
{
    return length >= 64u ? ~(uint64_t)0 : (((uint64_t)1 << length) - 1u);
}

static int64_t raw_minimum(const gs_hil_signal *sig)
{
    if (!sig->is_signed) {
        return 0;
    }
    return -(int64_t)((uint64_t)1 << (sig->length - 1u));
}

/* The signal's raw value, sign-extended. */
static int64_t get_raw(const gs_hil_signal *sig, const uint8_t *data)
{
    uint64_t raw = (frame_bits(data) >> sig->start) & length_mask(sig->length);
    if (sig->is_signed && sig->length < 64u && (raw >> (sig->length - 1u)) != 0u) {
        raw |= ~length_mask(sig->length);
    }
    return (int64_t)raw;
}

double gs_hil_signal_value(const gs_hil_signal *sig, const uint8_t *data)
{
    return (double)get_raw(sig, data) * sig->scale + sig->offset;
}

void gs_hil_put_raw(const gs_hil_signal *sig, uint64_t raw, uint8_t *data)
{
    uint64_t mask = length_mask(sig->length) << sig->start;
    uint64_t bits = (frame_bits(data) & ~mask) | ((raw << sig->start) & mask);
    for (unsigned i = 0; i < GS_HIL_MAX_DATA; ++i) {
        data[i] = (uint8_t)(bits >> (8u * i));
    }
}

static double nearest_zero(const gs_hil_signal *sig)
{
    double x = sig->minimum > 0.0 ? sig->minimum : 0.0;
    return x < sig->maximum ? x : sig->maximum;
}

int gs_hil_put_value(const gs_hil_signal *sig, double value, uint8_t *data)
{
    int clamped = 1;
    double x = value;
    if (isnan(x)) {
        x = nearest_zero(sig);
    } else if (x < sig->minimum) { /* also -inf */
        x = sig->minimum;
    } else if (x > sig->maximum) {
        x = sig->maximum;
    } else {
        clamped = 0;
    }
    /* nearbyint rounds half to even in the default rounding mode, like Python's round() */
    double raw = nearbyint((x - sig->offset) / sig->scale);
    gs_hil_put_raw(sig, (uint64_t)(int64_t)raw, data);
    return clamped;
}

int gs_hil_role_command_index(gs_hil_role role)
{
    switch (role) {
    case GS_HIL_ROLE_CMD_BASE_SPEED:
        return GS_HIL_CMD_BASE_SPEED;
    case GS_HIL_ROLE_CMD_BASE_TORQUE:
        return GS_HIL_CMD_BASE_TORQUE;
    case GS_HIL_ROLE_CMD_LOAD:
        return GS_HIL_CMD_LOAD;
    case GS_HIL_ROLE_CMD_MODE:
        return GS_HIL_CMD_MODE;
    case GS_HIL_ROLE_NONE:
    case GS_HIL_ROLE_OUT:
    case GS_HIL_ROLE_OUT_FOLLOWER_ANGLE:
    case GS_HIL_ROLE_IN_BASE_SPEED:
    case GS_HIL_ROLE_IN_BASE_TORQUE:
    case GS_HIL_ROLE_IN_LOAD:
    case GS_HIL_ROLE_STATUS_COUNTER:
    case GS_HIL_ROLE_STATUS_FLAG:
    case GS_HIL_ROLE_STATUS_COUNT:
    default:
        return -1;
    }
}

gs_hil_reason gs_hil_decode_command(const gs_hil_frame_spec *spec, const uint8_t *data, unsigned length,
                                    gs_hil_command *cmd)
{
    uint8_t padded[GS_HIL_MAX_DATA] = {0};
    if (length != spec->length) {
        return GS_HIL_REJECTED_BAD_LENGTH;
    }
    memcpy(padded, data, length);
    memset(cmd, 0, sizeof *cmd);
    for (unsigned i = 0; i < spec->signal_count; ++i) {
        const gs_hil_signal *sig = &spec->signals[i];
        int64_t raw = get_raw(sig, padded);
        double v = (double)raw * sig->scale + sig->offset;
        int mode = -1;
        if (!isfinite(v)) {
            return GS_HIL_REJECTED_UNDECODABLE;
        }
        if (sig->role == GS_HIL_ROLE_CMD_MODE) {
            mode = sig->modes[raw - raw_minimum(sig)];
            if (sig->mode_choices && mode < 0) {
                return GS_HIL_REJECTED_UNDECODABLE;
            }
        }
        /* the tolerance absorbs the decimal rounding of DBC limits, as in the Python bridge */
        double tol = fabs(sig->scale) * 1e-6;
        if (v < sig->minimum - tol || v > sig->maximum + tol) {
            return GS_HIL_REJECTED_OUT_OF_RANGE;
        }
        int slot = gs_hil_role_command_index(sig->role);
        if (slot == GS_HIL_CMD_MODE) {
            if (mode < 0) {
                return GS_HIL_REJECTED_UNDECODABLE;
            }
            v = (double)mode;
        }
        if (slot >= 0) {
            cmd->value[slot] = v;
            cmd->present[slot] = 1;
        }
    }
    return GS_HIL_PENDING;
}
