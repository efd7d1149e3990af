/*
 * Parser of the runner's parameter file: one `key = value` per line, `#`
 * comments. The keys are the members of the C parameter structs
 * (block.<member>, block.backlash.<member>, rig.<member>) and the options
 * their C enumerators; both are read from the library's parameter tables
 * (gs_*_param_info, expanded from gearsim/parameters.h), so a parameter of
 * the core is a key here without a line of this file. Tables are
 * whitespace-separated numbers. Unset keys keep the C defaults. Strict:
 * unknown or repeated keys, bad numbers and unknown options are errors
 * naming the file, line and key.
 *
 * Two rules are the runner's own: the step (rig.dt_s) comes from --period
 * and --substeps, and the temperature is never a CAN input, so
 * rig.temperature_source takes GS_TEMPERATURE_FROM_MODEL only. The runner
 * adds one key of its own, run.ambient_temperature_K.
 */
#define _POSIX_C_SOURCE 200809L
#include "params.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define KEY_SIZE   80
#define MAX_FIELDS 96

/* The runner's own key: the ambient and measured temperature inputs. */
static const gs_param_options no_options = {"", NULL, 0};
static const gs_param_info run_info[] = {
    {"ambient_temperature", "ambient_temperature", "ambient_temperature_K", "K", "K",
     "ambient and measured temperature inputs (> 0)", GS_PARAM_REAL, GS_PARAM_FIXED,
     offsetof(runner_params, ambient_temperature_K), sizeof(gs_real), 1, 1, "", "", NULL, 0, &no_options},
};

enum { GROUP_BLOCK = 0, GROUP_RIG = 1, GROUP_RUN = 2 };

/* One key of the file: a leaf of a parameter table, flattened. */
typedef struct {
    char key[KEY_SIZE];
    const gs_param_info *info;
    int group;     /* which struct of runner_params it lives in */
    size_t offset; /* byte offset in that struct */
} field;

typedef struct {
    field fields[MAX_FIELDS];
    size_t count;
} field_list;

/* The step is the runner's: --period / --substeps, never the file. */
static const char step_key[] = "rig.dt_s";

/* Appends the leaves of table under prefix; nested groups become
 * prefix.member.<leaf>. Returns -1 if the list or a key is too small (the
 * tables are static: a build that trips this needs larger limits). */
static int add_fields(field_list *list, const char *prefix, const gs_param_info *table, size_t count, int group,
                      size_t base)
{
    for (size_t i = 0; i < count; ++i) {
        const gs_param_info *e = &table[i];
        char key[KEY_SIZE];
        const int used = snprintf(key, sizeof key, "%s%s", prefix, e->member);
        if (used < 0 || (size_t)used + 2 > sizeof key) {
            return -1;
        }
        if (e->kind == GS_PARAM_GROUP) {
            key[used] = '.';
            key[used + 1] = '\0';
            if (add_fields(list, key, e->members, e->member_count, group, base + e->offset) != 0) {
                return -1;
            }
            continue;
        }
        if (strcmp(key, step_key) == 0) {
            continue;
        }
        if (list->count == MAX_FIELDS) {
            return -1;
        }
        field *f = &list->fields[list->count++];
        memcpy(f->key, key, sizeof key);
        f->info = e;
        f->group = group;
        f->offset = base + e->offset;
    }
    return 0;
}

/* The keys that do not depend on the block: rig.* and run.* (run.* lives in
 * runner_params itself: its offsets are absolute). */
static int common_fields(field_list *list)
{
    list->count = 0;
    if (add_fields(list, "rig.", gs_rig_param_info, GS_RIG_PARAM_FIELDS, GROUP_RIG, 0) != 0) {
        return -1;
    }
    return add_fields(list, "run.", run_info, sizeof run_info / sizeof run_info[0], GROUP_RUN, 0);
}

/* Appends the block.* keys of one block. */
static int block_fields(field_list *list, gs_rig_block block)
{
    const int gear = block == GS_RIG_SIMPLE_GEAR;
    return add_fields(list, "block.", gear ? gs_simple_gear_param_info : gs_rack_pinion_param_info,
                      gear ? (size_t)GS_SIMPLE_GEAR_PARAM_FIELDS : (size_t)GS_RACK_PINION_PARAM_FIELDS, GROUP_BLOCK, 0);
}

typedef struct {
    const char *path;
    unsigned line;
    char *message;
    size_t size;
} parse_context;

static int parse_error(const parse_context *ctx, const char *key, const char *what)
{
    snprintf(ctx->message, ctx->size, "%s:%u: %s%s%s", ctx->path, ctx->line, key, *key ? ": " : "", what);
    return -1;
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t') {
        ++s;
    }
    char *end = s + strlen(s);
    while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r' || end[-1] == '\n')) {
        *--end = '\0';
    }
    return s;
}

