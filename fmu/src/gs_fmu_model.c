/* gs_fmu_model.c - the FMI variable tables of the rig FMUs (see gs_fmu_model.h).
 *
 * Names are the program names of docs/physics.md sections 9-11 and of
 * docs/python-api.md; tables are scalarised with the "structured" naming
 * convention (temperature_vector[1], efficiency_matrix[2,3], 1-based), their
 * used length set by temperature_count / load_count. The inputs and outputs
 * come from gearsim/fields.h: the same names as the C structs, the Python
 * package and the firmware columns. */
#include <stdio.h>
#include <string.h>

#include "gs_fmu_model.h"

/* Enum parameters are stored as int in the C structs. */
typedef char gs_fmu_enum_size_check_[(sizeof(gs_friction_model) == sizeof(int) &&
                                      sizeof(gs_loss_smoothing) == sizeof(int) &&
                                      sizeof(gs_hard_stop_model) == sizeof(int) &&
                                      sizeof(gs_output_rotation) == sizeof(int) &&
                                      sizeof(gs_rack_parameterization) == sizeof(int) &&
                                      sizeof(gs_rack_direction) == sizeof(int) &&
                                      sizeof(gs_base_drive) == sizeof(int) &&
                                      sizeof(gs_temperature_source) == sizeof(int))
                                         ? 1
                                         : -1];

/* Every input and output is a gs_real (gearsim/rig.h): the tables below store
 * them as GS_FMU_S_REAL. */
typedef char gs_fmu_io_real_check_[(sizeof(gs_rig_input) == GS_RIG_INPUT_FIELDS * sizeof(gs_real) &&
                                    sizeof(gs_rig_output) == GS_RIG_OUTPUT_FIELDS * sizeof(gs_real))
                                       ? 1
                                       : -1];

/* ---- enumeration types (values are the C enum values) */

static const gs_fmu_enum_item output_shaft_rotates_items[] = {
    {"same", GS_ROTATES_SAME, "follower turns with the base (s = +1)"},
    {"opposite", GS_ROTATES_OPPOSITE, "follower turns against the base (s = -1)"},
};
static const gs_fmu_enum_item gear_friction_items[] = {
    {"none", GS_FRICTION_NONE, "no meshing losses"},
    {"constant_efficiency", GS_FRICTION_CONSTANT_EFFICIENCY, "constant efficiency"},
    {"load_dependent_efficiency", GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY,
     "idle torque plus load-proportional Coulomb torque"},
    {"temperature_dependent_efficiency", GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY,
     "efficiency table over temperature"},
    {"temperature_load_dependent_efficiency", GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY,
     "efficiency table over temperature and base load"},
};
static const gs_fmu_enum_item rack_friction_items[] = {
    {"none", GS_FRICTION_NONE, "no meshing losses"},
    {"constant_efficiency", GS_FRICTION_CONSTANT_EFFICIENCY, "constant efficiency"},
    {"temperature_dependent_efficiency", GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY,
     "efficiency table over temperature"},
};
static const gs_fmu_enum_item loss_smoothing_items[] = {
    {"passive", GS_SMOOTHING_PASSIVE, "never produces negative loss power"},
    {"simscape", GS_SMOOTHING_SIMSCAPE, "eq. 2.1 as published (slightly active near zero power)"},
};
static const gs_fmu_enum_item hard_stop_items[] = {
    {"smooth", GS_HARD_STOP_SMOOTH, "stiffness and damping through the transition region, damped rebound"},
    {"full_undamped", GS_HARD_STOP_FULL_UNDAMPED, "full stiffness and damping at bounds, undamped rebound"},
    {"full_damped", GS_HARD_STOP_FULL_DAMPED, "full stiffness and damping at bounds, damped rebound"},
};
static const gs_fmu_enum_item parameterization_items[] = {
    {"pinion_radius", GS_PARAMETERIZE_PINION_RADIUS, "r_P = pinion_radius"},
    {"tooth_parameters", GS_PARAMETERIZE_TOOTH_PARAMETERS, "r_P = teeth_count*spacing/(2*pi)"},
};
static const gs_fmu_enum_item rack_direction_items[] = {
    {"positive", GS_RACK_POSITIVE, "positive pinion rotation moves the rack in + (s_R = +1)"},
    {"negative", GS_RACK_NEGATIVE, "positive pinion rotation moves the rack in - (s_R = -1)"},
};
static const gs_fmu_enum_item base_drive_items[] = {
    {"speed", GS_BASE_SPEED_DRIVEN,
     "input " GS_FMU_INPUT_PREFIX "base_speed is held; output base_torque is what the drive applies"},
    {"torque", GS_BASE_TORQUE_DRIVEN,
     "input " GS_FMU_INPUT_PREFIX "base_torque acts on base_inertia; speeds are outputs"},
};

