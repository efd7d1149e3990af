/*
 * What a frame table may say (gearsim/hil.h): the names of roles, modes,
 * flags, counters and reasons, expanded from the header's lists; the kind of
 * a frame; the rules of gs_hil_dbc_check. The C runner's build step and the
 * Python package fill frame tables from DBC files; both are checked here.
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gearsim/hil.h"

#define GS_HIL_NAME_(suffix, name) name,
static const char *const role_names[GS_HIL_ROLES] = {GS_HIL_ROLE_LIST(GS_HIL_NAME_)};
static const char *const mode_names[GS_HIL_MODES] = {GS_HIL_MODE_LIST(GS_HIL_NAME_)};
static const char *const flag_names[GS_HIL_FLAGS] = {GS_HIL_FLAG_LIST(GS_HIL_NAME_)};
static const char *const count_names[GS_HIL_COUNTS] = {GS_HIL_COUNT_LIST(GS_HIL_NAME_)};
static const char *const reason_names[GS_HIL_REASONS] = {GS_HIL_REASON_LIST(GS_HIL_NAME_)};
static const char *const result_names[GS_HIL_PARAM_RESULTS] = {GS_HIL_PARAM_RESULT_LIST(GS_HIL_NAME_)};
static const char *const fault_names[GS_HIL_FAULTS] = {GS_HIL_FAULT_LIST(GS_HIL_NAME_)};
static const char *const op_names[GS_HIL_OPS] = {GS_HIL_OP_LIST(GS_HIL_NAME_)};

typedef struct {
    gs_hil_mode mode;
    const char *name;
} mode_alias;
#define GS_HIL_ALIAS_(suffix, name) {GS_HIL_MODE_##suffix, name},
static const mode_alias mode_aliases[] = {GS_HIL_MODE_ALIAS_LIST(GS_HIL_ALIAS_)};

static const char *name_in(const char *const *names, unsigned count, unsigned i)
{
    return i < count ? names[i] : "?";
}

const char *gs_hil_role_name(gs_hil_role role)
{
    return name_in(role_names, GS_HIL_ROLES, (unsigned)role);
}

const char *gs_hil_mode_name(gs_hil_mode mode)
{
    return name_in(mode_names, GS_HIL_MODES, (unsigned)mode);
}

const char *gs_hil_flag_name(gs_hil_flag flag)
{
    return name_in(flag_names, GS_HIL_FLAGS, (unsigned)flag);
}

const char *gs_hil_count_name(gs_hil_count count)
{
    return name_in(count_names, GS_HIL_COUNTS, (unsigned)count);
}

const char *gs_hil_reason_name(gs_hil_reason reason)
{
    return name_in(reason_names, GS_HIL_REASONS, (unsigned)reason);
}

const char *gs_hil_param_result_name(gs_hil_param_result result)
{
    return name_in(result_names, GS_HIL_PARAM_RESULTS, (unsigned)result);
}

const char *gs_hil_fault_name(gs_hil_fault_kind kind)
{
    return name_in(fault_names, GS_HIL_FAULTS, (unsigned)kind);
}

const char *gs_hil_op_name(gs_hil_op op)
{
    return name_in(op_names, GS_HIL_OPS, (unsigned)op);
}

/* Index of name in names[0..count), or -1. */
static int index_of(const char *const *names, unsigned count, const char *name)
{
    for (unsigned i = 0; i < count; ++i) {
        if (strcmp(names[i], name) == 0) {
            return (int)i;
        }
    }
    return -1;
}

static int is_family(const char *name)
{
    size_t n = strlen(name);
    return n > 0 && name[n - 1u] == '.';
}

/* The member of a family: an output field, a flag or a counter. */
static int family_member(gs_hil_role family, const char *member, size_t *aux)
{
    int i = -1;
    if (family == GS_HIL_ROLE_OUT) {
        for (unsigned k = 0; k < (unsigned)GS_RIG_OUTPUT_FIELDS; ++k) {
            if (strcmp(gs_rig_output_info[k].name, member) == 0) {
                *aux = gs_rig_output_info[k].offset / sizeof(gs_real);
                return 0;
            }
        }
    } else if (family == GS_HIL_ROLE_STATUS_FLAG) {
        i = index_of(flag_names, GS_HIL_FLAGS, member);
    } else if (family == GS_HIL_ROLE_STATUS_COUNT) {
        i = index_of(count_names, GS_HIL_COUNTS, member);
    }
    if (i < 0) {
        return -1;
    }
    *aux = (size_t)i;
    return 0;
}

