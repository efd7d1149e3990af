/*
 * The bridge's logic (gearsim/hil.h), period by period: the one
 * implementation of docs/hil.md's "Time model", "Commands, modes, safe
 * state", "Frame classes and counters" and "Status", which the C runner and
 * the Python bridge both run. No I/O, no heap: everything lives in the
 * gs_hil_bridge.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "internal.h"

/* The counters whose growth sets the latched flags, in flag order from
 * GS_HIL_FLAG_CMD_REJECTED on. */
static const gs_hil_count latched_counts[GS_HIL_LATCHED_FLAGS] = {
    GS_HIL_COUNT_RX_REJECTED, GS_HIL_COUNT_RX_LATE,       GS_HIL_COUNT_SATURATIONS,   GS_HIL_COUNT_OVERRUNS,
    GS_HIL_COUNT_TX_ERRORS,   GS_HIL_COUNT_PARAM_CHANGES, GS_HIL_COUNT_PARAM_REFUSED, GS_HIL_COUNT_LOG_DROPPED,
};

static gs_hil_count reason_class(gs_hil_reason reason)
{
    if (reason >= GS_HIL_IGNORED_FEEDBACK_ID) {
        return GS_HIL_COUNT_RX_IGNORED;
    }
    if (reason >= GS_HIL_LATE_SUPERSEDED) {
        return GS_HIL_COUNT_RX_LATE;
    }
    return GS_HIL_COUNT_RX_REJECTED;
}

static gs_hil_reason count_reason(gs_hil_bridge *b, gs_hil_reason reason)
{
    b->counters.count[reason_class(reason)] += 1u;
    b->counters.reasons[reason] += 1u;
    return reason;
}

static gs_hil_status fail(gs_hil_error *err, const char *parameter, const char *message)
{
    if (err != NULL) {
        err->parameter = parameter;
        snprintf(err->message, sizeof err->message, "%s", message);
    }
    return GS_HIL_E_CONFIG;
}

static gs_hil_status check_cycles(gs_hil_bridge *b, gs_hil_error *err)
{
    const gs_hil_dbc *dbc = b->config.dbc;
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        const gs_hil_frame_spec *f = &dbc->frames[i];
        b->cycle_periods[i] = 0;
        if (b->kind[i] != GS_HIL_FRAME_FEEDBACK) {
            continue;
        }
        double n = ((double)f->cycle_ms / 1000.0) / b->period_s;
        double whole = nearbyint(n);
        if (fabs(n - whole) > 1e-6 * (n > 1.0 ? n : 1.0) || whole < 1.0 || whole > 4294967295.0) {
            char text[200];
            snprintf(text, sizeof text,
                     "feedback frame %s: cycle time %u ms is not a whole number of frame periods (%g ms)", f->name,
                     f->cycle_ms, b->period_s * 1e3);
            return fail(err, "period", text);
        }
        b->cycle_periods[i] = (unsigned)whole;
    }
    return GS_HIL_OK;
}

static void index_frames(gs_hil_bridge *b)
{
    const gs_hil_dbc *dbc = b->config.dbc;
    b->command_count = 0;
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        const gs_hil_frame_spec *f = &dbc->frames[i];
        b->kind[i] = gs_hil_frame_kind_of(f);
        b->command_index[i] = 0;
        if (b->kind[i] != GS_HIL_FRAME_COMMAND) {
            continue;
        }
        b->command_index[i] = b->command_count++; /* at most GS_HIL_MAX_COMMAND_FRAMES: gs_hil_dbc_check */
        for (unsigned s = 0; s < f->signal_count; ++s) {
            int slot = gs_hil_role_command_index(f->signals[s].role);
            if (slot >= 0) {
                b->has_role[slot] = 1;
            }
        }
    }
}

