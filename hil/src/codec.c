/*
 * The codec over a frame table (gearsim/hil.h): integer and IEEE float
 * signals, little-endian (Intel) or big-endian (Motorola), in classic
 * frames. Scaling and rounding follow cantools (physical = raw * scale +
 * offset; raw = round half to even of (physical - offset) / scale), so the
 * bytes equal cantools' strict encoding of the same clamped value;
 * tests/python/hil checks it frame for frame.
 */
#include <math.h>
#include <string.h>

#include "gearsim/hil.h"

static uint64_t length_mask(unsigned length)
{
    return length >= 64u ? ~(uint64_t)0 : (((uint64_t)1 << length) - 1u);
}

/* The frame's bytes as one little-endian word (data[0] least significant). */
static uint64_t little_word(const uint8_t *data)
{
    uint64_t bits = 0;
    for (unsigned i = 0; i < GS_HIL_MAX_DATA; ++i) {
        bits |= (uint64_t)data[i] << (8u * i);
    }
    return bits;
}

/* The frame's bytes as one big-endian word (data[0] most significant). */
static uint64_t big_word(const uint8_t *data)
{
    uint64_t bits = 0;
    for (unsigned i = 0; i < GS_HIL_MAX_DATA; ++i) {
        bits = (bits << 8u) | data[i];
    }
    return bits;
}

/* Where the signal's least significant bit sits in its word: in the little
 * word at its start bit; in the big word below its most significant bit,
 * which the DBC numbers start (bit 7 of byte 0 is 7, bit 0 of byte 1 is 8). */
static unsigned word_shift(const gs_hil_signal *sig)
{
    if (!sig->is_big_endian) {
        return sig->start;
    }
    unsigned msb_from_top = (sig->start / 8u) * 8u + (7u - sig->start % 8u);
    return 64u - msb_from_top - sig->length;
}

static uint64_t get_bits(const gs_hil_signal *sig, const uint8_t *data)
{
    uint64_t word = sig->is_big_endian ? big_word(data) : little_word(data);
    return (word >> word_shift(sig)) & length_mask(sig->length);
}

void gs_hil_put_raw(const gs_hil_signal *sig, uint64_t raw, uint8_t *data)
{
    unsigned shift = word_shift(sig);
    uint64_t mask = length_mask(sig->length) << shift;
    uint64_t word = sig->is_big_endian ? big_word(data) : little_word(data);
    word = (word & ~mask) | ((raw << shift) & mask);
    for (unsigned i = 0; i < GS_HIL_MAX_DATA; ++i) {
        unsigned byte_shift = sig->is_big_endian ? 8u * (GS_HIL_MAX_DATA - 1u - i) : 8u * i;
        data[i] = (uint8_t)(word >> byte_shift);
    }
}

/* The raw value of an integer signal, sign-extended. */
static int64_t get_integer(const gs_hil_signal *sig, const uint8_t *data)
{
    uint64_t raw = get_bits(sig, data);
    if (sig->is_signed && sig->length < 64u && (raw >> (sig->length - 1u)) != 0u) {
        raw |= ~length_mask(sig->length);
    }
    return (int64_t)raw;
}