int gs_hil_role_parse(const char *text, gs_hil_role *role, size_t *aux)
{
    *role = GS_HIL_ROLE_NONE;
    *aux = 0;
    if (text == NULL || text[0] == '\0') {
        return -1;
    }
    /* whole names first: out.follower_angle is not an output field */
    for (unsigned r = 1; r < GS_HIL_ROLES; ++r) {
        if (!is_family(role_names[r]) && strcmp(role_names[r], text) == 0) {
            *role = (gs_hil_role)r;
            return 0;
        }
    }
    for (unsigned r = 1; r < GS_HIL_ROLES; ++r) {
        size_t n = strlen(role_names[r]);
        if (is_family(role_names[r]) && strncmp(role_names[r], text, n) == 0 &&
            family_member((gs_hil_role)r, text + n, aux) == 0) {
            *role = (gs_hil_role)r;
            return 0;
        }
    }
    return -1;
}

/* Case-insensitive comparison of a and b[0..n). */
static int same_name(const char *a, const char *b, size_t n)
{
    if (strlen(a) != n) {
        return 0;
    }
    for (size_t i = 0; i < n; ++i) {
        if (tolower((unsigned char)a[i]) != tolower((unsigned char)b[i])) {
            return 0;
        }
    }
    return 1;
}

int gs_hil_mode_parse(const char *name)
{
    if (name == NULL) {
        return -1;
    }
    const char *end = name + strlen(name);
    while (*name != '\0' && isspace((unsigned char)*name)) {
        ++name;
    }
    while (end > name && isspace((unsigned char)end[-1])) {
        --end;
    }
    size_t n = (size_t)(end - name);
    for (unsigned m = 0; m < GS_HIL_MODES; ++m) {
        if (same_name(mode_names[m], name, n)) {
            return (int)m;
        }
    }
    for (size_t k = 0; k < sizeof mode_aliases / sizeof mode_aliases[0]; ++k) {
        if (same_name(mode_aliases[k].name, name, n)) {
            return (int)mode_aliases[k].mode;
        }
    }
    return -1;
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
    case GS_HIL_ROLE_PARAM_ID:
    case GS_HIL_ROLE_PARAM_ELEMENT:
    case GS_HIL_ROLE_PARAM_VALUE:
    case GS_HIL_ROLE_ACK_ID:
    case GS_HIL_ROLE_ACK_ELEMENT:
    case GS_HIL_ROLE_ACK_VALUE:
    case GS_HIL_ROLE_ACK_RESULT:
    case GS_HIL_ROLES:
    default:
        return -1;
    }
}

static int is_status_role(gs_hil_role role)
{
    return role == GS_HIL_ROLE_STATUS_COUNTER || role == GS_HIL_ROLE_STATUS_FLAG || role == GS_HIL_ROLE_STATUS_COUNT;
}

static int is_param_role(gs_hil_role role)
{
    return role == GS_HIL_ROLE_PARAM_ID || role == GS_HIL_ROLE_PARAM_ELEMENT || role == GS_HIL_ROLE_PARAM_VALUE;
}

static int is_ack_role(gs_hil_role role)
{
    return role == GS_HIL_ROLE_ACK_ID || role == GS_HIL_ROLE_ACK_ELEMENT || role == GS_HIL_ROLE_ACK_VALUE ||
           role == GS_HIL_ROLE_ACK_RESULT;
}

/* The kind of frame a role makes (OTHER for no role). */
static gs_hil_frame_kind kind_of_role(gs_hil_role role)
{
    if (role == GS_HIL_ROLE_NONE) {
        return GS_HIL_FRAME_OTHER;
    }
    if (gs_hil_role_command_index(role) >= 0) {
        return GS_HIL_FRAME_COMMAND;
    }
    if (is_param_role(role)) {
        return GS_HIL_FRAME_PARAM;
    }
    return is_ack_role(role) ? GS_HIL_FRAME_ACK : GS_HIL_FRAME_FEEDBACK;
}

gs_hil_frame_kind gs_hil_frame_kind_of(const gs_hil_frame_spec *spec)
{
    gs_hil_frame_kind kind = GS_HIL_FRAME_OTHER;
    for (unsigned s = 0; s < spec->signal_count; ++s) {
        gs_hil_frame_kind k = kind_of_role(spec->signals[s].role);
        if (k == GS_HIL_FRAME_COMMAND) {
            return k; /* a frame with any command role is a command frame */
        }
        if (k != GS_HIL_FRAME_OTHER && kind == GS_HIL_FRAME_OTHER) {
            kind = k;
        }
    }
    return kind;
}

