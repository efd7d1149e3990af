/*
 * The fault stage (gearsim/hil.h, docs/hil.md "Fault injection"): between the
 * model's values and the encoder, and on the frames the encoder made. A
 * fault never touches the rig's state or inputs: it changes what is sent.
 * Each one is counted (gs_hil_fault.count and the counter "faults") and,
 * while it acts, sets the state flag fault_active. Per period the work is
 * bounded by GS_HIL_MAX_FAULTS per encoded signal and frame; nothing is
 * allocated.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "internal.h"

/* splitmix64: the seed's sequence (never stuck at 0, unlike xorshift). */
static uint64_t next_random(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15u);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
    return z ^ (z >> 31);
}

/* A uniform number in (0, 1]. */
static double uniform(uint64_t *state)
{
    return ((double)(next_random(state) >> 11) + 1.0) * 0x1.0p-53;
}

/* A standard normal number (Box-Muller, one of the pair). */
static double normal(uint64_t *state)
{
    double u1 = uniform(state), u2 = uniform(state);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * 3.141592653589793 * u2);
}

static int is_signal_fault(gs_hil_fault_kind kind)
{
    return kind <= GS_HIL_FAULT_CLAMP;
}

static int is_value_role(gs_hil_role role)
{
    return role == GS_HIL_ROLE_OUT || role == GS_HIL_ROLE_OUT_FOLLOWER_ANGLE || role == GS_HIL_ROLE_IN_BASE_SPEED ||
           role == GS_HIL_ROLE_IN_BASE_TORQUE || role == GS_HIL_ROLE_IN_LOAD;
}

static int has_counter(const gs_hil_frame_spec *f)
{
    for (unsigned s = 0; s < f->signal_count; ++s) {
        if (f->signals[s].role == GS_HIL_ROLE_STATUS_COUNTER) {
            return 1;
        }
    }
    return 0;
}

static gs_hil_status refuse(gs_hil_error *err, const char *parameter, const char *what)
{
    if (err != NULL) {
        err->parameter = parameter;
        snprintf(err->message, sizeof err->message, "%s", what);
    }
    return GS_HIL_E_CONFIG;
}

/* The parts of a spec the frame table decides. */
static gs_hil_status check_target(const gs_hil_bridge *b, const gs_hil_fault_spec *f, gs_hil_error *err)
{
    const gs_hil_dbc *dbc = b->config.dbc;
    if (f->frame >= dbc->frame_count || b->kind[f->frame] != GS_HIL_FRAME_FEEDBACK) {
        return refuse(err, "frame", "a fault acts on a feedback frame of the DBC");
    }
    const gs_hil_frame_spec *spec = &dbc->frames[f->frame];
    if (is_signal_fault(f->kind)) {
        if (f->signal < 0 || (unsigned)f->signal >= spec->signal_count ||
            !is_value_role(spec->signals[f->signal].role)) {
            return refuse(err, "signal", "a signal fault acts on a feedback signal with an out. or in. role");
        }
    } else if (f->kind == GS_HIL_FAULT_COUNTER_STOP && !has_counter(spec)) {
        return refuse(err, "frame", "counter_stop acts on a frame with a status.counter signal");
    }
    return GS_HIL_OK;
}

/* The parts of a spec its kind decides. */
static gs_hil_status check_values(const gs_hil_fault_spec *f, gs_hil_error *err)
{
    switch (f->kind) {
    case GS_HIL_FAULT_OFFSET:
    case GS_HIL_FAULT_GAIN:
    case GS_HIL_FAULT_STUCK:
        return isfinite(f->value) ? GS_HIL_OK : refuse(err, "value", "must be a finite number");
    case GS_HIL_FAULT_NOISE:
        return isfinite(f->value) && f->value >= 0.0 ? GS_HIL_OK
                                                     : refuse(err, "value", "noise: a standard deviation >= 0");
    case GS_HIL_FAULT_QUANTISE:
        return isfinite(f->value) && f->value > 0.0 ? GS_HIL_OK : refuse(err, "value", "quantise: a step > 0");
    case GS_HIL_FAULT_CLAMP:
        return !isnan(f->value) && !isnan(f->value2) && f->value <= f->value2 ? GS_HIL_OK
                                                                              : refuse(err, "min", "clamp: min <= max");
    case GS_HIL_FAULT_DELAY:
        return f->periods >= 1u && f->periods < GS_HIL_DELAY_MAX
                   ? GS_HIL_OK
                   : refuse(err, "periods", "delay: 1 to 127 frame periods");
    case GS_HIL_FAULT_CORRUPT:
        return f->periods >= 1u && f->periods <= 64u ? GS_HIL_OK : refuse(err, "bits", "corrupt: 1 to 64 bits");
    case GS_HIL_FAULT_FREEZE:
    case GS_HIL_FAULT_DROPOUT:
    case GS_HIL_FAULT_DROP:
    case GS_HIL_FAULT_DUPLICATE:
    case GS_HIL_FAULT_COUNTER_STOP:
        return GS_HIL_OK;
    case GS_HIL_FAULTS:
    default:
        return refuse(err, "fault", "no such fault");
    }
}