gs_hil_status gs_hil_bridge_init(gs_hil_bridge *b, const gs_hil_config *config, gs_rig_block block,
                                 const gs_rig_consts *consts, gs_rig_state *state, gs_hil_error *err)
{
    if (b == NULL || config == NULL || config->dbc == NULL || consts == NULL || state == NULL) {
        return fail(err, "bridge", "a required pointer is NULL");
    }
    memset(b, 0, sizeof *b);
    if (gs_hil_dbc_check(config->dbc, err) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    b->config = *config;
    b->consts = consts;
    b->state = state;
    if (config->dbc->block != block) {
        return fail(err, "dbc", "the DBC is for the other rig block");
    }
    if (config->substeps < 1u) {
        return fail(err, "substeps", "substeps must be an integer >= 1");
    }
    if (!(isfinite(config->timeout_s) && config->timeout_s > 0.0)) {
        return fail(err, "timeout", "timeout must be a time > 0 s");
    }
    b->period_s = (double)config->dt_s * (double)config->substeps;
    if (!(isfinite(b->period_s) && b->period_s > 0.0)) {
        return fail(err, "period", "period must be a time > 0 s");
    }
    double timeout_periods = nearbyint(config->timeout_s / b->period_s);
    if (!(timeout_periods < 1e15)) {
        return fail(err, "timeout", "timeout is too many periods");
    }
    b->timeout_periods = timeout_periods < 1.0 ? 1u : (uint64_t)timeout_periods;
    index_frames(b);
    if (check_cycles(b, err) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    int driving = config->base_drive == GS_BASE_SPEED_DRIVEN ? GS_HIL_CMD_BASE_SPEED : GS_HIL_CMD_BASE_TORQUE;
    if (!b->has_role[driving]) {
        return fail(err, "dbc",
                    driving == GS_HIL_CMD_BASE_SPEED
                        ? "the DBC has no cmd.base_speed signal, which a speed-driven rig needs"
                        : "the DBC has no cmd.base_torque signal, which a torque-driven rig needs");
    }
    b->feedback_count = gs_hil_feedback_order(config->dbc, b->feedback_order);
    b->timed_out = 1;
    b->dirty = 1;
    b->flag_state[GS_HIL_FLAG_CMD_TIMEOUT] = 1;
    b->flag_state[GS_HIL_FLAG_SAFE_STATE] = 1;
    b->commanded.ambient_temperature = config->ambient_temperature_K;
    b->commanded.measured_temperature = config->ambient_temperature_K;
    b->input = b->commanded;
    gs_hil_init_tuning_(b, block);
    return GS_HIL_OK;
}

unsigned gs_hil_pending(const gs_hil_bridge *b)
{
    unsigned n = 0;
    for (unsigned i = 0; i < b->command_count; ++i) {
        n += b->commands[i].has_pending ? 1u : 0u;
    }
    return n + b->request_count;
}

static const gs_hil_frame_spec *find_frame(const gs_hil_dbc *dbc, const gs_hil_frame *frame, unsigned *index)
{
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        if (dbc->frames[i].id == frame->id && (dbc->frames[i].is_extended != 0) == (frame->is_extended != 0)) {
            *index = i;
            return &dbc->frames[i];
        }
    }
    return NULL;
}

/* The value of the signal with role in a decoded frame's data (0 without). */
static double role_value(const gs_hil_frame_spec *spec, const uint8_t *data, gs_hil_role role)
{
    for (unsigned s = 0; s < spec->signal_count; ++s) {
        if (spec->signals[s].role == role) {
            return gs_hil_signal_value(&spec->signals[s], data);
        }
    }
    return 0.0;
}

/* A parameter frame: decoded and range-checked as a command is, then queued
 * (or refused: counted and acknowledged). */
static gs_hil_reason handle_param(gs_hil_bridge *b, const gs_hil_frame_spec *spec, const gs_hil_frame *frame)
{
    gs_hil_command unused;
    gs_hil_reason decoded = gs_hil_decode_command(spec, frame->data, frame->length, &unused);
    if (decoded != GS_HIL_PENDING) {
        return count_reason(b, decoded);
    }
    uint8_t data[GS_HIL_MAX_DATA] = {0};
    memcpy(data, frame->data, frame->length);
    double id = role_value(spec, data, GS_HIL_ROLE_PARAM_ID);
    double element = role_value(spec, data, GS_HIL_ROLE_PARAM_ELEMENT);
    double value = role_value(spec, data, GS_HIL_ROLE_PARAM_VALUE);
    /* the index signals are unsigned integers (gs_hil_dbc_check) */
    gs_hil_param_result r = gs_hil_request_param(b, (unsigned)id, (unsigned)element, value);
    if (r == GS_HIL_PARAM_APPLIED) {
        return GS_HIL_PENDING;
    }
    return r == GS_HIL_PARAM_BUSY ? GS_HIL_REJECTED_PARAM_BUSY : GS_HIL_REJECTED_BAD_PARAM; /* counted */
}

gs_hil_reason gs_hil_handle(gs_hil_bridge *b, const gs_hil_frame *frame)
{
    unsigned index = 0;
    gs_hil_command cmd;
    b->counters.count[GS_HIL_COUNT_RX_TOTAL] += 1u;
    if (frame->is_error) {
        return count_reason(b, GS_HIL_IGNORED_ERROR_FRAME);
    }
    if (frame->is_remote) {
        return count_reason(b, GS_HIL_IGNORED_REMOTE_FRAME);
    }
    const gs_hil_frame_spec *spec = find_frame(b->config.dbc, frame, &index);
    if (spec == NULL) {
        return count_reason(b, GS_HIL_REJECTED_UNKNOWN_ID);
    }
    if (b->kind[index] == GS_HIL_FRAME_FEEDBACK || b->kind[index] == GS_HIL_FRAME_ACK) {
        return count_reason(b, GS_HIL_IGNORED_FEEDBACK_ID);
    }
    if (b->kind[index] == GS_HIL_FRAME_PARAM) {
        return handle_param(b, spec, frame);
    }
    if (b->kind[index] == GS_HIL_FRAME_OTHER) {
        return count_reason(b, GS_HIL_IGNORED_OTHER_DBC_FRAME);
    }
    gs_hil_reason decoded = gs_hil_decode_command(spec, frame->data, frame->length, &cmd);
    if (decoded != GS_HIL_PENDING) {
        return count_reason(b, decoded);
    }
    if (cmd.present[GS_HIL_CMD_MODE]) {
        int mode = (int)cmd.value[GS_HIL_CMD_MODE];
        int drive = b->config.base_drive == GS_BASE_SPEED_DRIVEN ? GS_HIL_MODE_SPEED : GS_HIL_MODE_TORQUE;
        if (mode != GS_HIL_MODE_DISABLED && mode != drive) {
            return count_reason(b, GS_HIL_REJECTED_MODE_MISMATCH);
        }
    }
    gs_hil_command_slot *slot = &b->commands[b->command_index[index]];
    if ((slot->has_held && frame->timestamp_s < slot->held_ts) ||
        (slot->has_pending && frame->timestamp_s < slot->pending_ts)) {
        return count_reason(b, GS_HIL_LATE_OUT_OF_ORDER);
    }
    if (slot->has_pending) {
        count_reason(b, GS_HIL_LATE_SUPERSEDED);
    }
    slot->pending = cmd;
    slot->pending_ts = frame->timestamp_s;
    slot->has_pending = 1;
    return GS_HIL_PENDING;
}

static void apply_pending(gs_hil_bridge *b)
{
    uint64_t now = b->counters.count[GS_HIL_COUNT_PERIODS];
    int applied = 0;
    for (unsigned i = 0; i < b->command_count; ++i) {
        gs_hil_command_slot *slot = &b->commands[i];
        if (!slot->has_pending) {
            continue;
        }
        slot->held = slot->pending;
        slot->held_ts = slot->pending_ts;
        slot->has_held = 1;
        slot->has_pending = 0;
        slot->last_rx_period = now;
        slot->has_last_rx = 1;
        b->counters.count[GS_HIL_COUNT_RX_USED] += 1u;
        applied = 1;
    }
    if (applied) {
        b->ever_commanded = 1;
        b->dirty = 1;
    }
}

/* The timeout, the safe state and the inputs for the coming periods. */
static void update_state(gs_hil_bridge *b)
{
    uint64_t now = b->counters.count[GS_HIL_COUNT_PERIODS];
    int stale = 0;
    uint64_t oldest = UINT64_MAX;
    gs_hil_command held;
    memset(&held, 0, sizeof held);
    for (unsigned i = 0; i < b->command_count; ++i) {
        const gs_hil_command_slot *slot = &b->commands[i];
        if (!slot->has_last_rx || now - slot->last_rx_period > b->timeout_periods) {
            stale = 1;
        }
        if (slot->has_last_rx && slot->last_rx_period < oldest) {
            oldest = slot->last_rx_period;
        }
        for (int r = 0; r < GS_HIL_CMD_ROLES && slot->has_held; ++r) {
            if (slot->held.present[r]) {
                held.value[r] = slot->held.value[r];
                held.present[r] = 1;
            }
        }
    }
    gs_hil_counters *c = &b->counters;
    if (stale && !b->timed_out && b->ever_commanded) {
        c->count[GS_HIL_COUNT_TIMEOUTS] += 1u;
    } else if (!stale && b->timed_out && c->count[GS_HIL_COUNT_TIMEOUTS] > c->count[GS_HIL_COUNT_RECOVERIES]) {
        c->count[GS_HIL_COUNT_RECOVERIES] += 1u;
    }
    b->timed_out = stale;
    b->dirty = 0;
    if (!stale) {
        b->stale_at = oldest + b->timeout_periods + 1u; /* first period at which a command is stale */
    }
    int disabled = !stale && held.present[GS_HIL_CMD_MODE] && (int)held.value[GS_HIL_CMD_MODE] == GS_HIL_MODE_DISABLED;
    int safe = stale || disabled;
    b->flag_state[GS_HIL_FLAG_CMD_TIMEOUT] = stale;
    b->flag_state[GS_HIL_FLAG_SAFE_STATE] = safe;
    b->flag_state[GS_HIL_FLAG_DRIVE_DISABLED] = disabled;
    gs_rig_input *in = &b->commanded;
    in->base_speed = 0;
    in->base_torque = 0;
    in->load = 0;
    if (safe) {
        return;
    }
    if (held.present[GS_HIL_CMD_LOAD]) {
        in->load = (gs_real)held.value[GS_HIL_CMD_LOAD];
    }
    if (b->config.base_drive == GS_BASE_SPEED_DRIVEN) {
        in->base_speed = (gs_real)held.value[GS_HIL_CMD_BASE_SPEED];
    } else {
        in->base_torque = (gs_real)held.value[GS_HIL_CMD_BASE_TORQUE];
    }
}

static const double two_pi = 2.0 * 3.141592653589793;

/* Python's math.fmod(x, 2*pi) % (2*pi): in [0, 2*pi), +0.0 for a zero remainder. */
static double angle_modulo(double x)
{
    double r = fmod(x, two_pi);
    double m = fmod(r, two_pi);
    if (m < 0.0) {
        m += two_pi;
    } else if (!(m > 0.0)) {
        m = 0.0; /* -0.0 becomes +0.0, as in Python */
    }
    return m;
}

/* The model's value of a feedback signal this period: an output or an input
 * the rig applied. The fault stage (fault.c) acts between this and the
 * encoder. */
double gs_hil_model_value_(const gs_hil_bridge *b, const gs_hil_signal *sig)
{
    const gs_real *out = (const gs_real *)(const void *)&b->output;
    switch (sig->role) {
    case GS_HIL_ROLE_OUT:
        return (double)out[sig->aux];
    case GS_HIL_ROLE_OUT_FOLLOWER_ANGLE:
        return angle_modulo((double)b->output.follower_position);
    case GS_HIL_ROLE_IN_BASE_SPEED:
        return (double)b->input.base_speed;
    case GS_HIL_ROLE_IN_BASE_TORQUE:
        return (double)b->input.base_torque;
    case GS_HIL_ROLE_IN_LOAD:
        return (double)b->input.load;
    case GS_HIL_ROLE_NONE: /* a signal without a role: the value in its range nearest 0 */
        return 0.0;
    case GS_HIL_ROLE_CMD_BASE_SPEED:
    case GS_HIL_ROLE_CMD_BASE_TORQUE:
    case GS_HIL_ROLE_CMD_LOAD:
    case GS_HIL_ROLE_CMD_MODE:
    case GS_HIL_ROLE_STATUS_COUNTER:
    case GS_HIL_ROLE_STATUS_FLAG:
    case GS_HIL_ROLE_STATUS_COUNT:
    case GS_HIL_ROLE_PARAM_ID:
    case GS_HIL_ROLE_PARAM_ELEMENT:
    case GS_HIL_ROLE_PARAM_VALUE:
    case GS_HIL_ROLE_ACK_ID:
    case GS_HIL_ROLE_ACK_ELEMENT:
    case GS_HIL_ROLE_ACK_VALUE:
    case GS_HIL_ROLE_ACK_RESULT:
    case GS_HIL_ROLES:
    default:
        return nan("");
    }
}

/* The value a command signal has in the command applied this period (NaN
 * before any). */
static double command_value(const gs_hil_bridge *b, unsigned frame, unsigned signal)
{
    const gs_hil_signal *sig = &b->config.dbc->frames[frame].signals[signal];
    int slot = gs_hil_role_command_index(sig->role);
    const gs_hil_command_slot *c = &b->commands[b->command_index[frame]];
    if (slot < 0 || !c->has_held || !c->held.present[slot]) {
        return nan("");
    }
    return c->held.value[slot];
}

double gs_hil_source_value_(const gs_hil_bridge *b, const gs_hil_condition *c)
{
    switch (c->source) {
    case GS_HIL_SOURCE_FEEDBACK:
        return gs_hil_model_value_(b, &b->config.dbc->frames[c->frame].signals[c->signal]);
    case GS_HIL_SOURCE_COMMAND:
        return command_value(b, c->frame, c->signal);
    case GS_HIL_SOURCE_FLAG:
    default:
        return b->flag_state[c->flag] ? 1.0 : 0.0;
    }
}

int gs_hil_condition_holds_(const gs_hil_bridge *b, const gs_hil_condition *c)
{
    double x = gs_hil_source_value_(b, c), v = c->value;
    switch (c->op) {
    case GS_HIL_OP_LT:
        return x < v;
    case GS_HIL_OP_LE:
        return x <= v;
    case GS_HIL_OP_GT:
        return x > v;
    case GS_HIL_OP_GE:
        return x >= v;
    case GS_HIL_OP_EQ:
        return x <= v && x >= v;
    case GS_HIL_OP_NE:
        return x < v || x > v;
    case GS_HIL_OPS:
    default:
        return 0;
    }
}

/* Flags latched since the previous frame of this ID (updated once per frame). */
static void latch_flags(gs_hil_bridge *b, unsigned frame_index, int latched[GS_HIL_LATCHED_FLAGS])
{
    for (unsigned k = 0; k < GS_HIL_LATCHED_FLAGS; ++k) {
        uint64_t now = b->counters.count[latched_counts[k]];
        latched[k] = now > b->latched_at[frame_index][k];
        b->latched_at[frame_index][k] = now;
    }
}

/* The raw value of a status signal (counter, flag, count). */
static uint64_t status_raw(gs_hil_bridge *b, unsigned frame_index, const gs_hil_signal *sig,
                           int latched[GS_HIL_LATCHED_FLAGS], int *have_latched)
{
    if (sig->role == GS_HIL_ROLE_STATUS_COUNTER) {
        uint64_t held;
        if (b->fault_count > 0u && gs_hil_fault_counter_(b, frame_index, b->status_seq[frame_index], &held)) {
            return held; /* counter_stop: the counter does not move */
        }
        return b->status_seq[frame_index]++;
    }
    if (sig->role == GS_HIL_ROLE_STATUS_COUNT) {
        return b->counters.count[sig->aux];
    }
    if (sig->aux < GS_HIL_STATE_FLAGS) {
        return (uint64_t)(b->flag_state[sig->aux] != 0);
    }
    if (!*have_latched) {
        latch_flags(b, frame_index, latched);
        *have_latched = 1;
    }
    return (uint64_t)(latched[sig->aux - GS_HIL_STATE_FLAGS] != 0);
}

static int is_status_signal(const gs_hil_signal *sig)
{
    return sig->role == GS_HIL_ROLE_STATUS_COUNTER || sig->role == GS_HIL_ROLE_STATUS_FLAG ||
           sig->role == GS_HIL_ROLE_STATUS_COUNT;
}

/* Encode one feedback frame into *frame; clamped values count as saturations. */
static void encode_frame(gs_hil_bridge *b, unsigned frame_index, gs_hil_frame *frame)
{
    const gs_hil_frame_spec *spec = &b->config.dbc->frames[frame_index];
    int latched[GS_HIL_LATCHED_FLAGS] = {0};
    int have_latched = 0;
    for (unsigned s = 0; s < spec->signal_count; ++s) {
        const gs_hil_signal *sig = &spec->signals[s];
        if (is_status_signal(sig)) {
            gs_hil_put_raw(sig, status_raw(b, frame_index, sig, latched, &have_latched), frame->data);
            continue;
        }
        double x = gs_hil_model_value_(b, sig);
        if (b->fault_count > 0u) {
            x = gs_hil_fault_value_(b, frame_index, s, x);
        }
        if (gs_hil_put_value(sig, x, frame->data) && sig->role != GS_HIL_ROLE_NONE) {
            b->counters.count[GS_HIL_COUNT_SATURATIONS] += 1u;
            frame->saturated |= (uint64_t)1 << s;
        }
    }
}

static void send(gs_hil_bridge *b, const gs_hil_frame *frame)
{
    if (b->config.send != NULL && b->config.send(b->config.send_context, frame) != 0) {
        b->counters.count[GS_HIL_COUNT_TX_ERRORS] += 1u;
    } else {
        b->counters.count[GS_HIL_COUNT_TX_FRAMES] += 1u;
    }
}

static void start_frame(const gs_hil_bridge *b, const gs_hil_frame_spec *spec, gs_hil_frame *frame)
{
    memset(frame, 0, sizeof *frame);
    frame->timestamp_s = b->config.stamp_origin_s + (double)b->counters.count[GS_HIL_COUNT_PERIODS] * b->period_s;
    frame->id = spec->id;
    frame->is_extended = spec->is_extended;
    frame->length = spec->length;
}

/* The acknowledgements of the parameter requests settled this period. */
static void emit_acks(gs_hil_bridge *b)
{
    const gs_hil_dbc *dbc = b->config.dbc;
    for (unsigned i = 0; i < dbc->frame_count && b->ack_count > 0u; ++i) {
        if (b->kind[i] != GS_HIL_FRAME_ACK) {
            continue;
        }
        const gs_hil_frame_spec *spec = &dbc->frames[i];
        for (unsigned k = 0; k < b->ack_count; ++k) {
            const gs_hil_param_request *r = &b->acks[k];
            gs_hil_frame frame;
            start_frame(b, spec, &frame);
            for (unsigned s = 0; s < spec->signal_count; ++s) {
                const gs_hil_signal *sig = &spec->signals[s];
                double x = sig->role == GS_HIL_ROLE_ACK_ID        ? (double)r->index
                           : sig->role == GS_HIL_ROLE_ACK_ELEMENT ? (double)r->element
                           : sig->role == GS_HIL_ROLE_ACK_VALUE   ? r->value
                           : sig->role == GS_HIL_ROLE_ACK_RESULT  ? (double)r->result
                                                                  : 0.0;
                (void)gs_hil_put_value(sig, x, frame.data); /* clamped, never wrapped; not a feedback saturation */
            }
            send(b, &frame);
        }
    }
    b->ack_count = 0;
}

static void emit(gs_hil_bridge *b)
{
    uint64_t n = b->counters.count[GS_HIL_COUNT_PERIODS];
    gs_hil_frame frame;
    for (unsigned k = 0; k < b->feedback_count; ++k) {
        unsigned i = b->feedback_order[k];
        if (n % b->cycle_periods[i] != 0u) {
            continue;
        }
        start_frame(b, &b->config.dbc->frames[i], &frame);
        encode_frame(b, i, &frame);
        unsigned copies = b->fault_count > 0u ? gs_hil_fault_frame_(b, i, &frame) : 1u;
        for (unsigned c = 0; c < copies; ++c) {
            send(b, &frame);
        }
    }
    emit_acks(b);
}

void gs_hil_advance(gs_hil_bridge *b, uint64_t periods)
{
    if (b->closed) {
        return;
    }
    for (uint64_t p = 0; p < periods; ++p) {
        apply_pending(b);
        uint64_t now = b->counters.count[GS_HIL_COUNT_PERIODS];
        gs_hil_swap_params_(b); /* the parameter requests due now take effect */
        if (b->scenario != NULL) {
            gs_hil_scenario_start_(b, now);
        }
        if (b->dirty || (!b->timed_out && now >= b->stale_at)) {
            update_state(b);
        }
        b->input = b->commanded;
        if (b->has_load) { /* the scenario's load adds to the commanded one */
            b->input.load = (gs_real)((double)b->commanded.load + gs_hil_scenario_load_(b, now));
        }
        for (unsigned s = 0; s < b->config.substeps; ++s) {
            gs_rig_step(b->consts, b->state, &b->input, &b->output);
        }
        b->counters.steps += b->config.substeps;
        b->counters.count[GS_HIL_COUNT_PERIODS] = now + 1u;
        if (b->fault_count > 0u) {
            gs_hil_faults_update_(b, now);
        }
        if (b->scenario != NULL) {
            gs_hil_scenario_end_(b, now);
        }
        emit(b);
        if (!b->config.deferred_prepare) {
            gs_hil_prepare(b);
        }
    }
}

uint64_t gs_hil_period_at(const gs_hil_bridge *b, double t_s)
{
    double k = ceil((t_s - GS_HIL_REPLAY_SLACK_S) / b->period_s);
    return k > 0.0 ? (uint64_t)k : 0u;
}

void gs_hil_advance_to(gs_hil_bridge *b, double t_s)
{
    uint64_t k = gs_hil_period_at(b, t_s);
    uint64_t now = b->counters.count[GS_HIL_COUNT_PERIODS];
    if (k > now) {
        gs_hil_advance(b, k - now);
    }
}

uint64_t gs_hil_periods_in(const gs_hil_bridge *b, double s)
{
    double n = nearbyint(s / b->period_s); /* half to even, as Python's round() */
    return n > 0.0 ? (uint64_t)n : 0u;
}

void gs_hil_close(gs_hil_bridge *b)
{
    if (b->closed) {
        return;
    }
    for (unsigned i = 0; i < b->command_count; ++i) {
        if (b->commands[i].has_pending) {
            b->commands[i].has_pending = 0;
            count_reason(b, GS_HIL_LATE_AFTER_STOP);
        }
    }
    for (unsigned i = 0; i < b->request_count; ++i) {
        count_reason(b, GS_HIL_LATE_AFTER_STOP);
    }
    b->request_count = 0;
    b->closed = 1;
}
