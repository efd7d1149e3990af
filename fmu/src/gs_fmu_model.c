/* gs_fmu_model.c - the FMI variables of the rig FMUs (see gs_fmu_model.h).
 *
 * Every variable comes from a table of the library: the inputs and outputs
 * from gs_rig_input_info / gs_rig_output_info (gearsim/fields.h), the
 * parameters from gs_rig_param_info and the block's gs_*_param_info
 * (gearsim/parameters.h): name (the program name of docs/physics.md sections
 * 9-11 and of the Python package, the rack rig's where it differs), unit,
 * description, option list and whether it is tunable. Nothing of a parameter
 * is written here. Tables are scalarised with the "structured" naming
 * convention (temperature_vector[1], efficiency_matrix[2,3], 1-based), their
 * used length set by temperature_count / load_count. */
#include <stdio.h>
#include <string.h>

#include "gs_fmu_model.h"

/* Enum parameters are stored as int in the C structs (an FMU is built for a
 * host ABI, where enums are int-sized). */
typedef char
    gs_fmu_enum_size_check_[(sizeof(gs_friction_model) == sizeof(int) && sizeof(gs_loss_smoothing) == sizeof(int) &&
                             sizeof(gs_hard_stop_model) == sizeof(int) && sizeof(gs_output_rotation) == sizeof(int) &&
                             sizeof(gs_rack_parameterization) == sizeof(int) &&
                             sizeof(gs_rack_direction) == sizeof(int) && sizeof(gs_base_drive) == sizeof(int) &&
                             sizeof(gs_temperature_source) == sizeof(int))
                                ? 1
                                : -1];

/* ---- units: SI base-unit exponents (kg, m, s, K, rad) */

static const gs_fmu_unit units[] = {
    {"s", 0, 0, 1, 0, 0, NULL, 1.0, 0.0},
    {"rad", 0, 0, 0, 0, 1, "deg", 57.29577951308232, 0.0},
    {"rad/s", 0, 0, -1, 0, 1, "rpm", 9.549296585513721, 0.0},
    {"rad/s2", 0, 0, -2, 0, 1, NULL, 1.0, 0.0},
    {"m", 0, 1, 0, 0, 0, "mm", 1000.0, 0.0},
    {"m/s", 0, 1, -1, 0, 0, NULL, 1.0, 0.0},
    {"m/s2", 0, 1, -2, 0, 0, NULL, 1.0, 0.0},
    {"N", 1, 1, -2, 0, 0, NULL, 1.0, 0.0},
    {"N.m", 1, 2, -2, 0, 0, NULL, 1.0, 0.0},
    {"N/m", 1, 0, -2, 0, 0, NULL, 1.0, 0.0},
    {"N.s/m", 1, 0, -1, 0, 0, NULL, 1.0, 0.0},
    {"N.m.s/rad", 1, 2, -1, 0, -1, NULL, 1.0, 0.0},
    {"N.m/rad", 1, 2, -2, 0, -1, NULL, 1.0, 0.0},
    {"kg", 1, 0, 0, 0, 0, NULL, 1.0, 0.0},
    {"kg.m2", 1, 2, 0, 0, 0, NULL, 1.0, 0.0},
    {"K", 0, 0, 0, 1, 0, "degC", 1.0, -273.15},
    {"W", 1, 2, -3, 0, 0, NULL, 1.0, 0.0},
    {"J", 1, 2, -2, 0, 0, NULL, 1.0, 0.0},
    {"J/K", 1, 2, -2, -1, 0, NULL, 1.0, 0.0},
    {"K/W", -1, -2, 3, 1, 0, NULL, 1.0, 0.0},
};

const gs_fmu_unit *gs_fmu_units(size_t *count)
{
    *count = sizeof units / sizeof units[0];
    return units;
}

/* The library's units are written as pint parses them; FMI writes products
 * with '.' and powers without an operator: "N*m*s/rad" is "N.m.s/rad",
 * "kg*m**2" is "kg.m2", "rad/s^2" is "rad/s2". */