#define GS_FMU_COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const gs_fmu_enum_type enum_types[] = {
    {"OutputShaftRotates", "Simple Gear output shaft direction", output_shaft_rotates_items,
     GS_FMU_COUNT(output_shaft_rotates_items)},
    {"FrictionModel", "Simple Gear meshing-loss model", gear_friction_items,
     GS_FMU_COUNT(gear_friction_items)},
    {"RackFrictionModel", "Rack & Pinion meshing-loss model", rack_friction_items,
     GS_FMU_COUNT(rack_friction_items)},
    {"LossSmoothing", "power-threshold smoothing of the efficiency laws", loss_smoothing_items,
     GS_FMU_COUNT(loss_smoothing_items)},
    {"HardStopModel", "backlash hard-stop contact law", hard_stop_items, GS_FMU_COUNT(hard_stop_items)},
    {"Parameterization", "how the pinion radius is given", parameterization_items,
     GS_FMU_COUNT(parameterization_items)},
    {"RackDirectionality", "rack direction for positive pinion rotation", rack_direction_items,
     GS_FMU_COUNT(rack_direction_items)},
    {"BaseDrive", "how the base (pinion) shaft is driven", base_drive_items, GS_FMU_COUNT(base_drive_items)},
};

const gs_fmu_enum_type *gs_fmu_enum_types(size_t *count)
{
    *count = sizeof enum_types / sizeof enum_types[0];
    return enum_types;
}

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

/* The units of gearsim/fields.h are written as pint parses them; FMI writes
 * products with '.' and powers without '^'. The spellings that differ: */
static const struct {
    const char *table;
    const char *fmi;
} unit_spellings[] = {
    {"N*m", "N.m"},
    {"rad/s^2", "rad/s2"},
    {"m/s^2", "m/s2"},
};

