/*
 * gs_fmu_model.h - the FMI variables of the gearsim rig FMUs.
 *
 * The variables of a rig (gear rig, rack rig) are expanded from the
 * library's tables: the inputs and outputs from gearsim/fields.h
 * (gs_rig_input_info, gs_rig_output_info: name, unit of each rig,
 * description), the inputs' names under GS_FMU_INPUT_PREFIX; the parameters
 * from gearsim/parameters.h (gs_rig_param_info and the block's table: name
 * in each rig, unit, description, option list, tunable or fixed). Units are
 * translated to FMI syntax by gs_fmu_unit_from_table. The FMU binary
 * (gs_fmu.c) reads and writes values through the variables; the generator
 * (gs_fmu_modeldescription.c) writes modelDescription.xml and the docs table
 * from them, with start values read from gs_*_params_default(), so the two
 * can never disagree. The value reference of a variable is its index.
 *
 * Internal to the FMU build: not part of the gearsim C API.
 */
#ifndef GS_FMU_MODEL_H
#define GS_FMU_MODEL_H

#include <stddef.h>

#include "gearsim/gearsim.h"

/* FMI names of the inputs: this prefix and the name of gearsim/fields.h
 * ("inputs.base_speed", a structured name). The outputs carry the table's
 * names as they are; an input cannot, because base_speed and base_torque are
 * both an input and an output of the rig and FMI variable names are unique. */
#define GS_FMU_INPUT_PREFIX "inputs."

#define GS_FMU_MAX_VARS  256
#define GS_FMU_NAME_SIZE 48
#define GS_FMU_GUID_SIZE 40 /* "{8-4-4-4-12}" plus the terminating NUL */

typedef enum { GS_FMU_RIG_GEAR = 0, GS_FMU_RIG_RACK = 1 } gs_fmu_rig;

typedef enum {
    GS_FMU_T_REAL = 0,
    GS_FMU_T_INTEGER = 1,
    GS_FMU_T_BOOLEAN = 2,
    GS_FMU_T_ENUMERATION = 3 /* set and read through fmi2SetInteger / fmi2GetInteger */
} gs_fmu_type;

typedef enum { GS_FMU_C_PARAMETER = 0, GS_FMU_C_INPUT = 1, GS_FMU_C_OUTPUT = 2 } gs_fmu_causality;

typedef enum { GS_FMU_V_FIXED = 0, GS_FMU_V_TUNABLE = 1, GS_FMU_V_CONTINUOUS = 2 } gs_fmu_variability;

/* Which struct holds the value. */
typedef enum { GS_FMU_AT_PARAMS = 0, GS_FMU_AT_INPUT = 1, GS_FMU_AT_OUTPUT = 2 } gs_fmu_region;

/* How the value is stored in C: a gs_real, or an int (also every C enum and
 * every C boolean flag of the params structs). */
typedef enum { GS_FMU_S_REAL = 0, GS_FMU_S_INT = 1 } gs_fmu_storage;

/* Every parameter of one FMU instance. Both blocks are present so that one
 * offset table serves both rigs; each rig uses its own block. */
typedef struct {
    gs_simple_gear_params gear;
    gs_rack_pinion_params rack;
    gs_rig_params rig;
} gs_fmu_params;

typedef struct {
    char name[GS_FMU_NAME_SIZE]; /* FMI name, e.g. "efficiency_matrix[2,3]" */
    const char *base_name;       /* without the index: the name gs_error.parameter uses */
    gs_fmu_type type;
    gs_fmu_causality causality;
    gs_fmu_variability variability;
    gs_fmu_region region;
    gs_fmu_storage storage;
    size_t offset;                   /* byte offset in gs_fmu_params / gs_rig_input / gs_rig_output */
    const char *unit;                /* a unit of gs_fmu_units(), or NULL when dimensionless */
    const char *enum_type;           /* GS_FMU_T_ENUMERATION: the name of its option list */
    const gs_param_options *options; /* GS_FMU_T_ENUMERATION: the option list (the type's items) */
    const char *description;
} gs_fmu_var;

/* SI base-unit exponents of an FMI unit definition, plus display units. */
typedef struct {
    const char *name;
    int kg, m, s, K, rad;
    const char *display_name; /* NULL or one display unit */
    double display_factor;
    double display_offset;
} gs_fmu_unit;

/* Fills vars (capacity >= GS_FMU_MAX_VARS) with the variables of a rig, in
 * value-reference order: inputs, outputs, the rig's parameters, the block's,
 * the block's backlash. Returns their count (0 if capacity is too small or a
 * unit of the library's tables has no FMI unit). */
size_t gs_fmu_variables(gs_fmu_rig rig, gs_fmu_var *vars, size_t capacity);

/* Start values: the C defaults of the block and rig, and the input starts. */
void gs_fmu_defaults(gs_fmu_params *params, gs_rig_input *input);

/* Validates params and initialises the rig's constants and state
 * (gs_rig_init_gear / _rack). */
gs_status gs_fmu_init_rig(gs_fmu_rig rig, const gs_fmu_params *params, gs_rig_consts *consts, gs_rig_state *state,
                          gs_error *err);

/* The FMI unit (a name of gs_fmu_units()) of a unit of the library's tables,
 * which are written as pint parses them ("N*m", "kg*m**2", "rad/s^2"); NULL
 * for the dimensionless "1" or "", and for a unit without an FMI definition
 * (*known = 0 then; known may be NULL). */
const char *gs_fmu_unit_from_table(const char *table_unit, int *known);

/* Value access. base is the gs_fmu_params, gs_rig_input or gs_rig_output the
 * variable's region names. */
double gs_fmu_read_real(const gs_fmu_var *v, const void *base);
void gs_fmu_write_real(const gs_fmu_var *v, void *base, double value);
int gs_fmu_read_int(const gs_fmu_var *v, const void *base);
void gs_fmu_write_int(const gs_fmu_var *v, void *base, int value);

/* "Real", "Integer", "Boolean" or "Enumeration": the FMI element name. */
const char *gs_fmu_type_name(gs_fmu_type type);

const char *gs_fmu_model_identifier(gs_fmu_rig rig);
const char *gs_fmu_model_name(gs_fmu_rig rig);
const char *gs_fmu_model_description(gs_fmu_rig rig);

/* A GUID derived from the variable table and the start values (the same
 * string in modelDescription.xml and in the binary). */
void gs_fmu_guid(gs_fmu_rig rig, char guid[GS_FMU_GUID_SIZE]);

const gs_fmu_unit *gs_fmu_units(size_t *count);

#endif /* GS_FMU_MODEL_H */
