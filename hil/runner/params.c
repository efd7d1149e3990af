/*
 * Parser of the runner's parameter file: one `key = value` per line, `#`
 * comments, keys named after the C parameter structs (block.<field>,
 * block.backlash.<field>, rig.<field>), options by their C enumerator name,
 * tables as whitespace-separated numbers. Unset keys keep the C defaults.
 * Strict: unknown or repeated keys, bad numbers and unknown options are
 * errors naming the file, line and key.
 */
#define _POSIX_C_SOURCE 200809L
#include "params.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef enum { KIND_REAL, KIND_INT, KIND_ENUM, KIND_REALS } field_kind;

typedef struct {
    const char *name;
    int value;
} enum_option;

typedef struct {
    const char *key;
    field_kind kind;
    size_t offset;
    size_t count;                /* KIND_REALS: capacity */
    const enum_option *options;  /* KIND_ENUM: NULL-terminated */
} field_spec;

#define OPTION(name) {#name, name}
static const enum_option rotation_options[] = {OPTION(GS_ROTATES_SAME), OPTION(GS_ROTATES_OPPOSITE), {NULL, 0}};
static const enum_option friction_options[] = {
    OPTION(GS_FRICTION_NONE), OPTION(GS_FRICTION_CONSTANT_EFFICIENCY),
    OPTION(GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY), OPTION(GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY),
    OPTION(GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY), {NULL, 0}};
static const enum_option smoothing_options[] = {OPTION(GS_SMOOTHING_PASSIVE), OPTION(GS_SMOOTHING_SIMSCAPE), {NULL, 0}};
static const enum_option hard_stop_options[] = {OPTION(GS_HARD_STOP_SMOOTH), OPTION(GS_HARD_STOP_FULL_UNDAMPED),
                                                OPTION(GS_HARD_STOP_FULL_DAMPED), {NULL, 0}};
static const enum_option parameterization_options[] = {OPTION(GS_PARAMETERIZE_PINION_RADIUS),
                                                       OPTION(GS_PARAMETERIZE_TOOTH_PARAMETERS), {NULL, 0}};
static const enum_option direction_options[] = {OPTION(GS_RACK_POSITIVE), OPTION(GS_RACK_NEGATIVE), {NULL, 0}};
static const enum_option drive_options[] = {OPTION(GS_BASE_SPEED_DRIVEN), OPTION(GS_BASE_TORQUE_DRIVEN), {NULL, 0}};
static const enum_option temperature_options[] = {OPTION(GS_TEMPERATURE_FROM_MODEL), {NULL, 0}};

#define REAL(prefix, type, member) {prefix #member, KIND_REAL, offsetof(type, member), 1, NULL}
#define INT(prefix, type, member) {prefix #member, KIND_INT, offsetof(type, member), 1, NULL}
#define ENUM(prefix, type, member, options) {prefix #member, KIND_ENUM, offsetof(type, member), 1, options}
#define REALS(prefix, type, member, n) {prefix #member, KIND_REALS, offsetof(type, member), n, NULL}

#define BACKLASH_FIELDS(type)                                                      \
    INT("block.", type, backlash.enabled),                                         \
    ENUM("block.", type, backlash.hard_stop_model, hard_stop_options),             \
    REAL("block.", type, backlash.linear_backlash_m),                              \
    REAL("block.", type, backlash.base_radius_m),                                  \
    REAL("block.", type, backlash.transition_region_m),                            \
    REAL("block.", type, backlash.stiffness_N_m),                                  \
    REAL("block.", type, backlash.damping_N_s_m),                                  \
    REAL("block.", type, backlash.initial_position_m),                             \
    INT("block.", type, backlash.no_pull),                                         \
    INT("block.", type, backlash.lock_enabled),                                    \
    REAL("block.", type, backlash.contact_speed_threshold_m_s),                    \
    REAL("block.", type, backlash.contact_release_force_N)

