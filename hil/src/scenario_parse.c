/*
 * Reading a scenario file (gearsim/hil.h, docs/hil.md "Scenarios"): a subset
 * of TOML (a [scenario] table and [[step]] tables of `key = value` lines,
 * values strings, numbers and booleans; comments) that Python's tomllib
 * reads the same. Text in, a gs_hil_scenario out; no I/O, no heap. The
 * first error ends the reading with one message "FILE:LINE: key: what".
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

#define KEY_MAX    32
#define TABLE_KEYS 24

typedef enum { VALUE_STRING = 0, VALUE_NUMBER, VALUE_BOOL } value_type;

typedef struct {
    char key[KEY_MAX];
    value_type type;
    char text[GS_HIL_TEXT_MAX];
    double number;
    int is_integer;
    int boolean;
    unsigned line;
} entry;

typedef enum { TABLE_NONE = 0, TABLE_SCENARIO, TABLE_STEP } table_kind;

typedef struct {
    table_kind kind;
    unsigned line;
    entry entries[TABLE_KEYS];
    unsigned count;
} table;

typedef struct {
    gs_hil_scenario *s;
    gs_hil_error *err;
    table t;
    int seen_scenario;
    int have_duration;
    double last_at; /* the latest step time, checked against the duration */
    unsigned last_at_line;
} parser;