const char *gs_fmu_unit_from_table(const char *table_unit, int *known)
{
    if (known != NULL) {
        *known = 1;
    }
    if (table_unit == NULL || table_unit[0] == '\0' || strcmp(table_unit, "1") == 0) {
        return NULL;
    }
    const char *fmi = table_unit;
    for (size_t i = 0; i < sizeof unit_spellings / sizeof unit_spellings[0]; ++i) {
        if (strcmp(table_unit, unit_spellings[i].table) == 0) {
            fmi = unit_spellings[i].fmi;
        }
    }
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

/* ---- variable tables */

/* Which rig an entry belongs to. */
enum { BOTH = 0, GEAR_ONLY = 1, RACK_ONLY = 2 };

typedef struct {
    const char *name;
    gs_fmu_type type;
    gs_fmu_variability variability;
    gs_fmu_storage storage;
    size_t offset;          /* in the group's struct */
    int n1, n2;             /* array extents, 0 = scalar */
    size_t stride1, stride2;
    const char *unit;
    const char *enum_type;
    const char *description;
    int only;
    /* the rack rig's name, unit and description where they differ (NULL = same) */
    const char *rack_name;
    const char *rack_unit;
    const char *rack_description;
    /* 1: unit and rack_unit are units of gearsim/fields.h (pint syntax),
     * translated by gs_fmu_unit_from_table */
    int table_units;
} entry;

#define REAL_(T, nm, fld, var, un, desc) \
    {.name = nm, .type = GS_FMU_T_REAL, .variability = var, .storage = GS_FMU_S_REAL, \
     .offset = offsetof(T, fld), .unit = un, .description = desc}
#define VEC_(T, nm, fld, var, un, desc) \
    {.name = nm, .type = GS_FMU_T_REAL, .variability = var, .storage = GS_FMU_S_REAL, \
     .offset = offsetof(T, fld), .n1 = GS_TABLE_MAX, .stride1 = sizeof(gs_real), .unit = un, \
     .description = desc}
#define ENUM_(T, nm, fld, etype, desc) \
    {.name = nm, .type = GS_FMU_T_ENUMERATION, .variability = GS_FMU_V_FIXED, .storage = GS_FMU_S_INT, \
     .offset = offsetof(T, fld), .enum_type = etype, .description = desc}
#define BOOL_(T, nm, fld, desc) \
    {.name = nm, .type = GS_FMU_T_BOOLEAN, .variability = GS_FMU_V_FIXED, .storage = GS_FMU_S_INT, \
     .offset = offsetof(T, fld), .description = desc}
#define INT_(T, nm, fld, desc) \
    {.name = nm, .type = GS_FMU_T_INTEGER, .variability = GS_FMU_V_FIXED, .storage = GS_FMU_S_INT, \
     .offset = offsetof(T, fld), .description = desc}

#define FIXED GS_FMU_V_FIXED
#define TUNABLE GS_FMU_V_TUNABLE
#define CONT GS_FMU_V_CONTINUOUS

static const entry rig_entries[] = {
    REAL_(gs_rig_params, "dt", dt_s, FIXED, "s",
          "fixed internal step; every communication step must be a whole multiple of it"),
    ENUM_(gs_rig_params, "base_drive", base_drive, "BaseDrive",
          "base (pinion) shaft: speed-driven (" GS_FMU_INPUT_PREFIX "base_speed) or torque-driven ("
          GS_FMU_INPUT_PREFIX "base_torque)"),
    REAL_(gs_rig_params, "base_inertia", base_inertia_kg_m2, FIXED, "kg.m2",
          "base (pinion) shaft inertia: > 0 when torque-driven; speed-driven adds base_inertia*alpha to base_torque"),
    REAL_(gs_rig_params, "initial_base_speed", initial_base_speed_rad_s, FIXED, "rad/s",
          "torque-driven: base speed at the start"),
    {.name = "follower_inertia", .type = GS_FMU_T_REAL, .variability = FIXED, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_rig_params, driven_inertia), .unit = "kg.m2",
     .description = "inertia on the follower shaft (> 0)", .rack_name = "rack_mass", .rack_unit = "kg",
     .rack_description = "mass moved with the rack (> 0)"},
    {.name = "load_coulomb_friction", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, load_coulomb_friction), .unit = "N.m",
     .description = "constant Coulomb friction torque on the follower, opposing motion (>= 0)",
     .rack_unit = "N", .rack_description = "constant Coulomb friction force on the rack, opposing motion (>= 0)"},
    {.name = "load_coulomb_speed_threshold", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, load_coulomb_speed_threshold),
     .unit = "rad/s", .description = "speed scale of the tanh(4 w/w_th) smoothing of load_coulomb_friction (> 0)",
     .rack_unit = "m/s"},
    {.name = "load_offset", .type = GS_FMU_T_REAL, .variability = TUNABLE, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_rig_params, load_offset), .unit = "N.m",
     .description = "constant torque on the follower (gravity, cable drag)", .rack_unit = "N",
     .rack_description = "constant force on the rack (gravity on an inclined axis, cable drag)"},
    BOOL_(gs_rig_params, "heat_path", heat_path,
          "true: heat flows to " GS_FMU_INPUT_PREFIX
          "ambient_temperature through thermal_resistance; false: adiabatic"),
    REAL_(gs_rig_params, "thermal_resistance", thermal_resistance_K_W, TUNABLE, "K/W",
          "housing-to-ambient thermal resistance R_th (> 0 when heat_path)"),
    BOOL_(gs_rig_params, "temperature_input", temperature_source,
          "true: temperature-dependent losses use " GS_FMU_INPUT_PREFIX
          "measured_temperature instead of the thermal state"),
    REAL_(gs_rig_params, "accel_filter_time_constant", accel_filter_time_constant_s, FIXED, "s",
          "speed-driven: first-order low-pass on the base acceleration (0 = raw backward difference)"),
    INT_(gs_rig_params, "contact_substeps", contact_substeps,
         "backlash: contact sub-steps per internal step, 1..64, 0 = chosen at initialisation"),
    /* Stribeck friction: tunable like the Coulomb level it rises from */
    {.name = "load_breakaway_friction", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, load_breakaway_friction), .unit = "N.m",
     .description = "Stribeck: friction torque on the follower at rest (0 = none, else >= load_coulomb_friction)",
     .rack_unit = "N",
     .rack_description = "Stribeck: friction force on the rack at rest (0 = none, else >= load_coulomb_friction)"},
    {.name = "load_stribeck_speed", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, load_stribeck_speed), .unit = "rad/s",
     .description = "Stribeck speed v_S: F_C + (F_brk - F_C)*exp(-(v/v_S)^2) (> 0)", .rack_unit = "m/s"},
    /* Compliance changes the rig's degrees of freedom: fixed */
    REAL_(gs_rig_params, "compliance_stiffness", compliance_stiffness_Nm_rad, FIXED, "N.m/rad",
          "torsional stiffness of the base shaft, drive to base gear (0 = rigid; speed-driven base, "
          "no backlash; with base_inertia 0 the spring acts at the mesh)"),
    REAL_(gs_rig_params, "compliance_damping", compliance_damping_Nm_s_rad, FIXED, "N.m.s/rad",
          "torsional damping of the base shaft (>= 0)"),
    /* Torque ripple on the base side: sum A_i*cos(i*theta_B + phi_i) + sum M_j*cos(j*Z*theta_B + psi_j) */
    {.name = "ripple_revolution_amplitude", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, ripple_revolution_amplitude_Nm),
     .n1 = GS_RIPPLE_HARMONICS, .stride1 = sizeof(gs_real), .unit = "N.m",
     .description = "base-side ripple amplitude A_i of harmonic i per revolution (>= 0)"},
    {.name = "ripple_revolution_phase", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, ripple_revolution_phase_rad),
     .n1 = GS_RIPPLE_HARMONICS, .stride1 = sizeof(gs_real), .unit = "rad",
     .description = "phase phi_i of the per-revolution ripple harmonic i"},
    {.name = "ripple_mesh_amplitude", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, ripple_mesh_amplitude_Nm),
     .n1 = GS_RIPPLE_HARMONICS, .stride1 = sizeof(gs_real), .unit = "N.m",
     .description = "base-side ripple amplitude M_j of harmonic j per tooth mesh (>= 0)"},
    {.name = "ripple_mesh_phase", .type = GS_FMU_T_REAL, .variability = TUNABLE,
     .storage = GS_FMU_S_REAL, .offset = offsetof(gs_rig_params, ripple_mesh_phase_rad),
     .n1 = GS_RIPPLE_HARMONICS, .stride1 = sizeof(gs_real), .unit = "rad",
     .description = "phase psi_j of the per-tooth ripple harmonic j"},
    {.name = "ripple_mesh_teeth", .type = GS_FMU_T_INTEGER, .variability = FIXED, .storage = GS_FMU_S_INT,
     .offset = offsetof(gs_rig_params, ripple_mesh_teeth),
     .description = "teeth Z of the base gear per revolution (>= 1 when a ripple_mesh_amplitude > 0)",
     .rack_description = "teeth Z of the pinion per revolution (>= 1 when a ripple_mesh_amplitude > 0)"},
    BOOL_(gs_rig_params, "load_friction_regularised", load_friction_regularised,
          "true: a freely moving driven side's friction is F*tanh(4 v/load_coulomb_speed_threshold) "
          "(it creeps, no stiction); false: the set-valued Coulomb law"),
    BOOL_(gs_rig_params, "base_speed_ramp", base_speed_ramp,
          "speed-driven rigid mesh, true: the speed terms at the step's mean speed (the inputs' linear ramp)"),
};