static const field_spec gear_fields[] = {
    REAL("block.", gs_simple_gear_params, teeth_ratio),
    ENUM("block.", gs_simple_gear_params, output_shaft_rotates, rotation_options),
    ENUM("block.", gs_simple_gear_params, friction_model, friction_options),
    ENUM("block.", gs_simple_gear_params, loss_smoothing, smoothing_options),
    REAL("block.", gs_simple_gear_params, efficiency_const),
    REAL("block.", gs_simple_gear_params, power_threshold_W),
    REAL("block.", gs_simple_gear_params, idle_torque_Nm),
    REAL("block.", gs_simple_gear_params, nominal_output_torque_Nm),
    REAL("block.", gs_simple_gear_params, efficiency_nominal),
    REAL("block.", gs_simple_gear_params, speed_threshold_rad_s),
    INT("block.", gs_simple_gear_params, temperature_count),
    REALS("block.", gs_simple_gear_params, temperature_vector_K, GS_TABLE_MAX),
    REALS("block.", gs_simple_gear_params, efficiency_vector, GS_TABLE_MAX),
    INT("block.", gs_simple_gear_params, load_count),
    REALS("block.", gs_simple_gear_params, load_vector_Nm, GS_TABLE_MAX),
    REALS("block.", gs_simple_gear_params, efficiency_matrix, GS_TABLE_MAX * GS_TABLE_MAX),
    BACKLASH_FIELDS(gs_simple_gear_params),
    REALS("block.", gs_simple_gear_params, viscous_coefficients, 2),
    REAL("block.", gs_simple_gear_params, thermal_mass_J_K),
    REAL("block.", gs_simple_gear_params, initial_temperature_K),
};

static const field_spec rack_fields[] = {
    ENUM("block.", gs_rack_pinion_params, parameterization, parameterization_options),
    REAL("block.", gs_rack_pinion_params, pinion_radius_m),
    REAL("block.", gs_rack_pinion_params, teeth_count),
    REAL("block.", gs_rack_pinion_params, spacing_m),
    ENUM("block.", gs_rack_pinion_params, rack_directionality, direction_options),
    ENUM("block.", gs_rack_pinion_params, friction_model, friction_options),
    ENUM("block.", gs_rack_pinion_params, loss_smoothing, smoothing_options),
    REAL("block.", gs_rack_pinion_params, efficiency_const),
    INT("block.", gs_rack_pinion_params, temperature_count),
    REALS("block.", gs_rack_pinion_params, temperature_vector_K, GS_TABLE_MAX),
    REALS("block.", gs_rack_pinion_params, efficiency_vector, GS_TABLE_MAX),
    REAL("block.", gs_rack_pinion_params, power_threshold_W),
    REAL("block.", gs_rack_pinion_params, pinion_viscous_coefficient),
    REAL("block.", gs_rack_pinion_params, rack_viscous_coefficient),
    REAL("block.", gs_rack_pinion_params, thermal_mass_J_K),
    REAL("block.", gs_rack_pinion_params, initial_temperature_K),
    BACKLASH_FIELDS(gs_rack_pinion_params),
};

/* dt_s is not here: the runner sets it from --period / --substeps. */
static const field_spec rig_fields[] = {
    ENUM("rig.", gs_rig_params, base_drive, drive_options),
    REAL("rig.", gs_rig_params, base_inertia_kg_m2),
    REAL("rig.", gs_rig_params, initial_base_speed_rad_s),
    REAL("rig.", gs_rig_params, driven_inertia),
    REAL("rig.", gs_rig_params, load_coulomb_friction),
    REAL("rig.", gs_rig_params, load_coulomb_speed_threshold),
    REAL("rig.", gs_rig_params, load_offset),
    INT("rig.", gs_rig_params, heat_path),
    REAL("rig.", gs_rig_params, thermal_resistance_K_W),
    ENUM("rig.", gs_rig_params, temperature_source, temperature_options),
    REAL("rig.", gs_rig_params, accel_filter_time_constant_s),
    INT("rig.", gs_rig_params, contact_substeps),
    REAL("rig.", gs_rig_params, load_breakaway_friction),
    REAL("rig.", gs_rig_params, load_stribeck_speed),
    REAL("rig.", gs_rig_params, compliance_stiffness_Nm_rad),
    REAL("rig.", gs_rig_params, compliance_damping_Nm_s_rad),
    REALS("rig.", gs_rig_params, ripple_revolution_amplitude_Nm, GS_RIPPLE_HARMONICS),
    REALS("rig.", gs_rig_params, ripple_revolution_phase_rad, GS_RIPPLE_HARMONICS),
    REALS("rig.", gs_rig_params, ripple_mesh_amplitude_Nm, GS_RIPPLE_HARMONICS),
    REALS("rig.", gs_rig_params, ripple_mesh_phase_rad, GS_RIPPLE_HARMONICS),
    INT("rig.", gs_rig_params, ripple_mesh_teeth),
    INT("rig.", gs_rig_params, load_friction_regularised),
    INT("rig.", gs_rig_params, base_speed_ramp),
};

static const field_spec run_fields[] = {
    REAL("run.", runner_params, ambient_temperature_K),
};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))
#define MAX_FIELDS 64

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