int gs_hil_frame_is_status(const gs_hil_frame_spec *spec)
{
    for (unsigned s = 0; s < spec->signal_count; ++s) {
        if (is_status_role(spec->signals[s].role)) {
            return 1;
        }
    }
    return 0;
}

unsigned gs_hil_feedback_order(const gs_hil_dbc *dbc, unsigned order[GS_HIL_MAX_FRAMES])
{
    unsigned count = 0;
    for (int status = 0; status <= 1; ++status) {
        unsigned first = count;
        for (unsigned i = 0; i < dbc->frame_count && i < GS_HIL_MAX_FRAMES; ++i) {
            const gs_hil_frame_spec *f = &dbc->frames[i];
            if (gs_hil_frame_kind_of(f) != GS_HIL_FRAME_FEEDBACK || gs_hil_frame_is_status(f) != status) {
                continue;
            }
            unsigned j = count++;
            while (j > first && dbc->frames[order[j - 1u]].id > f->id) {
                order[j] = order[j - 1u];
                --j;
            }
            order[j] = i;
        }
    }
    return count;
}

/* ---- the rules ------------------------------------------------------------- */

#ifdef __GNUC__
static gs_hil_status refuse(gs_hil_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
#endif

static gs_hil_status refuse(gs_hil_error *err, const char *fmt, ...)
{
    if (err != NULL) {
        va_list ap;
        va_start(ap, fmt);
        err->parameter = "dbc";
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return GS_HIL_E_CONFIG;
}

/* The physical range of a signal's raw bits (+-inf for a float signal). */
static void raw_range(const gs_hil_signal *sig, double *low, double *high)
{
    if (sig->is_float) {
        *low = -HUGE_VAL;
        *high = HUGE_VAL;
        return;
    }
    double lo_raw = sig->is_signed ? -ldexp(1.0, (int)sig->length - 1) : 0.0;
    double hi_raw = sig->is_signed ? ldexp(1.0, (int)sig->length - 1) - 1.0 : ldexp(1.0, (int)sig->length) - 1.0;
    double a = lo_raw * sig->scale + sig->offset, b = hi_raw * sig->scale + sig->offset;
    *low = a < b ? a : b;
    *high = a < b ? b : a;
}

void gs_hil_signal_limits(const gs_hil_signal *sig, double *minimum, double *maximum)
{
    double low, high;
    raw_range(sig, &low, &high);
    *minimum = isinf(sig->minimum) ? low : sig->minimum; /* -HUGE_VAL: the DBC gives none */
    *maximum = isinf(sig->maximum) ? high : sig->maximum;
}

/* The most significant bit's index counted from the frame's first bit as
 * a big-endian 64-bit word, for a big-endian signal. */
static unsigned msb_index(const gs_hil_signal *sig)
{
    return (sig->start / 8u) * 8u + (7u - sig->start % 8u);
}

/* The signal's bits lie inside a frame of length bytes. */
static int fits_frame(const gs_hil_signal *sig, unsigned length)
{
    unsigned bits = 8u * length;
    if (sig->length < 1u || sig->length > 64u) {
        return 0;
    }
    if (sig->is_big_endian) {
        return sig->start < bits && msb_index(sig) + sig->length <= bits;
    }
    return sig->start + sig->length <= bits;
}

static gs_hil_status check_range(const gs_hil_frame_spec *f, const gs_hil_signal *sig, gs_hil_error *err)
{
    double low, high, minimum, maximum;
    raw_range(sig, &low, &high);
    gs_hil_signal_limits(sig, &minimum, &maximum);
    if (minimum > maximum) {
        return refuse(err, "%s.%s: minimum %.10g > maximum %.10g", f->name, sig->name, minimum, maximum);
    }
    /* the tolerance absorbs the decimal rounding of DBC limits */
    double tol = fabs(sig->scale) * 1e-6;
    gs_hil_frame_kind from = kind_of_role(sig->role); /* what the rig sends must never wrap */
    int feedback = from == GS_HIL_FRAME_FEEDBACK || from == GS_HIL_FRAME_ACK;
    if (feedback && (minimum < low - tol || maximum > high + tol)) {
        return refuse(err,
                      "%s.%s: range [%.10g, %.10g] does not fit %u %s bits at scale %.10g ([%.10g, %.10g]); "
                      "values would wrap",
                      f->name, sig->name, minimum, maximum, sig->length, sig->is_signed ? "signed" : "unsigned",
                      sig->scale, low, high);
    }
    return GS_HIL_OK;
}

static gs_hil_status check_mode(const gs_hil_frame_spec *f, const gs_hil_signal *sig, gs_hil_error *err)
{
    if (sig->is_float) {
        return refuse(err, "%s.%s: a mode signal must be an integer signal", f->name, sig->name);
    }
    for (unsigned c = 0; c < sig->choice_count; ++c) {
        if (gs_hil_mode_parse(sig->choices[c].name) < 0) {
            return refuse(err, "%s.%s: mode value %lld is named '%s'; expected one of Disabled, Speed, Torque", f->name,
                          sig->name, (long long)sig->choices[c].value, sig->choices[c].name);
        }
    }
    return GS_HIL_OK;
}

static gs_hil_status check_role(const gs_hil_frame_spec *f, const gs_hil_signal *sig, gs_hil_error *err)
{
    size_t aux_limit = sig->role == GS_HIL_ROLE_OUT            ? (size_t)GS_RIG_OUTPUT_FIELDS
                       : sig->role == GS_HIL_ROLE_STATUS_FLAG  ? (size_t)GS_HIL_FLAGS
                       : sig->role == GS_HIL_ROLE_STATUS_COUNT ? (size_t)GS_HIL_COUNTS
                                                               : 1u;
    if ((unsigned)sig->role >= GS_HIL_ROLES || sig->aux >= aux_limit) {
        return refuse(err, "%s.%s: role %d (aux %lu) is not a role of gearsim/hil.h", f->name, sig->name,
                      (int)sig->role, (unsigned long)sig->aux);
    }
    int counter = sig->role == GS_HIL_ROLE_STATUS_COUNT || sig->role == GS_HIL_ROLE_STATUS_COUNTER;
    int index = sig->role == GS_HIL_ROLE_PARAM_ID || sig->role == GS_HIL_ROLE_PARAM_ELEMENT ||
                sig->role == GS_HIL_ROLE_ACK_ID || sig->role == GS_HIL_ROLE_ACK_ELEMENT ||
                sig->role == GS_HIL_ROLE_ACK_RESULT;
    if ((counter || index) && (sig->is_float || sig->is_signed || sig->scale < 1.0 || sig->scale > 1.0 ||
                               sig->offset < 0.0 || sig->offset > 0.0)) {
        return refuse(err, "%s.%s: a %s must be an unsigned integer signal (scale 1, offset 0)", f->name, sig->name,
                      counter ? "counter" : "parameter index or result");
    }
    double minimum, maximum;
    gs_hil_signal_limits(sig, &minimum, &maximum);
    if (sig->role == GS_HIL_ROLE_STATUS_FLAG && (minimum > 0.0 || maximum < 1.0)) {
        return refuse(err, "%s.%s: a flag must hold 0 and 1", f->name, sig->name);
    }
    if (sig->role == GS_HIL_ROLE_CMD_MODE) {
        return check_mode(f, sig, err);
    }
    return GS_HIL_OK;
}

static gs_hil_status check_signal(const gs_hil_frame_spec *f, gs_hil_frame_kind kind, const gs_hil_signal *sig,
                                  gs_hil_error *err)
{
    if (kind != GS_HIL_FRAME_OTHER) {
        if (sig->is_float && sig->length != 32u && sig->length != 64u) {
            return refuse(err, "%s.%s: a float signal has 32 or 64 bits, not %u", f->name, sig->name, sig->length);
        }
        if (!fits_frame(sig, f->length)) {
            return refuse(err, "%s.%s: its %u bits from bit %u do not fit the frame's %u bytes", f->name, sig->name,
                          sig->length, sig->start, f->length);
        }
    }
    if (check_range(f, sig, err) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    return sig->role == GS_HIL_ROLE_NONE ? GS_HIL_OK : check_role(f, sig, err);
}

static const char *const kind_names[] = {"command", "feedback", "other", "parameter", "acknowledgement"};

static gs_hil_status check_frame(const gs_hil_frame_spec *f, gs_hil_error *err)
{
    gs_hil_frame_kind kind = gs_hil_frame_kind_of(f);
    for (unsigned s = 0; s < f->signal_count; ++s) {
        gs_hil_frame_kind k = kind_of_role(f->signals[s].role);
        if (k != GS_HIL_FRAME_OTHER && k != kind) {
            return refuse(err, "%s mixes %s and %s roles", f->name, kind_names[kind], kind_names[k]);
        }
    }
    if (kind == GS_HIL_FRAME_FEEDBACK && f->cycle_ms == 0u) {
        return refuse(err, "feedback frame %s has no GenMsgCycleTime", f->name);
    }
    if (kind != GS_HIL_FRAME_OTHER && f->is_multiplexed) {
        return refuse(err, "%s: multiplexed frames are not supported for commands, parameters or feedback", f->name);
    }
    if (kind != GS_HIL_FRAME_OTHER && f->length > GS_HIL_MAX_DATA) {
        return refuse(err, "%s: %u data bytes; command and feedback frames are classic CAN frames of at most %u",
                      f->name, f->length, GS_HIL_MAX_DATA);
    }
    if (f->signal_count > 64u) {
        return refuse(err, "%s: more than 64 signals", f->name);
    }
    for (unsigned s = 0; s < f->signal_count; ++s) {
        if (check_signal(f, kind, &f->signals[s], err) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
    }
    return GS_HIL_OK;
}

/* A command, parameter or acknowledgement role on one signal of the whole
 * DBC only; a parameter frame with its index and value. */
static gs_hil_status check_unique_roles(const gs_hil_dbc *dbc, gs_hil_error *err)
{
    const gs_hil_frame_spec *frame_of[GS_HIL_ROLES] = {NULL};
    const gs_hil_signal *signal_of[GS_HIL_ROLES] = {NULL};
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        const gs_hil_frame_spec *f = &dbc->frames[i];
        for (unsigned s = 0; s < f->signal_count; ++s) {
            gs_hil_role role = f->signals[s].role;
            gs_hil_frame_kind k = kind_of_role(role);
            if (k != GS_HIL_FRAME_COMMAND && k != GS_HIL_FRAME_PARAM && k != GS_HIL_FRAME_ACK) {
                continue;
            }
            if (signal_of[role] != NULL) {
                return refuse(err, "%s role '%s' is on %s.%s and on %s.%s", kind_names[k], gs_hil_role_name(role),
                              frame_of[role]->name, signal_of[role]->name, f->name, f->signals[s].name);
            }
            frame_of[role] = f;
            signal_of[role] = &f->signals[s];
        }
    }
    int any_param = signal_of[GS_HIL_ROLE_PARAM_ID] != NULL || signal_of[GS_HIL_ROLE_PARAM_ELEMENT] != NULL ||
                    signal_of[GS_HIL_ROLE_PARAM_VALUE] != NULL;
    if (any_param && (signal_of[GS_HIL_ROLE_PARAM_ID] == NULL || signal_of[GS_HIL_ROLE_PARAM_VALUE] == NULL)) {
        return refuse(err, "a parameter frame needs a param.id and a param.value signal");
    }
    return GS_HIL_OK;
}

gs_hil_status gs_hil_dbc_check(const gs_hil_dbc *dbc, gs_hil_error *err)
{
    if (dbc == NULL || (dbc->frames == NULL && dbc->frame_count > 0u)) {
        return refuse(err, "no frame table");
    }
    if (dbc->frame_count > GS_HIL_MAX_FRAMES) {
        return refuse(err, "%u frames; at most %u", dbc->frame_count, GS_HIL_MAX_FRAMES);
    }
    unsigned command_frames = 0, param_frames = 0, ack_frames = 0;
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        if (check_frame(&dbc->frames[i], err) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
        gs_hil_frame_kind kind = gs_hil_frame_kind_of(&dbc->frames[i]);
        command_frames += kind == GS_HIL_FRAME_COMMAND;
        param_frames += kind == GS_HIL_FRAME_PARAM;
        ack_frames += kind == GS_HIL_FRAME_ACK;
    }
    if (command_frames > GS_HIL_MAX_COMMAND_FRAMES) {
        return refuse(err, "%u command frames; at most %u", command_frames, GS_HIL_MAX_COMMAND_FRAMES);
    }
    if (param_frames > 1u || ack_frames > 1u) {
        return refuse(err, "%u parameter and %u acknowledgement frames; at most one of each", param_frames, ack_frames);
    }
    return check_unique_roles(dbc, err);
}