static const entry gear_entries[] = {
    REAL_(gs_simple_gear_params, "teeth_ratio", teeth_ratio, FIXED, NULL,
          "follower-to-base teeth ratio N_F/N_B (> 0)"),
    ENUM_(gs_simple_gear_params, "output_shaft_rotates", output_shaft_rotates, "OutputShaftRotates",
          "output shaft rotates in the same or opposite direction"),
    ENUM_(gs_simple_gear_params, "friction_model", friction_model, "FrictionModel", "meshing-loss model"),
    ENUM_(gs_simple_gear_params, "loss_smoothing", loss_smoothing, "LossSmoothing",
          "power-threshold smoothing of the efficiency laws"),
    REAL_(gs_simple_gear_params, "efficiency_const", efficiency_const, TUNABLE, NULL,
          "constant efficiency, 0 < eta <= 1"),
    REAL_(gs_simple_gear_params, "power_threshold", power_threshold_W, TUNABLE, "W",
          "follower power threshold of the efficiency smoothing (> 0)"),
    REAL_(gs_simple_gear_params, "idle_torque", idle_torque_Nm, TUNABLE, "N.m",
          "input shaft torque at no load (>= 0)"),
    REAL_(gs_simple_gear_params, "nominal_output_torque", nominal_output_torque_Nm, TUNABLE, "N.m",
          "nominal output torque (> 0)"),
    REAL_(gs_simple_gear_params, "efficiency_nominal", efficiency_nominal, TUNABLE, NULL,
          "efficiency at the nominal output torque, 0 < eta < 1"),
    REAL_(gs_simple_gear_params, "speed_threshold", speed_threshold_rad_s, TUNABLE, "rad/s",
          "follower angular velocity threshold of the load-dependent loss (> 0)"),
    INT_(gs_simple_gear_params, "temperature_count", temperature_count,
         "entries used in temperature_vector, efficiency_vector and the rows of efficiency_matrix (2..10)"),
    VEC_(gs_simple_gear_params, "temperature_vector", temperature_vector_K, TUNABLE, "K",
         "temperature breakpoints, strictly increasing"),
    VEC_(gs_simple_gear_params, "efficiency_vector", efficiency_vector, TUNABLE, NULL,
         "efficiency at each temperature, in (0, 1]"),
    INT_(gs_simple_gear_params, "load_count", load_count,
         "entries used in load_vector and the columns of efficiency_matrix (2..10)"),
    VEC_(gs_simple_gear_params, "load_vector", load_vector_Nm, TUNABLE, "N.m",
         "base-gear load breakpoints, >= 0, strictly increasing"),
    {.name = "efficiency_matrix", .type = GS_FMU_T_REAL, .variability = TUNABLE, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_simple_gear_params, efficiency_matrix), .n1 = GS_TABLE_MAX, .n2 = GS_TABLE_MAX,
     .stride1 = sizeof(gs_real[GS_TABLE_MAX]), .stride2 = sizeof(gs_real),
     .description = "efficiency [temperature row, load column], in (0, 1]"},
    {.name = "viscous_coefficients", .type = GS_FMU_T_REAL, .variability = TUNABLE, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_simple_gear_params, viscous_coefficients), .n1 = 2, .stride1 = sizeof(gs_real),
     .unit = "N.m.s/rad", .description = "viscous coefficients [base, follower] (>= 0)"},
    REAL_(gs_simple_gear_params, "thermal_mass", thermal_mass_J_K, TUNABLE, "J/K",
          "thermal mass (> 0; temperature-dependent models)"),
    REAL_(gs_simple_gear_params, "initial_temperature", initial_temperature_K, FIXED, "K",
          "initial temperature (> 0)"),
};