static int parse_real(const char *text, double *value)
{
    char *end = NULL;
    errno = 0;
    *value = strtod(text, &end);
    return end != text && *end == '\0' && errno == 0 && isfinite(*value) ? 0 : -1;
}

/* Stores an int or enum value in a member of size bytes (enums may be
 * narrower than int on some ABIs). */
static void store_int(unsigned char *where, size_t size, int value)
{
    if (size == sizeof(int)) {
        memcpy(where, &value, sizeof value);
    } else if (size == sizeof(short)) {
        const short narrow = (short)value;
        memcpy(where, &narrow, sizeof narrow);
    } else {
        *where = (unsigned char)value;
    }
}

static int set_integer(const parse_context *ctx, const field *f, const char *value, unsigned char *where)
{
    char *end = NULL;
    errno = 0;
    long n = strtol(value, &end, 10);
    if (end == value || *end != '\0' || errno != 0 || n < -1000000 || n > 1000000) {
        return parse_error(ctx, f->key, "not an integer");
    }
    store_int(where, f->info->size, (int)n);
    return 0;
}

static int set_option(const parse_context *ctx, const field *f, const char *value, unsigned char *where)
{
    const gs_param_options *o = f->info->options;
    for (size_t k = 0; k < o->count; ++k) {
        if (strcmp(o->items[k].enumerator, value) == 0) {
            if (strcmp(f->key, "rig.temperature_source") == 0 && o->items[k].value != GS_TEMPERATURE_FROM_MODEL) {
                return parse_error(ctx, f->key, "the temperature is never a CAN input: only GS_TEMPERATURE_FROM_MODEL");
            }
            store_int(where, f->info->size, o->items[k].value);
            return 0;
        }
    }
    char what[320];
    int used = snprintf(what, sizeof what, "unknown option '%.60s'; one of", value);
    for (size_t k = 0; k < o->count && used > 0 && (size_t)used < sizeof what; ++k) {
        used += snprintf(what + used, sizeof what - (size_t)used, " %s", o->items[k].enumerator);
    }
    return parse_error(ctx, f->key, what);
}

static int set_reals(const parse_context *ctx, const field *f, char *value, unsigned char *where)
{
    const size_t capacity = f->info->length * f->info->columns;
    size_t n = 0;
    double x = 0.0;
    char *save = NULL;
    for (char *tok = strtok_r(value, " \t", &save); tok != NULL; tok = strtok_r(NULL, " \t", &save)) {
        if (n == capacity) {
            char what[80];
            snprintf(what, sizeof what, "more than %zu numbers", capacity);
            return parse_error(ctx, f->key, what);
        }
        if (parse_real(tok, &x) != 0) {
            return parse_error(ctx, f->key, capacity > 1 ? "not a list of finite numbers" : "not a finite number");
        }
        const gs_real r = (gs_real)x;
        memcpy(where + n * sizeof r, &r, sizeof r);
        ++n;
    }
    return n == 0 ? parse_error(ctx, f->key, "no value") : 0;
}

static int set_field(const parse_context *ctx, const field *f, char *value, unsigned char *where)
{
    switch (f->info->kind) {
    case GS_PARAM_OPTION:
        return set_option(ctx, f, value, where);
    case GS_PARAM_BOOL:
        return f->info->options->count > 0 ? set_option(ctx, f, value, where) : set_integer(ctx, f, value, where);
    case GS_PARAM_INT:
    case GS_PARAM_COUNT:
        return set_integer(ctx, f, value, where);
    case GS_PARAM_REAL:
    case GS_PARAM_ARRAY:
    case GS_PARAM_TABLE:
    case GS_PARAM_MATRIX:
        return set_reals(ctx, f, value, where);
    case GS_PARAM_GROUP:
        break; /* flattened by add_fields */
    }
    return parse_error(ctx, f->key, "not a value");
}

typedef struct {
    int block_seen;
    field_list keys;
    unsigned char seen[MAX_FIELDS]; /* no key twice */
} parse_state;

static unsigned char *group_base(runner_params *out, int group)
{
    switch (group) {
    case GROUP_BLOCK:
        return out->block == GS_RIG_SIMPLE_GEAR ? (unsigned char *)&out->gear : (unsigned char *)&out->rack;
    case GROUP_RIG:
        return (unsigned char *)&out->rig;
    default:
        return (unsigned char *)out;
    }
}