const char *gs_fmu_unit_from_table(const char *table_unit, int *known)
{
    if (known != NULL) {
        *known = 1;
    }
    if (table_unit == NULL || table_unit[0] == '\0' || strcmp(table_unit, "1") == 0) {
        return NULL;
    }
    char fmi[GS_FMU_NAME_SIZE];
    size_t n = 0;
    for (const char *c = table_unit; *c != '\0' && n + 1 < sizeof fmi; ++c) {
        if (c[0] == '*' && c[1] == '*') {
            ++c; /* "**": the power follows */
        } else if (*c == '*') {
            fmi[n++] = '.';
        } else if (*c != '^') {
            fmi[n++] = *c;
        }
    }
    fmi[n] = '\0';
    for (size_t i = 0; i < sizeof units / sizeof units[0]; ++i) {
        if (strcmp(fmi, units[i].name) == 0) {
            return units[i].name;
        }
    }
    if (known != NULL) {
        *known = 0;
    }
    return NULL;
}

/* ---- variables */

typedef struct {
    gs_fmu_var *vars;
    size_t n;
    size_t capacity;
    int rack;
    int failed; /* capacity exceeded, or a unit without an FMI definition */
} var_list;

static gs_fmu_var *next_var(var_list *l)
{
    if (l->n >= l->capacity) {
        l->failed = 1;
        return NULL;
    }
    gs_fmu_var *v = &l->vars[l->n++];
    memset(v, 0, sizeof *v);
    return v;
}

static const char *fmi_unit(var_list *l, const char *table_unit)
{
    int known;
    const char *unit = gs_fmu_unit_from_table(table_unit, &known);
    if (!known) {
        l->failed = 1;
    }
    return unit;
}

/* Inputs or outputs: one Real per entry of a field table; the inputs' names
 * under GS_FMU_INPUT_PREFIX. */
static void add_io(var_list *l, const gs_field_info *table, size_t count, gs_fmu_causality causality,
                   gs_fmu_region region, const char *prefix)
{
    for (size_t i = 0; i < count && !l->failed; ++i) {
        const gs_field_info *f = &table[i];
        gs_fmu_var *v = next_var(l);
        if (v == NULL) {
            return;
        }
        (void)snprintf(v->name, sizeof v->name, "%s%s", prefix, f->name);
        v->base_name = f->name;
        v->type = GS_FMU_T_REAL;
        v->causality = causality;
        v->variability = GS_FMU_V_CONTINUOUS;
        v->region = region;
        v->storage = GS_FMU_S_REAL;
        v->offset = f->offset;
        v->unit = fmi_unit(l, l->rack ? f->rack_unit : f->gear_unit);
        v->description = f->doc;
    }
}

static gs_fmu_type fmi_type(gs_param_kind kind)
{
    switch (kind) {
    case GS_PARAM_INT:
    case GS_PARAM_COUNT:
        return GS_FMU_T_INTEGER;
    case GS_PARAM_BOOL:
        return GS_FMU_T_BOOLEAN;
    case GS_PARAM_OPTION:
        return GS_FMU_T_ENUMERATION;
    case GS_PARAM_REAL:
    case GS_PARAM_ARRAY:
    case GS_PARAM_TABLE:
    case GS_PARAM_MATRIX:
    case GS_PARAM_GROUP:
        break;
    }
    return GS_FMU_T_REAL;
}

/* One parameter: a scalar, or one variable per element of an array, table
 * or matrix. base is the offset of its struct in gs_fmu_params. */