static const entry rack_entries[] = {
    ENUM_(gs_rack_pinion_params, "parameterization", parameterization, "Parameterization",
          "pinion radius given directly or by tooth parameters"),
    REAL_(gs_rack_pinion_params, "pinion_radius", pinion_radius_m, FIXED, "m", "pinion radius (> 0)"),
    REAL_(gs_rack_pinion_params, "teeth_count", teeth_count, FIXED, NULL, "number of pinion teeth (> 0)"),
    REAL_(gs_rack_pinion_params, "spacing", spacing_m, FIXED, "m", "rack tooth spacing (> 0)"),
    ENUM_(gs_rack_pinion_params, "rack_directionality", rack_directionality, "RackDirectionality",
          "rack direction for positive pinion rotation"),
    ENUM_(gs_rack_pinion_params, "friction_model", friction_model, "RackFrictionModel", "meshing-loss model"),
    ENUM_(gs_rack_pinion_params, "loss_smoothing", loss_smoothing, "LossSmoothing",
          "power-threshold smoothing of the efficiency laws"),
    REAL_(gs_rack_pinion_params, "efficiency_const", efficiency_const, TUNABLE, NULL,
          "constant efficiency, 0 < eta <= 1"),
    INT_(gs_rack_pinion_params, "temperature_count", temperature_count,
         "entries used in temperature_vector and efficiency_vector (2..10)"),
    VEC_(gs_rack_pinion_params, "temperature_vector", temperature_vector_K, TUNABLE, "K",
         "temperature breakpoints, strictly increasing"),
    VEC_(gs_rack_pinion_params, "efficiency_vector", efficiency_vector, TUNABLE, NULL,
         "efficiency at each temperature, in (0, 1]"),
    REAL_(gs_rack_pinion_params, "power_threshold", power_threshold_W, TUNABLE, "W",
          "rack power threshold of the efficiency smoothing (> 0)"),
    REAL_(gs_rack_pinion_params, "pinion_viscous_coefficient", pinion_viscous_coefficient, TUNABLE,
          "N.m.s/rad", "pinion viscous coefficient (>= 0)"),
    REAL_(gs_rack_pinion_params, "rack_viscous_coefficient", rack_viscous_coefficient, TUNABLE, "N.s/m",
          "rack viscous coefficient (>= 0)"),
    REAL_(gs_rack_pinion_params, "thermal_mass", thermal_mass_J_K, TUNABLE, "J/K",
          "thermal mass (> 0; temperature-dependent model)"),
    REAL_(gs_rack_pinion_params, "initial_temperature", initial_temperature_K, FIXED, "K",
          "initial temperature (> 0)"),
};