#ifdef __GNUC__
static gs_hil_status fail(parser *p, unsigned line, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
#endif

static gs_hil_status fail(parser *p, unsigned line, const char *key, const char *fmt, ...)
{
    char what[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    p->err->parameter = "scenario";
    snprintf(p->err->message, sizeof p->err->message, "%s:%u: %s: %s", p->s->file, line, key, what);
    return GS_HIL_E_CONFIG;
}

/* ---- lines --------------------------------------------------------------------- */

static const char *skip_blank(const char *c, const char *end)
{
    while (c < end && (*c == ' ' || *c == '\t')) {
        ++c;
    }
    return c;
}

static int is_key_char(char c)
{
    return isalnum((unsigned char)c) || c == '_' || c == '-';
}

/* After a value: blanks, then nothing or a comment. */
static int rest_is_empty(const char *c, const char *end)
{
    c = skip_blank(c, end);
    return c == end || *c == '#';
}

static gs_hil_status read_string(parser *p, unsigned line, const char *key, const char **c, const char *end, entry *e)
{
    char quote = **c;
    size_t n = 0;
    const char *q = *c + 1;
    for (; q < end && *q != quote; ++q) {
        char ch = *q;
        if (quote == '"' && ch == '\\') {
            if (++q == end) {
                break;
            }
            switch (*q) {
            case '"':
                ch = '"';
                break;
            case '\\':
                ch = '\\';
                break;
            case 'n':
                ch = '\n';
                break;
            case 't':
                ch = '\t';
                break;
            default:
                return fail(p, line, key, "escape \\%c is not used in a scenario (\\\" \\\\ \\n \\t)", *q);
            }
        }
        if ((unsigned char)ch < 0x20u && ch != '\t') {
            return fail(p, line, key, "control character in a string");
        }
        if (n + 1u >= sizeof e->text) {
            return fail(p, line, key, "string longer than %u characters", (unsigned)sizeof e->text - 1u);
        }
        e->text[n++] = ch;
    }
    if (q == end) {
        return fail(p, line, key, "string without its closing quote");
    }
    e->text[n] = '\0';
    e->type = VALUE_STRING;
    *c = q + 1;
    return GS_HIL_OK;
}

/* A TOML decimal number: [+-] digits (single underscores between them)
 * [. digits] [e [+-] digits]; inf and nan are refused. */
static gs_hil_status read_number(parser *p, unsigned line, const char *key, const char **c, const char *end, entry *e)
{
    char digits[64];
    size_t n = 0;
    const char *q = *c;
    int integer = 1, any_digit = 0;
    while (q < end && (isdigit((unsigned char)*q) || strchr("+-._eE", *q) != NULL)) {
        if (*q == '_') {
            if (q == *c || !isdigit((unsigned char)q[-1]) || q + 1 == end || !isdigit((unsigned char)q[1])) {
                return fail(p, line, key, "'_' in a number stands between two digits");
            }
            ++q;
            continue;
        }
        integer &= *q != '.' && *q != 'e' && *q != 'E';
        any_digit |= isdigit((unsigned char)*q) != 0;
        if (n + 1u >= sizeof digits) {
            return fail(p, line, key, "number too long");
        }
        digits[n++] = *q++;
    }
    digits[n] = '\0';
    char *stop = NULL;
    double x = any_digit ? strtod(digits, &stop) : 0.0;
    if (!any_digit || stop != digits + n || !isfinite(x)) {
        return fail(p, line, key, "not a value (a string in quotes, a finite number, true or false)");
    }
    e->type = VALUE_NUMBER;
    e->number = x;
    e->is_integer = integer;
    *c = q;
    return GS_HIL_OK;
}

static gs_hil_status read_value(parser *p, unsigned line, const char *key, const char **c, const char *end, entry *e)
{
    size_t left = (size_t)(end - *c);
    if (**c == '"' || **c == '\'') {
        if (left >= 3u && (*c)[1] == **c && (*c)[2] == **c) {
            return fail(p, line, key, "multi-line strings are not used in a scenario");
        }
        return read_string(p, line, key, c, end, e);
    }
    if (left >= 4u && strncmp(*c, "true", 4) == 0 && (left == 4u || !is_key_char((*c)[4]))) {
        e->type = VALUE_BOOL;
        e->boolean = 1;
        *c += 4;
        return GS_HIL_OK;
    }
    if (left >= 5u && strncmp(*c, "false", 5) == 0 && (left == 5u || !is_key_char((*c)[5]))) {
        e->type = VALUE_BOOL;
        e->boolean = 0;
        *c += 5;
        return GS_HIL_OK;
    }
    if (**c == '[' || **c == '{') {
        return fail(p, line, key, "arrays and inline tables are not used in a scenario");
    }
    return read_number(p, line, key, c, end, e);
}

static gs_hil_status close_table(parser *p);

static gs_hil_status header(parser *p, unsigned line, const char *c, const char *end)
{
    int array = end - c >= 2 && c[1] == '[';
    const char *name = skip_blank(c + (array ? 2 : 1), end);
    const char *stop = name;
    while (stop < end && is_key_char(*stop)) {
        ++stop;
    }
    const char *close = skip_blank(stop, end);
    int closed = array ? (end - close >= 2 && close[0] == ']' && close[1] == ']') : (close < end && *close == ']');
    char shown[40];
    snprintf(shown, sizeof shown, "%.*s", (int)(stop - name), name);
    if (!closed || !rest_is_empty(close + (array ? 2 : 1), end)) {
        return fail(p, line, "table", "expected [scenario] or [[step]]");
    }
    if (close_table(p) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    memset(&p->t, 0, sizeof p->t);
    p->t.line = line;
    if (!array && strcmp(shown, "scenario") == 0) {
        if (p->seen_scenario) {
            return fail(p, line, "[scenario]", "given twice");
        }
        p->seen_scenario = 1;
        p->t.kind = TABLE_SCENARIO;
        return GS_HIL_OK;
    }
    if (array && strcmp(shown, "step") == 0) {
        p->t.kind = TABLE_STEP;
        return GS_HIL_OK;
    }
    return fail(p, line, array ? "[[table]]" : "[table]", "unknown table '%s': a scenario has [scenario] and [[step]]",
                shown);
}

static gs_hil_status key_value(parser *p, unsigned line, const char *c, const char *end)
{
    const char *k = c;
    while (c < end && is_key_char(*c)) {
        ++c;
    }
    char key[KEY_MAX];
    if (c == k || (size_t)(c - k) >= sizeof key) {
        return fail(p, line, "key", "expected 'key = value' with a bare key (letters, digits, _ and -)");
    }
    snprintf(key, sizeof key, "%.*s", (int)(c - k), k);
    c = skip_blank(c, end);
    if (c == end || *c != '=') {
        return fail(p, line, key,
                    c < end && *c == '.' ? "dotted keys are not used in a scenario" : "expected 'key = value'");
    }
    c = skip_blank(c + 1, end);
    if (c == end) {
        return fail(p, line, key, "no value");
    }
    if (p->t.kind == TABLE_NONE) {
        return fail(p, line, key, "outside a table: start with [scenario] or [[step]]");
    }
    for (unsigned i = 0; i < p->t.count; ++i) {
        if (strcmp(p->t.entries[i].key, key) == 0) {
            return fail(p, line, key, "given twice (first on line %u)", p->t.entries[i].line);
        }
    }
    if (p->t.count == TABLE_KEYS) {
        return fail(p, line, key, "too many keys in one table");
    }
    entry *e = &p->t.entries[p->t.count];
    memset(e, 0, sizeof *e);
    memcpy(e->key, key, sizeof key);
    e->line = line;
    if (read_value(p, line, key, &c, end, e) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!rest_is_empty(c, end)) {
        return fail(p, line, key, "unexpected text after the value");
    }
    p->t.count++;
    return GS_HIL_OK;
}

static gs_hil_status one_line(parser *p, unsigned line, const char *c, const char *end)
{
    while (end > c && (end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t')) {
        --end;
    }
    c = skip_blank(c, end);
    if (c == end || *c == '#') {
        return GS_HIL_OK;
    }
    return *c == '[' ? header(p, line, c, end) : key_value(p, line, c, end);
}

/* ---- the entries of a table ------------------------------------------------------- */

static entry *find(parser *p, const char *key)
{
    for (unsigned i = 0; i < p->t.count; ++i) {
        if (strcmp(p->t.entries[i].key, key) == 0) {
            return &p->t.entries[i];
        }
    }
    return NULL;
}

static gs_hil_status number(parser *p, const char *key, int required, double *out)
{
    entry *e = find(p, key);
    if (e == NULL) {
        return required ? fail(p, p->t.line, key, "missing (a number)") : GS_HIL_OK;
    }
    if (e->type != VALUE_NUMBER) {
        return fail(p, e->line, key, "expected a number");
    }
    *out = e->number;
    return GS_HIL_OK;
}

static gs_hil_status string(parser *p, const char *key, int required, const char **out)
{
    entry *e = find(p, key);
    if (e == NULL) {
        return required ? fail(p, p->t.line, key, "missing (a string)") : GS_HIL_OK;
    }
    if (e->type != VALUE_STRING) {
        return fail(p, e->line, key, "expected a string in quotes");
    }
    *out = e->text;
    return GS_HIL_OK;
}

static unsigned line_of(parser *p, const char *key)
{
    entry *e = find(p, key);
    return e != NULL ? e->line : p->t.line;
}

/* Every key of the table is one of allowed (a space-separated list). */
static gs_hil_status only(parser *p, const char *what, const char *allowed)
{
    for (unsigned i = 0; i < p->t.count; ++i) {
        const char *key = p->t.entries[i].key;
        size_t n = strlen(key);
        const char *hit = strstr(allowed, key);
        while (hit != NULL && !((hit == allowed || hit[-1] == ' ') && (hit[n] == ' ' || hit[n] == '\0'))) {
            hit = strstr(hit + 1, key);
        }
        if (hit == NULL) {
            return fail(p, p->t.entries[i].line, key, "not a key of %s (keys: %s)", what, allowed);
        }
    }
    return GS_HIL_OK;
}

static gs_hil_status scenario_table(parser *p)
{
    gs_hil_scenario *s = p->s;
    const char *name = NULL;
    double seed = 1.0;
    if (only(p, "[scenario]", "name description duration seed") != GS_HIL_OK ||
        string(p, "name", 0, &name) != GS_HIL_OK || number(p, "duration", 1, &s->duration_s) != GS_HIL_OK ||
        number(p, "seed", 0, &seed) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    const char *description = NULL;
    if (string(p, "description", 0, &description) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!(s->duration_s > 0.0 && s->duration_s < 1e9)) {
        return fail(p, line_of(p, "duration"), "duration", "a time > 0 s (and below 1e9 s)");
    }
    if (!(seed >= 0.0 && seed < 9.0e15) || floor(seed) < seed) {
        return fail(p, line_of(p, "seed"), "seed", "a whole number >= 0");
    }
    s->seed = (uint64_t)seed;
    snprintf(s->name, sizeof s->name, "%.127s", name != NULL ? name : "scenario");
    p->have_duration = 1;
    return GS_HIL_OK;
}

/* ---- names of the DBC ------------------------------------------------------------- */

/* "Signal" or "Frame.Signal" among the frames of kind (a value role for
 * feedback, a command role for commands): 0 and the indices, -1 none, -2
 * more than one. */
static int find_signal(const gs_hil_dbc *dbc, const char *text, gs_hil_frame_kind kind, unsigned *frame,
                       unsigned *signal)
{
    const char *dot = strchr(text, '.');
    int found = 0;
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        const gs_hil_frame_spec *f = &dbc->frames[i];
        if (gs_hil_frame_kind_of(f) != kind) {
            continue;
        }
        if (dot != NULL && (strlen(f->name) != (size_t)(dot - text) || strncmp(f->name, text, (size_t)(dot - text)))) {
            continue;
        }
        const char *name = dot != NULL ? dot + 1 : text;
        for (unsigned k = 0; k < f->signal_count; ++k) {
            const gs_hil_signal *sig = &f->signals[k];
            int usable = kind == GS_HIL_FRAME_COMMAND
                             ? gs_hil_role_command_index(sig->role) >= 0
                             : (sig->role == GS_HIL_ROLE_OUT || sig->role == GS_HIL_ROLE_OUT_FOLLOWER_ANGLE ||
                                sig->role == GS_HIL_ROLE_IN_BASE_SPEED || sig->role == GS_HIL_ROLE_IN_BASE_TORQUE ||
                                sig->role == GS_HIL_ROLE_IN_LOAD);
            if (usable && strcmp(sig->name, name) == 0) {
                *frame = i;
                *signal = k;
                ++found;
            }
        }
    }
    return found == 1 ? 0 : found == 0 ? -1 : -2;
}

static int find_frame(const gs_hil_dbc *dbc, const char *name, unsigned *frame)
{
    for (unsigned i = 0; i < dbc->frame_count; ++i) {
        if (strcmp(dbc->frames[i].name, name) == 0 && gs_hil_frame_kind_of(&dbc->frames[i]) == GS_HIL_FRAME_FEEDBACK) {
            *frame = i;
            return 0;
        }
    }
    return -1;
}

static int find_flag(const char *name, unsigned *flag)
{
    for (unsigned i = 0; i < GS_HIL_STATE_FLAGS; ++i) {
        if (strcmp(gs_hil_flag_name((gs_hil_flag)i), name) == 0) {
            *flag = i;
            return 0;
        }
    }
    return -1;
}

/* A signal or flag a condition or an expectation reads. commands_only: the
 * command signals and flags (expectations are on what the rig received). */
static gs_hil_status source(parser *p, const char *key, const char *name, int commands_only, gs_hil_condition *c)
{
    unsigned line = line_of(p, key);
    const gs_hil_dbc *dbc = p->s->dbc;
    int r = find_signal(dbc, name, GS_HIL_FRAME_COMMAND, &c->frame, &c->signal);
    if (r == 0) {
        c->source = GS_HIL_SOURCE_COMMAND;
        return GS_HIL_OK;
    }
    if (r == -1 && find_flag(name, &c->flag) == 0) {
        c->source = GS_HIL_SOURCE_FLAG;
        return GS_HIL_OK;
    }
    if (r == -1 && !commands_only) {
        r = find_signal(dbc, name, GS_HIL_FRAME_FEEDBACK, &c->frame, &c->signal);
        if (r == 0) {
            c->source = GS_HIL_SOURCE_FEEDBACK;
            return GS_HIL_OK;
        }
    }
    if (r == -2) {
        return fail(p, line, key, "'%s' is in more than one frame of %s: write Frame.Signal", name, dbc->name);
    }
    return fail(p, line, key, "'%s' is no %s of %s", name,
                commands_only ? "command signal (with a cmd. role) or state flag (cmd_timeout, safe_state, "
                                "drive_disabled, fault_active)"
                              : "feedback or command signal with a role, or state flag",
                dbc->name);
}

/* "Name op number", e.g. "BaseSpeed > 10". */
static gs_hil_status condition(parser *p, const char *text, gs_hil_condition *c)
{
    char name[GS_HIL_TEXT_MAX];
    size_t n = 0;
    const char *q = text;
    while (*q == ' ') {
        ++q;
    }
    while (*q != '\0' && (is_key_char(*q) || *q == '.') && n + 1u < sizeof name) {
        name[n++] = *q++;
    }
    name[n] = '\0';
    while (*q == ' ') {
        ++q;
    }
    int op = -1;
    for (int i = 0; i < GS_HIL_OPS; ++i) { /* longest first: <= before < */
        const char *o = gs_hil_op_name((gs_hil_op)i);
        size_t len = strlen(o);
        if (strncmp(q, o, len) == 0 && (op < 0 || len > strlen(gs_hil_op_name((gs_hil_op)op)))) {
            op = i;
        }
    }
    if (n == 0 || op < 0) {
        return fail(p, line_of(p, "when"), "when", "expected 'Signal op number' (op one of < <= > >= == !=)");
    }
    q += strlen(gs_hil_op_name((gs_hil_op)op));
    char *stop = NULL;
    double v = strtod(q, &stop);
    while (stop != NULL && *stop == ' ') {
        ++stop;
    }
    if (stop == q || stop == NULL || *stop != '\0' || !isfinite(v)) {
        return fail(p, line_of(p, "when"), "when", "expected 'Signal op number': '%s' is not a finite number", q);
    }
    c->op = (gs_hil_op)op;
    c->value = v;
    return source(p, "when", name, 0, c);
}

/* ---- steps ---------------------------------------------------------------------------- */

static gs_hil_status time_after(parser *p, const char *key, double at, double *out, int *given)
{
    *given = find(p, key) != NULL;
    if (!*given) {
        return GS_HIL_OK;
    }
    if (number(p, key, 1, out) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (strcmp(key, "until") == 0 ? !(*out > at) : !(*out > 0.0)) {
        return fail(p, line_of(p, key), key,
                    strcmp(key, "until") == 0 ? "a time after the step's 'at'" : "a time > 0 s");
    }
    return GS_HIL_OK;
}

static const char *fault_keys(gs_hil_fault_kind kind)
{
    switch (kind) {
    case GS_HIL_FAULT_OFFSET:
    case GS_HIL_FAULT_GAIN:
    case GS_HIL_FAULT_STUCK:
    case GS_HIL_FAULT_QUANTISE:
        return "at name fault signal value until duration when";
    case GS_HIL_FAULT_NOISE:
        return "at name fault signal value seed until duration when";
    case GS_HIL_FAULT_CLAMP:
        return "at name fault signal min max until duration when";
    case GS_HIL_FAULT_DELAY:
        return "at name fault signal periods until duration when";
    case GS_HIL_FAULT_FREEZE:
    case GS_HIL_FAULT_DROPOUT:
        return "at name fault signal until duration when";
    case GS_HIL_FAULT_CORRUPT:
        return "at name fault frame bits seed until duration when";
    case GS_HIL_FAULT_DROP:
    case GS_HIL_FAULT_DUPLICATE:
    case GS_HIL_FAULT_COUNTER_STOP:
    case GS_HIL_FAULTS:
    default:
        return "at name fault frame until duration when";
    }
}

static gs_hil_status whole(parser *p, const char *key, double low, double high, unsigned *out)
{
    double x = 0.0;
    if (number(p, key, 1, &x) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!(x >= low && x <= high) || floor(x) < x) {
        return fail(p, line_of(p, key), key, "a whole number from %g to %g", low, high);
    }
    *out = (unsigned)x;
    return GS_HIL_OK;
}

static gs_hil_status fault_target(parser *p, gs_hil_fault_spec *f)
{
    const char *target = NULL;
    int frame_fault = f->kind >= GS_HIL_FAULT_DROP;
    if (string(p, frame_fault ? "frame" : "signal", 1, &target) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    const gs_hil_dbc *dbc = p->s->dbc;
    if (frame_fault) {
        f->signal = -1;
        if (find_frame(dbc, target, &f->frame) != 0) {
            return fail(p, line_of(p, "frame"), "frame", "'%s' is no feedback frame of %s", target, dbc->name);
        }
        return GS_HIL_OK;
    }
    unsigned signal = 0;
    int r = find_signal(dbc, target, GS_HIL_FRAME_FEEDBACK, &f->frame, &signal);
    if (r != 0) {
        return fail(p, line_of(p, "signal"), "signal",
                    r == -2 ? "'%s' is in more than one frame of %s: write Frame.Signal"
                            : "'%s' is no feedback signal of %s with an out. or in. role",
                    target, dbc->name);
    }
    f->signal = (int)signal;
    return GS_HIL_OK;
}

static gs_hil_status fault_values(parser *p, gs_hil_fault_spec *f)
{
    switch (f->kind) {
    case GS_HIL_FAULT_NOISE:
        if (number(p, "value", 1, &f->value) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
        if (!(f->value >= 0.0)) {
            return fail(p, line_of(p, "value"), "value", "noise: a standard deviation >= 0");
        }
        break;
    case GS_HIL_FAULT_QUANTISE:
        if (number(p, "value", 1, &f->value) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
        if (!(f->value > 0.0)) {
            return fail(p, line_of(p, "value"), "value", "quantise: a step > 0");
        }
        break;
    case GS_HIL_FAULT_OFFSET:
    case GS_HIL_FAULT_GAIN:
    case GS_HIL_FAULT_STUCK:
        return number(p, "value", 1, &f->value);
    case GS_HIL_FAULT_CLAMP:
        f->value = -HUGE_VAL;
        f->value2 = HUGE_VAL;
        if (number(p, "min", 0, &f->value) != GS_HIL_OK || number(p, "max", 0, &f->value2) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
        if (find(p, "min") == NULL && find(p, "max") == NULL) {
            return fail(p, p->t.line, "min", "clamp: give min, max or both");
        }
        if (!(f->value <= f->value2)) {
            return fail(p, line_of(p, "max"), "max", "clamp: max >= min");
        }
        break;
    case GS_HIL_FAULT_DELAY:
        return whole(p, "periods", 1.0, (double)(GS_HIL_DELAY_MAX - 1), &f->periods);
    case GS_HIL_FAULT_CORRUPT:
        f->periods = 1;
        return find(p, "bits") != NULL ? whole(p, "bits", 1.0, 64.0, &f->periods) : GS_HIL_OK;
    case GS_HIL_FAULT_FREEZE:
    case GS_HIL_FAULT_DROPOUT:
    case GS_HIL_FAULT_DROP:
    case GS_HIL_FAULT_DUPLICATE:
    case GS_HIL_FAULT_COUNTER_STOP:
    case GS_HIL_FAULTS:
    default:
        break;
    }
    return GS_HIL_OK;
}

static gs_hil_status fault_step(parser *p, gs_hil_step *st)
{
    gs_hil_scenario *s = p->s;
    const char *kind = NULL;
    if (string(p, "fault", 1, &kind) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    int k = -1;
    for (int i = 0; i < GS_HIL_FAULTS; ++i) {
        if (strcmp(gs_hil_fault_name((gs_hil_fault_kind)i), kind) == 0) {
            k = i;
        }
    }
    if (k < 0 && strcmp(kind, "quantize") == 0) {
        k = GS_HIL_FAULT_QUANTISE;
    }
    if (k < 0) {
        return fail(p, line_of(p, "fault"), "fault",
                    "'%s' is no fault (offset gain noise freeze stuck dropout delay quantise clamp drop duplicate "
                    "corrupt counter_stop)",
                    kind);
    }
    if (s->fault_count == GS_HIL_MAX_FAULTS) {
        return fail(p, line_of(p, "fault"), "fault", "more than %d faults in one scenario", GS_HIL_MAX_FAULTS);
    }
    gs_hil_fault_def *d = &s->faults[s->fault_count];
    memset(d, 0, sizeof *d);
    d->spec.kind = (gs_hil_fault_kind)k;
    d->at_s = st->at_s;
    d->line = st->line;
    d->until_s = HUGE_VAL;
    double seed = (double)(s->seed + st->line); /* a seed of its own per fault by default */
    int has_until = 0, has_duration = 0;
    if (only(p, "a fault step", fault_keys(d->spec.kind)) != GS_HIL_OK || fault_target(p, &d->spec) != GS_HIL_OK ||
        fault_values(p, &d->spec) != GS_HIL_OK || number(p, "seed", 0, &seed) != GS_HIL_OK ||
        time_after(p, "until", st->at_s, &d->until_s, &has_until) != GS_HIL_OK ||
        time_after(p, "duration", st->at_s, &d->duration_s, &has_duration) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!(seed >= 0.0 && seed < 9.0e15) || floor(seed) < seed) {
        return fail(p, line_of(p, "seed"), "seed", "a whole number >= 0");
    }
    d->spec.seed = (uint64_t)seed;
    const char *when = NULL;
    if (string(p, "when", 0, &when) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (when != NULL) {
        d->spec.has_trigger = 1;
        if (condition(p, when, &d->spec.trigger) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
    } else if (has_until && has_duration) {
        return fail(p, line_of(p, "duration"), "duration", "give until or duration, not both (both with 'when')");
    }
    st->index = s->fault_count++;
    return GS_HIL_OK;
}

/* The range an expectation's equals/min/max give. */
static gs_hil_status expect_range(parser *p, gs_hil_expect_def *e, const char *target)
{
    entry *eq = find(p, "equals");
    double tol = 0.0;
    int has_tol = find(p, "tol") != NULL;
    if (number(p, "tol", 0, &tol) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (has_tol && !(tol >= 0.0)) {
        return fail(p, line_of(p, "tol"), "tol", "a tolerance >= 0");
    }
    e->minimum = -HUGE_VAL;
    e->maximum = HUGE_VAL;
    if (eq != NULL) {
        if (find(p, "min") != NULL || find(p, "max") != NULL) {
            return fail(p, eq->line, "equals", "give equals or min/max, not both");
        }
        double v = eq->number;
        const gs_hil_condition *t = &e->target;
        const gs_hil_signal *sig =
            t->source == GS_HIL_SOURCE_COMMAND ? &p->s->dbc->frames[t->frame].signals[t->signal] : NULL;
        if (eq->type == VALUE_STRING) {
            int mode = sig != NULL && sig->role == GS_HIL_ROLE_CMD_MODE ? gs_hil_mode_parse(eq->text) : -1;
            if (mode < 0) {
                return fail(p, eq->line, "equals",
                            "'%s': a name is a mode (disabled, speed, torque) of a cmd.mode signal", eq->text);
            }
            v = (double)mode;
            snprintf(e->what, sizeof e->what, "%.60s == %s", target, gs_hil_mode_name((gs_hil_mode)mode));
        } else if (eq->type == VALUE_BOOL) {
            v = eq->boolean ? 1.0 : 0.0;
            snprintf(e->what, sizeof e->what, "%.60s == %s", target, eq->boolean ? "true" : "false");
        } else {
            if (!has_tol && sig != NULL && sig->role != GS_HIL_ROLE_CMD_MODE) {
                tol = 0.5 * fabs(sig->scale); /* half a step of the signal's raw value */
            }
            snprintf(e->what, sizeof e->what, "%.60s == %g (+- %g)", target, v, tol);
        }
        e->minimum = v - tol;
        e->maximum = v + tol;
        return GS_HIL_OK;
    }
    if (find(p, "min") == NULL && find(p, "max") == NULL) {
        return fail(p, p->t.line, "equals", "an expect step needs equals, min or max");
    }
    if (has_tol) {
        return fail(p, line_of(p, "tol"), "tol", "tol goes with equals");
    }
    if (number(p, "min", 0, &e->minimum) != GS_HIL_OK || number(p, "max", 0, &e->maximum) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!(e->minimum <= e->maximum)) {
        return fail(p, line_of(p, "max"), "max", "max >= min");
    }
    snprintf(e->what, sizeof e->what, "%.60s in [%g, %g]", target, e->minimum, e->maximum);
    return GS_HIL_OK;
}

static gs_hil_status expect_step(parser *p, gs_hil_step *st)
{
    gs_hil_scenario *s = p->s;
    const char *target = NULL;
    if (only(p, "an expect step", "at name expect equals tol min max within until") != GS_HIL_OK ||
        string(p, "expect", 1, &target) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (s->expect_count == GS_HIL_MAX_EXPECTS) {
        return fail(p, line_of(p, "expect"), "expect", "more than %d expectations in one scenario", GS_HIL_MAX_EXPECTS);
    }
    gs_hil_expect_def *e = &s->expects[s->expect_count];
    memset(e, 0, sizeof *e);
    e->at_s = st->at_s;
    e->line = st->line;
    if (source(p, "expect", target, 1, &e->target) != GS_HIL_OK || expect_range(p, e, target) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    int within = 0, until = 0;
    double w = 0.0, u = 0.0;
    if (time_after(p, "within", st->at_s, &w, &within) != GS_HIL_OK ||
        time_after(p, "until", st->at_s, &u, &until) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (within && until) {
        return fail(p, line_of(p, "until"), "until", "give within (eventually) or until (always), not both");
    }
    e->mode = within ? GS_HIL_EXPECT_WITHIN : until ? GS_HIL_EXPECT_UNTIL : GS_HIL_EXPECT_AT;
    e->window_s = within ? w : until ? u : 0.0;
    char when[64];
    if (within) {
        snprintf(when, sizeof when, "within %g s of %g s", w, st->at_s);
    } else if (until) {
        snprintf(when, sizeof when, "from %g s until %g s", st->at_s, u);
    } else {
        snprintf(when, sizeof when, "at %g s", st->at_s);
    }
    if (st->name[0] != '\0') {
        snprintf(e->name, sizeof e->name, "%.127s", st->name);
    } else {
        char what[GS_HIL_TEXT_MAX];
        memcpy(what, e->what, sizeof what);
        snprintf(e->name, sizeof e->name, "%.80s %.40s", what, when);
    }
    st->index = s->expect_count++;
    return GS_HIL_OK;
}

static gs_hil_status param_step(parser *p, gs_hil_step *st)
{
    const char *name = NULL;
    if (only(p, "a param step", "at name param value") != GS_HIL_OK || string(p, "param", 1, &name) != GS_HIL_OK ||
        number(p, "value", 1, &st->value) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (gs_hil_param_parse(p->s->block, name, &st->param, &st->element) != 0) {
        char list[160];
        size_t used = 0;
        unsigned n = gs_hil_param_count(p->s->block);
        list[0] = '\0';
        for (unsigned i = 0; i < n && used + 1u < sizeof list; ++i) {
            int w = snprintf(list + used, sizeof list - used, "%s%s", i ? " " : "", gs_hil_param_key(p->s->block, i));
            used += w > 0 ? (size_t)w : 0u;
        }
        return fail(p, line_of(p, "param"), "param",
                    "'%s' is no tunable parameter of this rig (key, key[i] or key[i][j] of: %s%s)", name, list,
                    used + 1u >= sizeof list ? " ..." : "");
    }
    st->line = line_of(p, "value"); /* where a value the rig refuses is named */
    return GS_HIL_OK;
}

static gs_hil_status load_step(parser *p, gs_hil_step *st)
{
    int given = 0;
    if (only(p, "a load step", "at name load over") != GS_HIL_OK || number(p, "load", 1, &st->value) != GS_HIL_OK ||
        time_after(p, "over", st->at_s, &st->over_s, &given) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    return GS_HIL_OK;
}

static gs_hil_status step_table(parser *p)
{
    gs_hil_scenario *s = p->s;
    static const char *const actions[] = {"load", "param", "fault", "expect"};
    int action = -1;
    for (int i = 0; i < 4; ++i) {
        if (find(p, actions[i]) != NULL) {
            if (action >= 0) {
                return fail(p, line_of(p, actions[i]), actions[i], "one action per step: this one has %s too",
                            actions[action]);
            }
            action = i;
        }
    }
    if (action < 0) {
        return fail(p, p->t.line, "[[step]]", "needs one of load, param, fault, expect");
    }
    if (s->step_count == GS_HIL_SCENARIO_MAX_STEPS) {
        return fail(p, p->t.line, "[[step]]", "more than %d steps", GS_HIL_SCENARIO_MAX_STEPS);
    }
    gs_hil_step *st = &s->steps[s->step_count];
    memset(st, 0, sizeof *st);
    st->line = p->t.line;
    st->kind = (gs_hil_step_kind)action;
    const char *name = NULL;
    if (number(p, "at", 1, &st->at_s) != GS_HIL_OK || string(p, "name", 0, &name) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!(st->at_s >= 0.0)) {
        return fail(p, line_of(p, "at"), "at", "a time >= 0 s");
    }
    snprintf(st->name, sizeof st->name, "%.127s", name != NULL ? name : "");
    gs_hil_status r = action == 0   ? load_step(p, st)
                      : action == 1 ? param_step(p, st)
                      : action == 2 ? fault_step(p, st)
                                    : expect_step(p, st);
    if (r != GS_HIL_OK) {
        return r;
    }
    if (st->at_s >= p->last_at) {
        p->last_at = st->at_s;
        p->last_at_line = line_of(p, "at");
    }
    s->step_count++;
    return GS_HIL_OK;
}

static gs_hil_status close_table(parser *p)
{
    switch (p->t.kind) {
    case TABLE_SCENARIO:
        return scenario_table(p);
    case TABLE_STEP:
        return step_table(p);
    case TABLE_NONE:
    default:
        return GS_HIL_OK;
    }
}

/* Steps by time, file order among equal times (insertion sort: stable). */
static void sort_steps(gs_hil_scenario *s)
{
    for (unsigned i = 1; i < s->step_count; ++i) {
        gs_hil_step key = s->steps[i];
        unsigned j = i;
        while (j > 0u && s->steps[j - 1u].at_s > key.at_s) {
            s->steps[j] = s->steps[j - 1u];
            --j;
        }
        s->steps[j] = key;
    }
}

gs_hil_status gs_hil_scenario_parse(gs_hil_scenario *s, const char *text, size_t length, const char *file,
                                    const gs_hil_dbc *dbc, gs_rig_block block, gs_hil_error *err)
{
    static const gs_hil_error none = {NULL, ""};
    gs_hil_error local = none;
    parser p;
    memset(&p, 0, sizeof p);
    memset(s, 0, sizeof *s);
    p.s = s;
    p.err = err != NULL ? err : &local;
    const char *shown = file != NULL ? file : "scenario";
    size_t n = 0;
    while (n + 1u < sizeof s->file && shown[n] != '\0') {
        ++n;
    }
    memmove(s->file, shown, n); /* a name longer than the field is cut */
    s->file[n] = '\0';
    s->dbc = dbc;
    s->block = block;
    s->seed = 1;
    if (dbc == NULL || text == NULL) {
        return fail(&p, 0, "scenario", "no text or no DBC");
    }
    unsigned line = 0;
    const char *c = text, *end = text + length;
    while (c < end) {
        const char *eol = memchr(c, '\n', (size_t)(end - c));
        const char *stop = eol != NULL ? eol : end;
        ++line;
        if (memchr(c, '\0', (size_t)(stop - c)) != NULL) {
            return fail(&p, line, "text", "a NUL byte: not a text file");
        }
        if (one_line(&p, line, c, stop) != GS_HIL_OK) {
            return GS_HIL_E_CONFIG;
        }
        c = eol != NULL ? eol + 1 : end;
    }
    if (close_table(&p) != GS_HIL_OK) {
        return GS_HIL_E_CONFIG;
    }
    if (!p.have_duration) {
        return fail(&p, line > 0u ? line : 1u, "[scenario]",
                    "missing: a scenario starts with [scenario] and its duration");
    }
    if (p.last_at > s->duration_s) {
        return fail(&p, p.last_at_line, "at", "%g s is after the scenario's duration (%g s)", p.last_at, s->duration_s);
    }
    sort_steps(s);
    return GS_HIL_OK;
}