static void add_param(var_list *l, const gs_param_info *e, size_t base)
{
    const char *name = l->rack ? e->rack_key : e->key;
    const gs_fmu_type type = fmi_type(e->kind);
    const int indexed = e->kind == GS_PARAM_ARRAY || e->kind == GS_PARAM_TABLE || e->kind == GS_PARAM_MATRIX;
    const size_t element = e->size / (e->length * e->columns);
    for (size_t i = 0; i < e->length; ++i) {
        for (size_t j = 0; j < e->columns; ++j) {
            gs_fmu_var *v = next_var(l);
            if (v == NULL) {
                return;
            }
            if (e->kind == GS_PARAM_MATRIX) {
                (void)snprintf(v->name, sizeof v->name, "%s[%zu,%zu]", name, i + 1, j + 1);
            } else if (indexed) {
                (void)snprintf(v->name, sizeof v->name, "%s[%zu]", name, i + 1);
            } else {
                (void)snprintf(v->name, sizeof v->name, "%s", name);
            }
            v->base_name = name;
            v->type = type;
            v->causality = GS_FMU_C_PARAMETER;
            v->variability = e->flags == GS_PARAM_TUNABLE ? GS_FMU_V_TUNABLE : GS_FMU_V_FIXED;
            v->region = GS_FMU_AT_PARAMS;
            v->storage = type == GS_FMU_T_REAL ? GS_FMU_S_REAL : GS_FMU_S_INT;
            v->offset = base + e->offset + (i * e->columns + j) * element;
            v->unit = type == GS_FMU_T_REAL ? fmi_unit(l, l->rack ? e->rack_unit : e->gear_unit) : NULL;
            v->options = type == GS_FMU_T_ENUMERATION ? e->options : NULL;
            v->enum_type = v->options != NULL ? v->options->name : NULL;
            v->description = e->doc;
        }
    }
}

/* The parameters of a table, nested groups after the table's own (so that
 * the backlash follows the block's parameters); GEAR_ONLY entries are left
 * out of the rack rig. */
static void add_params(var_list *l, const gs_param_info *table, size_t count, size_t base)
{
    for (size_t i = 0; i < count && !l->failed; ++i) {
        const gs_param_info *e = &table[i];
        if (e->kind != GS_PARAM_GROUP && !(l->rack && e->flags == GS_PARAM_GEAR_ONLY)) {
            add_param(l, e, base);
        }
    }
    for (size_t i = 0; i < count && !l->failed; ++i) {
        if (table[i].kind == GS_PARAM_GROUP) {
            add_params(l, table[i].members, table[i].member_count, base + table[i].offset);
        }
    }
}

size_t gs_fmu_variables(gs_fmu_rig rig, gs_fmu_var *vars, size_t capacity)
{
    var_list l = {vars, 0, capacity, rig == GS_FMU_RIG_RACK, 0};
    add_io(&l, gs_rig_input_info, GS_RIG_INPUT_FIELDS, GS_FMU_C_INPUT, GS_FMU_AT_INPUT, GS_FMU_INPUT_PREFIX);
    add_io(&l, gs_rig_output_info, GS_RIG_OUTPUT_FIELDS, GS_FMU_C_OUTPUT, GS_FMU_AT_OUTPUT, "");
    add_params(&l, gs_rig_param_info, GS_RIG_PARAM_FIELDS, offsetof(gs_fmu_params, rig));
    if (l.rack) {
        add_params(&l, gs_rack_pinion_param_info, GS_RACK_PINION_PARAM_FIELDS, offsetof(gs_fmu_params, rack));
    } else {
        add_params(&l, gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS, offsetof(gs_fmu_params, gear));
    }
    return l.failed ? 0 : l.n;
}

void gs_fmu_defaults(gs_fmu_params *params, gs_rig_input *input)
{
    memset(params, 0, sizeof *params);
    params->gear = gs_simple_gear_params_default();
    params->rack = gs_rack_pinion_params_default();
    params->rig = gs_rig_params_default();
    memset(input, 0, sizeof *input);
    input->ambient_temperature = GS_R(293.15);
    input->measured_temperature = GS_R(300.0);
}

gs_status gs_fmu_init_rig(gs_fmu_rig rig, const gs_fmu_params *params, gs_rig_consts *consts, gs_rig_state *state,
                          gs_error *err)
{
    return rig == GS_FMU_RIG_GEAR ? gs_rig_init_gear(consts, state, &params->gear, &params->rig, err)
                                  : gs_rig_init_rack(consts, state, &params->rack, &params->rig, err);
}

double gs_fmu_read_real(const gs_fmu_var *v, const void *base)
{
    const unsigned char *p = (const unsigned char *)base + v->offset;
    if (v->storage == GS_FMU_S_REAL) {
        gs_real x;
        memcpy(&x, p, sizeof x);
        return (double)x;
    }
    int i;
    memcpy(&i, p, sizeof i);
    return (double)i;
}