static const entry backlash_entries[] = {
    BOOL_(gs_backlash_params, "backlash_enabled", enabled, "enable backlash (false: rigid mesh)"),
    ENUM_(gs_backlash_params, "hard_stop_model", hard_stop_model, "HardStopModel", "hard-stop contact law"),
    {.name = "linear_backlash", .type = GS_FMU_T_REAL, .variability = FIXED, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_backlash_params, linear_backlash_m), .unit = "m",
     .description = "total free travel b at the pitch line (> 0)",
     .rack_description = "total free travel b along the rack (> 0)"},
    {.name = "base_radius", .type = GS_FMU_T_REAL, .variability = FIXED, .storage = GS_FMU_S_REAL,
     .offset = offsetof(gs_backlash_params, base_radius_m), .unit = "m",
     .description = "base gear pitch radius r_B (> 0)", .only = GEAR_ONLY},
    REAL_(gs_backlash_params, "transition_region", transition_region_m, FIXED, "m",
          "transition region d of the smooth model (> 0)"),
    REAL_(gs_backlash_params, "stiffness", stiffness_N_m, FIXED, "N/m", "contact stiffness K (> 0)"),
    REAL_(gs_backlash_params, "damping", damping_N_s_m, FIXED, "N.s/m", "contact damping D (>= 0)"),
    REAL_(gs_backlash_params, "initial_backlash_position", initial_position_m, FIXED, "m",
          "initial backlash position x0 in [-b/2, b/2]"),
    BOOL_(gs_backlash_params, "contact_no_pull", no_pull, "the contact force never pulls the teeth together"),
    BOOL_(gs_backlash_params, "contact_lock_enabled", lock_enabled, "static contact lock"),
    REAL_(gs_backlash_params, "contact_speed_threshold", contact_speed_threshold_m_s, FIXED, "m/s",
          "lock mode: static contact speed threshold (> 0)"),
    REAL_(gs_backlash_params, "contact_release_force", contact_release_force_N, FIXED, "N",
          "lock mode: static contact release force threshold (>= 0)"),
};