/* The raw value of a signal as a double (an IEEE float's value). */
static double get_raw(const gs_hil_signal *sig, const uint8_t *data)
{
    if (!sig->is_float) {
        return (double)get_integer(sig, data);
    }
    uint64_t bits = get_bits(sig, data);
    if (sig->length == 32u) {
        uint32_t word = (uint32_t)bits;
        float f;
        memcpy(&f, &word, sizeof f);
        return (double)f;
    }
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

double gs_hil_signal_value(const gs_hil_signal *sig, const uint8_t *data)
{
    return get_raw(sig, data) * sig->scale + sig->offset;
}

static double nearest_zero(double minimum, double maximum)
{
    double x = minimum > 0.0 ? minimum : 0.0;
    return x < maximum ? x : maximum;
}

/* x clamped into [minimum, maximum]; *clamped set when it moved (NaN and
 * infinities always count, as values the rig should not send). */
static double clamp(double x, double minimum, double maximum, int *clamped)
{
    *clamped = 1;
    if (isnan(x)) {
        return nearest_zero(minimum, maximum);
    }
    if (isinf(x)) {
        return x > 0.0 ? maximum : minimum;
    }
    if (x < minimum) {
        return minimum;
    }
    if (x > maximum) {
        return maximum;
    }
    *clamped = 0;
    return x;
}

static uint64_t float_bits(const gs_hil_signal *sig, double raw)
{
    if (sig->length == 32u) {
        float f = (float)raw;
        uint32_t word;
        memcpy(&word, &f, sizeof word);
        return word;
    }
    uint64_t bits;
    memcpy(&bits, &raw, sizeof bits);
    return bits;
}

int gs_hil_put_value(const gs_hil_signal *sig, double value, uint8_t *data)
{
    double minimum, maximum;
    int clamped;
    gs_hil_signal_limits(sig, &minimum, &maximum);
    double x = clamp(value, minimum, maximum, &clamped);
    double raw = (x - sig->offset) / sig->scale;
    if (sig->is_float) {
        gs_hil_put_raw(sig, float_bits(sig, raw), data);
        return clamped;
    }
    /* nearbyint rounds half to even in the default rounding mode, like Python's round() */
    gs_hil_put_raw(sig, (uint64_t)(int64_t)nearbyint(raw), data);
    return clamped;
}

/* The mode a cmd.mode value names: by its value table when it has one, else
 * the value is the gs_hil_mode itself. -1: no such mode. */
static int mode_of(const gs_hil_signal *sig, double v)
{
    int64_t key = (int64_t)v; /* truncated, as a value table is looked up */
    if (sig->choice_count == 0u) {
        return key >= 0 && key < (int64_t)GS_HIL_MODES ? (int)key : -1;
    }
    for (unsigned c = 0; c < sig->choice_count; ++c) {
        if (sig->choices[c].value == key) {
            return gs_hil_mode_parse(sig->choices[c].name);
        }
    }
    return -1;
}

/* One signal of a command frame: GS_HIL_PENDING with *value (a mode as
 * gs_hil_mode), or why the frame is rejected. */
static gs_hil_reason decode_signal(const gs_hil_signal *sig, const uint8_t *data, double *value)
{
    double v = gs_hil_signal_value(sig, data);
    if (!isfinite(v)) {
        return GS_HIL_REJECTED_UNDECODABLE;
    }
    int is_mode = sig->role == GS_HIL_ROLE_CMD_MODE;
    /* a value table is checked before the range */
    if (is_mode && sig->choice_count > 0u && mode_of(sig, v) < 0) {
        return GS_HIL_REJECTED_UNDECODABLE;
    }
    double minimum, maximum;
    gs_hil_signal_limits(sig, &minimum, &maximum);
    /* the tolerance absorbs the decimal rounding of DBC limits */
    double tol = fabs(sig->scale) * 1e-6;
    if (v < minimum - tol || v > maximum + tol) {
        return GS_HIL_REJECTED_OUT_OF_RANGE;
    }
    if (is_mode) {
        int mode = mode_of(sig, v);
        if (mode < 0) {
            return GS_HIL_REJECTED_UNDECODABLE;
        }
        v = (double)mode;
    }
    *value = v;
    return GS_HIL_PENDING;
}

gs_hil_reason gs_hil_decode_command(const gs_hil_frame_spec *spec, const uint8_t *data, unsigned length,
                                    gs_hil_command *cmd)
{
    uint8_t padded[GS_HIL_MAX_DATA] = {0};
    memset(cmd, 0, sizeof *cmd);
    cmd->signal = -1;
    if (length != spec->length || length > GS_HIL_MAX_DATA) {
        return GS_HIL_REJECTED_BAD_LENGTH;
    }
    memcpy(padded, data, length);
    for (unsigned i = 0; i < spec->signal_count; ++i) {
        const gs_hil_signal *sig = &spec->signals[i];
        double v = 0.0;
        gs_hil_reason r = decode_signal(sig, padded, &v);
        if (r != GS_HIL_PENDING) {
            cmd->signal = (int)i;
            return r;
        }
        int slot = gs_hil_role_command_index(sig->role);
        if (slot >= 0) {
            cmd->value[slot] = v;
            cmd->present[slot] = 1;
        }
    }
    return GS_HIL_PENDING;
}