void gs_fmu_write_real(const gs_fmu_var *v, void *base, double value)
{
    unsigned char *p = (unsigned char *)base + v->offset;
    const gs_real x = (gs_real)value;
    memcpy(p, &x, sizeof x);
}

int gs_fmu_read_int(const gs_fmu_var *v, const void *base)
{
    int i;
    memcpy(&i, (const unsigned char *)base + v->offset, sizeof i);
    return i;
}

void gs_fmu_write_int(const gs_fmu_var *v, void *base, int value)
{
    memcpy((unsigned char *)base + v->offset, &value, sizeof value);
}

const char *gs_fmu_type_name(gs_fmu_type type)
{
    switch (type) {
    case GS_FMU_T_REAL:
        return "Real";
    case GS_FMU_T_INTEGER:
        return "Integer";
    case GS_FMU_T_BOOLEAN:
        return "Boolean";
    case GS_FMU_T_ENUMERATION:
        return "Enumeration";
    }
    return "?";
}

const char *gs_fmu_model_identifier(gs_fmu_rig rig)
{
    return rig == GS_FMU_RIG_GEAR ? "gearsim_gear_rig" : "gearsim_rack_rig";
}

const char *gs_fmu_model_name(gs_fmu_rig rig)
{
    return rig == GS_FMU_RIG_GEAR ? "gearsim.GearRig" : "gearsim.RackRig";
}

const char *gs_fmu_model_description(gs_fmu_rig rig)
{
    return rig == GS_FMU_RIG_GEAR
               ? "gearsim Simple Gear between a speed- or torque-driven base shaft and a follower inertia "
                 "(fixed-step C rig, docs/physics.md section 11)"
               : "gearsim Rack & Pinion between a speed- or torque-driven pinion shaft and a rack mass "
                 "(fixed-step C rig, docs/physics.md section 11)";
}

/* ---- GUID: FNV-1a over the variable table and the start values */

static unsigned long long fnv(unsigned long long h, const void *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    for (size_t i = 0; i < n; ++i) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static unsigned long long fnv_str(unsigned long long h, const char *s)
{
    return fnv(h, s != NULL ? s : "", s != NULL ? strlen(s) + 1 : 1);
}

void gs_fmu_guid(gs_fmu_rig rig, char guid[GS_FMU_GUID_SIZE])
{
    static const char version[] = GS_VERSION_STRING " fmu-1";
    gs_fmu_var vars[GS_FMU_MAX_VARS];
    gs_fmu_params params;
    gs_rig_input input;
    gs_fmu_defaults(&params, &input);
    const size_t n = gs_fmu_variables(rig, vars, GS_FMU_MAX_VARS);
    unsigned long long h[2] = {14695981039346656037ULL, 0x9e3779b97f4a7c15ULL};
    for (int k = 0; k < 2; ++k) {
        h[k] = fnv_str(h[k], gs_fmu_model_identifier(rig));
        h[k] = fnv_str(h[k], version);
        for (size_t i = 0; i < n; ++i) {
            const gs_fmu_var *v = &vars[i];
            const int kind[4] = {(int)v->type, (int)v->causality, (int)v->variability, (int)v->storage};
            h[k] = fnv_str(h[k], v->name);
            h[k] = fnv_str(h[k], v->unit);
            h[k] = fnv_str(h[k], v->enum_type);
            h[k] = fnv(h[k], kind, sizeof kind);
            if (v->causality != GS_FMU_C_OUTPUT) {
                const double start =
                    gs_fmu_read_real(v, v->region == GS_FMU_AT_PARAMS ? (const void *)&params : (const void *)&input);
                h[k] = fnv(h[k], &start, sizeof start);
            }
        }
        h[k] = fnv(h[k], &k, sizeof k);
    }
    memset(guid, 0, GS_FMU_GUID_SIZE); /* all GS_FMU_GUID_SIZE bytes are compared and serialized */
    (void)snprintf(guid, GS_FMU_GUID_SIZE, "{%08llx-%04llx-%04llx-%04llx-%012llx}", (h[0] >> 32) & 0xffffffffULL,
                   (h[0] >> 16) & 0xffffULL, h[0] & 0xffffULL, (h[1] >> 48) & 0xffffULL, h[1] & 0xffffffffffffULL);
}