/* Inputs and outputs: one entry per field of gearsim/fields.h, in its order
 * (the inputs' names under GS_FMU_INPUT_PREFIX). */
#define IO_(strct, fmi_name, nm, gear_unit, rack_unit_, doc)                                                \
    {.name = fmi_name, .type = GS_FMU_T_REAL, .variability = CONT, .storage = GS_FMU_S_REAL,             \
     .offset = offsetof(strct, nm), .unit = gear_unit, .rack_unit = rack_unit_, .description = doc,       \
     .table_units = 1},
#define INPUT_(type, nm, gear_unit, rack_unit_, doc) \
    IO_(gs_rig_input, GS_FMU_INPUT_PREFIX #nm, nm, gear_unit, rack_unit_, doc)
#define OUTPUT_(type, nm, gear_unit, rack_unit_, doc) IO_(gs_rig_output, #nm, nm, gear_unit, rack_unit_, doc)

static const entry input_entries[] = {GS_RIG_INPUT_LIST(INPUT_)};
static const entry output_entries[] = {GS_RIG_OUTPUT_LIST(OUTPUT_)};

typedef struct {
    const entry *entries;
    size_t count;
    gs_fmu_causality causality;
    gs_fmu_region region;
    size_t base;  /* offset of the group's struct in its region */
} group;

static size_t expand(const group *g, gs_fmu_rig rig, gs_fmu_var *vars, size_t n, size_t capacity)
{
    for (size_t e = 0; e < g->count; ++e) {
        const entry *en = &g->entries[e];
        if ((en->only == GEAR_ONLY && rig != GS_FMU_RIG_GEAR) || (en->only == RACK_ONLY && rig != GS_FMU_RIG_RACK)) {
            continue;
        }
        const int rack = rig == GS_FMU_RIG_RACK;
        const char *name = rack && en->rack_name ? en->rack_name : en->name;
        const int n1 = en->n1 > 0 ? en->n1 : 1;
        const int n2 = en->n2 > 0 ? en->n2 : 1;
        for (int i = 0; i < n1; ++i) {
            for (int j = 0; j < n2; ++j) {
                if (n >= capacity) {
                    return 0;
                }
                gs_fmu_var *v = &vars[n++];
                memset(v, 0, sizeof *v);
                if (en->n2 > 0) {
                    (void)snprintf(v->name, sizeof v->name, "%s[%d,%d]", name, i + 1, j + 1);
                } else if (en->n1 > 0) {
                    (void)snprintf(v->name, sizeof v->name, "%s[%d]", name, i + 1);
                } else {
                    (void)snprintf(v->name, sizeof v->name, "%s", name);
                }
                v->base_name = name;
                v->type = en->type;
                v->causality = g->causality;
                v->variability = en->variability;
                v->region = g->region;
                v->storage = en->storage;
                v->offset = g->base + en->offset + (size_t)i * en->stride1 + (size_t)j * en->stride2;
                v->unit = rack && en->rack_unit ? en->rack_unit : en->unit;
                if (en->table_units) {
                    int known;
                    v->unit = gs_fmu_unit_from_table(v->unit, &known);
                    if (!known) {
                        return 0;
                    }
                }
                v->enum_type = en->enum_type;
                v->description = rack && en->rack_description ? en->rack_description : en->description;
            }
        }
    }
    return n;
}

size_t gs_fmu_variables(gs_fmu_rig rig, gs_fmu_var *vars, size_t capacity)
{
    const int gear = rig == GS_FMU_RIG_GEAR;
    const group groups[] = {
        {input_entries, sizeof input_entries / sizeof input_entries[0], GS_FMU_C_INPUT, GS_FMU_AT_INPUT, 0},
        {output_entries, sizeof output_entries / sizeof output_entries[0], GS_FMU_C_OUTPUT, GS_FMU_AT_OUTPUT, 0},
        {rig_entries, sizeof rig_entries / sizeof rig_entries[0], GS_FMU_C_PARAMETER, GS_FMU_AT_PARAMS,
         offsetof(gs_fmu_params, rig)},
        gear ? (group){gear_entries, sizeof gear_entries / sizeof gear_entries[0], GS_FMU_C_PARAMETER,
                       GS_FMU_AT_PARAMS, offsetof(gs_fmu_params, gear)}
             : (group){rack_entries, sizeof rack_entries / sizeof rack_entries[0], GS_FMU_C_PARAMETER,
                       GS_FMU_AT_PARAMS, offsetof(gs_fmu_params, rack)},
        {backlash_entries, sizeof backlash_entries / sizeof backlash_entries[0], GS_FMU_C_PARAMETER,
         GS_FMU_AT_PARAMS, gear ? offsetof(gs_fmu_params, gear.backlash) : offsetof(gs_fmu_params, rack.backlash)},
    };
    size_t n = 0;
    for (size_t g = 0; g < sizeof groups / sizeof groups[0]; ++g) {
        n = expand(&groups[g], rig, vars, n, capacity);
        if (n == 0) {
            return 0;
        }
    }
    return n;
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

gs_status gs_fmu_init_rig(gs_fmu_rig rig, const gs_fmu_params *params, gs_rig_consts *consts,
                          gs_rig_state *state, gs_error *err)
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
    case GS_FMU_T_REAL: return "Real";
    case GS_FMU_T_INTEGER: return "Integer";
    case GS_FMU_T_BOOLEAN: return "Boolean";
    case GS_FMU_T_ENUMERATION: return "Enumeration";
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
                const double start = gs_fmu_read_real(v, v->region == GS_FMU_AT_PARAMS ? (const void *)&params
                                                                                       : (const void *)&input);
                h[k] = fnv(h[k], &start, sizeof start);
            }
        }
        h[k] = fnv(h[k], &k, sizeof k);
    }
    memset(guid, 0, GS_FMU_GUID_SIZE); /* all GS_FMU_GUID_SIZE bytes are compared and serialized */
    (void)snprintf(guid, GS_FMU_GUID_SIZE, "{%08llx-%04llx-%04llx-%04llx-%012llx}",
                   (h[0] >> 32) & 0xffffffffULL, (h[0] >> 16) & 0xffffULL, h[0] & 0xffffULL,
                   (h[1] >> 48) & 0xffffULL, h[1] & 0xffffffffffffULL);
}