gs_hil_status gs_hil_add_fault(gs_hil_bridge *b, const gs_hil_fault_spec *spec, gs_hil_error *err)
{
    if (b->fault_count == GS_HIL_MAX_FAULTS) {
        return refuse(err, "fault", "more faults than GS_HIL_MAX_FAULTS (16)");
    }
    if ((unsigned)spec->kind >= GS_HIL_FAULTS) {
        return refuse(err, "fault", "no such fault");
    }
    if (check_target(b, spec, err) != GS_HIL_OK || check_values(spec, err) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    gs_hil_fault *f = &b->faults[b->fault_count++];
    memset(f, 0, sizeof *f);
    f->spec = *spec;
    f->rng = spec->seed;
    f->ring_start = b->counters.count[GS_HIL_COUNT_PERIODS];
    f->stop_period = spec->end_period;
    return GS_HIL_OK;
}

static double delayed(const gs_hil_fault *f, uint64_t n)
{
    uint64_t d = f->spec.periods;
    uint64_t p = n >= f->ring_start + d ? n - d : f->ring_start; /* before the first record: the oldest */
    return f->ring[p % GS_HIL_DELAY_MAX];
}

void gs_hil_faults_update_(gs_hil_bridge *b, uint64_t n)
{
    int any = 0;
    for (unsigned i = 0; i < b->fault_count; ++i) {
        gs_hil_fault *f = &b->faults[i];
        const gs_hil_fault_spec *s = &f->spec;
        if (s->kind == GS_HIL_FAULT_DELAY) {
            const gs_hil_signal *sig = &b->config.dbc->frames[s->frame].signals[s->signal];
            f->ring[n % GS_HIL_DELAY_MAX] = gs_hil_model_value_(b, sig);
        }
        int in_window = n >= s->start_period && n < s->end_period;
        if (s->has_trigger && !f->triggered && in_window && gs_hil_condition_holds_(b, &s->trigger)) {
            f->triggered = 1;
            f->stop_period = s->duration_periods > 0u ? n + s->duration_periods : s->end_period;
        }
        f->active = in_window && (!s->has_trigger || (f->triggered && n < f->stop_period));
        if (!f->active) {
            f->has_counter = 0; /* a counter_stop holds the counter of its own span */
        }
        any |= f->active;
    }
    b->flag_state[GS_HIL_FLAG_FAULT_ACTIVE] = any;
}

static void counted(gs_hil_bridge *b, gs_hil_fault *f)
{
    f->count += 1u;
    b->counters.count[GS_HIL_COUNT_FAULTS] += 1u;
}

/* x half to even on a grid of step q. */
static double quantise(double x, double q)
{
    return nearbyint(x / q) * q;
}

double gs_hil_fault_value_(gs_hil_bridge *b, unsigned frame, unsigned signal, double x)
{
    uint64_t n = b->counters.count[GS_HIL_COUNT_PERIODS] - 1u; /* the period whose frames these are */
    for (unsigned i = 0; i < b->fault_count; ++i) {
        gs_hil_fault *f = &b->faults[i];
        const gs_hil_fault_spec *s = &f->spec;
        if (!is_signal_fault(s->kind) || s->frame != frame || s->signal != (int)signal) {
            continue;
        }
        if (!f->active) {
            f->last_value = x; /* what a freeze will hold */
            f->has_last = 1;
            continue;
        }
        switch (s->kind) {
        case GS_HIL_FAULT_OFFSET:
            x += s->value;
            break;
        case GS_HIL_FAULT_GAIN:
            x *= s->value;
            break;
        case GS_HIL_FAULT_NOISE:
            x += s->value * normal(&f->rng);
            break;
        case GS_HIL_FAULT_FREEZE:
            x = f->has_last ? f->last_value : x;
            break;
        case GS_HIL_FAULT_STUCK:
            x = s->value;
            break;
        case GS_HIL_FAULT_DELAY:
            x = delayed(f, n);
            break;
        case GS_HIL_FAULT_QUANTISE:
            x = quantise(x, s->value);
            break;
        case GS_HIL_FAULT_CLAMP:
            x = x < s->value ? s->value : x > s->value2 ? s->value2 : x;
            break;
        case GS_HIL_FAULT_DROPOUT:
            continue; /* acts on the frame: gs_hil_fault_frame_ */
        case GS_HIL_FAULT_DROP:
        case GS_HIL_FAULT_DUPLICATE:
        case GS_HIL_FAULT_CORRUPT:
        case GS_HIL_FAULT_COUNTER_STOP:
        case GS_HIL_FAULTS:
        default:
            continue;
        }
        counted(b, f);
    }
    return x;
}

/* periods distinct bits of the frame flipped: drawn from the seed, a bit
 * drawn twice moves on to the next one not yet flipped. */
static void flip_bits(gs_hil_fault *f, gs_hil_frame *frame)
{
    unsigned bits = 8u * (frame->length < GS_HIL_MAX_DATA ? frame->length : GS_HIL_MAX_DATA);
    uint64_t flipped = 0;
    for (unsigned k = 0; k < f->spec.periods && k < bits; ++k) {
        unsigned bit = (unsigned)(next_random(&f->rng) % bits);
        while ((flipped >> bit) & 1u) {
            bit = (bit + 1u) % bits;
        }
        flipped |= (uint64_t)1 << bit;
        frame->data[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    }
}

unsigned gs_hil_fault_frame_(gs_hil_bridge *b, unsigned frame_index, gs_hil_frame *frame)
{
    unsigned copies = 1;
    for (unsigned i = 0; i < b->fault_count; ++i) {
        gs_hil_fault *f = &b->faults[i];
        const gs_hil_fault_spec *s = &f->spec;
        if (!f->active || s->frame != frame_index) {
            continue;
        }
        switch (s->kind) {
        case GS_HIL_FAULT_DROPOUT:
        case GS_HIL_FAULT_DROP:
            copies = 0;
            break;
        case GS_HIL_FAULT_DUPLICATE:
            copies = copies > 0u ? 2u : 0u;
            break;
        case GS_HIL_FAULT_CORRUPT:
            flip_bits(f, frame);
            break;
        case GS_HIL_FAULT_OFFSET:
        case GS_HIL_FAULT_GAIN:
        case GS_HIL_FAULT_NOISE:
        case GS_HIL_FAULT_FREEZE:
        case GS_HIL_FAULT_STUCK:
        case GS_HIL_FAULT_DELAY:
        case GS_HIL_FAULT_QUANTISE:
        case GS_HIL_FAULT_CLAMP:
        case GS_HIL_FAULT_COUNTER_STOP:
        case GS_HIL_FAULTS:
        default:
            continue;
        }
        counted(b, f);
    }
    return copies;
}

int gs_hil_fault_counter_(gs_hil_bridge *b, unsigned frame_index, uint64_t next, uint64_t *value)
{
    for (unsigned i = 0; i < b->fault_count; ++i) {
        gs_hil_fault *f = &b->faults[i];
        if (!f->active || f->spec.kind != GS_HIL_FAULT_COUNTER_STOP || f->spec.frame != frame_index) {
            continue;
        }
        if (!f->has_counter) {
            f->counter = next > 0u ? next - 1u : 0u; /* the value the frame carried last */
            f->has_counter = 1;
        }
        *value = f->counter;
        counted(b, f);
        return 1;
    }
    return 0;
}