static int parse_block_line(parse_context *ctx, parse_state *st, const char *key, const char *value, runner_params *out)
{
    if (st->block_seen) {
        return parse_error(ctx, key, "given twice");
    }
    if (strcmp(value, "simple_gear") == 0) {
        out->block = GS_RIG_SIMPLE_GEAR;
    } else if (strcmp(value, "rack_pinion") == 0) {
        out->block = GS_RIG_RACK_PINION;
    } else {
        return parse_error(ctx, key, "must be simple_gear or rack_pinion");
    }
    if (block_fields(&st->keys, out->block) != 0) {
        return parse_error(ctx, key, "internal: the parameter tables exceed the parser's limits");
    }
    st->block_seen = 1;
    return 0;
}

static int parse_line(parse_context *ctx, parse_state *st, char *line, runner_params *out)
{
    char *hash = strchr(line, '#');
    if (hash != NULL) {
        *hash = '\0';
    }
    char *text = trim(line);
    if (*text == '\0') {
        return 0;
    }
    char *eq = strchr(text, '=');
    if (eq == NULL) {
        return parse_error(ctx, "", "expected 'key = value'");
    }
    *eq = '\0';
    char *key = trim(text);
    char *value = trim(eq + 1);
    if (*value == '\0') {
        return parse_error(ctx, key, "no value");
    }
    if (strcmp(key, "block") == 0) {
        return parse_block_line(ctx, st, key, value, out);
    }
    if (strcmp(key, step_key) == 0) {
        return parse_error(ctx, key, "the step is set by --period and --substeps, not in the file");
    }
    if (!st->block_seen && strncmp(key, "block.", 6) == 0) {
        return parse_error(ctx, key, "comes before the 'block = simple_gear|rack_pinion' line");
    }
    for (size_t i = 0; i < st->keys.count; ++i) {
        const field *f = &st->keys.fields[i];
        if (strcmp(f->key, key) == 0) {
            if (st->seen[i]) {
                return parse_error(ctx, key, "given twice");
            }
            st->seen[i] = 1;
            return set_field(ctx, f, value, group_base(out, f->group) + f->offset);
        }
    }
    return parse_error(ctx, key, "unknown key (gearsim-hil --list-params lists them)");
}

int runner_params_load(const char *path, runner_params *out, char *message, size_t message_size)
{
    parse_context ctx = {path, 0, message, message_size};
    static parse_state st; /* a few kB: not on the stack */
    memset(&st, 0, sizeof st);
    if (common_fields(&st.keys) != 0) {
        snprintf(message, message_size, "%s: internal: the parameter tables exceed the parser's limits", path);
        return -1;
    }
    memset(out, 0, sizeof *out);
    out->gear = gs_simple_gear_params_default();
    out->rack = gs_rack_pinion_params_default();
    out->rig = gs_rig_params_default();
    out->ambient_temperature_K = (gs_real)293.15;
    FILE *fh = fopen(path, "r");
    if (fh == NULL) {
        snprintf(message, message_size, "%s: cannot open the parameter file: %s", path, strerror(errno));
        return -1;
    }
    char line[4096];
    int rc = 0;
    while (rc == 0 && fgets(line, sizeof line, fh) != NULL) {
        ctx.line++;
        if (strchr(line, '\n') == NULL && !feof(fh)) {
            rc = parse_error(&ctx, "", "line longer than 4095 characters");
            break;
        }
        rc = parse_line(&ctx, &st, line, out);
    }
    if (rc == 0 && ferror(fh)) {
        snprintf(message, message_size, "%s: read error", path);
        rc = -1;
    }
    fclose(fh);
    if (rc == 0 && !st.block_seen) {
        snprintf(message, message_size, "%s: no 'block = simple_gear|rack_pinion' line", path);
        rc = -1;
    }
    return rc;
}

void runner_params_list(FILE *stream)
{
    static field_list list;
    static const struct {
        gs_rig_block block;
        const char *name;
    } blocks[] = {{GS_RIG_SIMPLE_GEAR, "simple_gear"}, {GS_RIG_RACK_PINION, "rack_pinion"}};
    for (size_t b = 0; b < sizeof blocks / sizeof blocks[0]; ++b) {
        list.count = 0;
        if (block_fields(&list, blocks[b].block) != 0) {
            return;
        }
        for (size_t i = 0; i < list.count; ++i) {
            fprintf(stream, "%s %s\n", blocks[b].name, list.fields[i].key);
        }
    }
    if (common_fields(&list) != 0) {
        return;
    }
    for (size_t i = 0; i < list.count; ++i) {
        fprintf(stream, "%s %s\n", list.fields[i].group == GROUP_RIG ? "rig" : "run", list.fields[i].key);
    }
}