static int set_field(const parse_context *ctx, const field_spec *f, char *value, void *base)
{
    char *where = (char *)base + f->offset;
    double x = 0.0;
    if (f->kind == KIND_REAL) {
        if (parse_real(value, &x) != 0) {
            return parse_error(ctx, f->key, "not a finite number");
        }
        *(gs_real *)(void *)where = (gs_real)x;
        return 0;
    }
    if (f->kind == KIND_INT) {
        char *end = NULL;
        errno = 0;
        long n = strtol(value, &end, 10);
        if (end == value || *end != '\0' || errno != 0 || n < -1000000 || n > 1000000) {
            return parse_error(ctx, f->key, "not an integer");
        }
        *(int *)(void *)where = (int)n;
        return 0;
    }
    if (f->kind == KIND_ENUM) {
        for (const enum_option *o = f->options; o->name != NULL; ++o) {
            if (strcmp(o->name, value) == 0) {
                memcpy(where, &o->value, sizeof o->value); /* the C enums here are int-sized */
                return 0;
            }
        }
        char what[256];
        int used = snprintf(what, sizeof what, "unknown option '%.60s'; one of", value);
        for (const enum_option *o = f->options; o->name != NULL && used > 0 && (size_t)used < sizeof what; ++o) {
            used += snprintf(what + used, sizeof what - (size_t)used, " %s", o->name);
        }
        return parse_error(ctx, f->key, what);
    }
    size_t n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(value, " \t", &save); tok != NULL; tok = strtok_r(NULL, " \t", &save)) {
        if (n == f->count) {
            char what[80];
            snprintf(what, sizeof what, "more than %zu numbers", f->count);
            return parse_error(ctx, f->key, what);
        }
        if (parse_real(tok, &x) != 0) {
            return parse_error(ctx, f->key, "not a list of finite numbers");
        }
        ((gs_real *)(void *)where)[n++] = (gs_real)x;
    }
    return n == 0 ? parse_error(ctx, f->key, "no value") : 0;
}

static const field_spec *find_field(const field_spec *fields, size_t n, const char *key, size_t *index)
{
    for (size_t i = 0; i < n; ++i) {
        if (strcmp(fields[i].key, key) == 0) {
            *index = i;
            return &fields[i];
        }
    }
    return NULL;
}

typedef struct {
    int block_seen;
    unsigned char seen[4][MAX_FIELDS]; /* block, rig, run: no key twice */
} parse_state;

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
        st->block_seen = 1;
        return 0;
    }
    const field_spec *fields = NULL;
    size_t n = 0;
    void *base = NULL;
    int group = 0;
    if (strncmp(key, "block.", 6) == 0) {
        if (!st->block_seen) {
            return parse_error(ctx, key, "comes before the 'block = simple_gear|rack_pinion' line");
        }
        int gear = out->block == GS_RIG_SIMPLE_GEAR;
        fields = gear ? gear_fields : rack_fields;
        n = gear ? COUNT(gear_fields) : COUNT(rack_fields);
        base = gear ? (void *)&out->gear : (void *)&out->rack;
    } else if (strncmp(key, "rig.", 4) == 0) {
        if (strcmp(key, "rig.dt_s") == 0) {
            return parse_error(ctx, key, "the step is set by --period and --substeps, not in the file");
        }
        fields = rig_fields, n = COUNT(rig_fields), base = &out->rig, group = 1;
    } else if (strncmp(key, "run.", 4) == 0) {
        fields = run_fields, n = COUNT(run_fields), base = out, group = 2;
    }
    size_t index = 0;
    const field_spec *f = fields != NULL ? find_field(fields, n, key, &index) : NULL;
    if (f == NULL) {
        return parse_error(ctx, key, "unknown key (gearsim-hil --list-params lists them)");
    }
    if (st->seen[group][index]) {
        return parse_error(ctx, key, "given twice");
    }
    st->seen[group][index] = 1;
    return set_field(ctx, f, value, base);
}

int runner_params_load(const char *path, runner_params *out, char *message, size_t message_size)
{
    parse_context ctx = {path, 0, message, message_size};
    parse_state st;
    memset(&st, 0, sizeof st);
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

static void list_fields(FILE *stream, const char *block, const field_spec *fields, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        fprintf(stream, "%s %s\n", block, fields[i].key);
    }
}

void runner_params_list(FILE *stream)
{
    list_fields(stream, "simple_gear", gear_fields, COUNT(gear_fields));
    list_fields(stream, "rack_pinion", rack_fields, COUNT(rack_fields));
    list_fields(stream, "rig", rig_fields, COUNT(rig_fields));
    list_fields(stream, "run", run_fields, COUNT(run_fields));
}
