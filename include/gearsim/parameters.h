/*
 * gearsim/parameters.h - the one table of the parameters of the blocks and
 * the rigs, and of their option lists.
 *
 * Each parameter is declared here once, as one line of an X-macro list. From
 * these lists come the params structs (gs_simple_gear_params,
 * gs_rack_pinion_params, gs_backlash_params, gs_rig_params), the option enums,
 * the run-time tables gs_*_param_info (which the Python package, the HIL
 * runner's parameter file and the FMUs read), so a name, unit or option is
 * written nowhere else. Defaults (gs_*_params_default) and validity rules
 * (gs_*_init) are code, in src/.
 *
 * Block lists (Simple Gear, Rack & Pinion, backlash):
 *   X(kind, type, member, count, key, unit, options, flags, doc)
 * Rig list (one struct for both rigs; the driven side is the follower shaft in
 * one and the rack in the other):
 *   X(kind, type, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc)
 *
 *   kind     REAL (gs_real), INT, BOOL (0/1, or a two-valued enum with
 *            options), OPTION (an enum with options), ARRAY (count gs_real),
 *            TABLE (GS_TABLE_MAX gs_real, used length in the member count),
 *            MATRIX (GS_TABLE_MAX x GS_TABLE_MAX gs_real, count is
 *            (rows' count member, columns' count member)), COUNT (the int
 *            holding a table's used length), GROUP (a nested params struct
 *            with a table of its own, gs_<member>_param_info);
 *   type     the C type of one element (gs_real, int, an enum, a struct);
 *   member   the C member;
 *   count    1 for scalars, the length of an ARRAY, the count member of a
 *            TABLE, (rows, columns) count members of a MATRIX;
 *   key      the program name (docs/physics.md section 9): Python keyword
 *            and model-file key, FMU variable, gs_error.parameter;
 *            rack_key the name in the Rack & Pinion rig;
 *   unit     the SI unit as pint parses it ("" = dimensionless or not a
 *            number); gear_unit / rack_unit in the two rigs;
 *   options  NONE, or the name of an option list GS_OPTIONS_<name> below
 *            (which is also the name of the FMU enumeration type);
 *   flags    FIXED, TUNABLE (may be changed between the steps of a running
 *            rig: FMU "tunable"), GEAR_ONLY (fixed, unused by the Rack &
 *            Pinion);
 *   doc      one line: meaning and valid range.
 *
 * Option lists: O(enumerator, name, doc) in enum order (values 0, 1, ...);
 * name is the string of Python, model files and FMU enumeration items, the
 * enumerator names the option in the HIL runner's parameter file.
 *
 * Adding a parameter: one line here, its default in gs_*_params_default()
 * and its rule in the init (CONTRIBUTING.md).
 */
#ifndef GEARSIM_PARAMETERS_H
#define GEARSIM_PARAMETERS_H

/* ---- option lists: O(enumerator, name, doc) */

#define GS_OPTIONS_OutputShaftRotates(O)                                \
    O(GS_ROTATES_SAME, "same", "follower turns with the base (s = +1)") \
    O(GS_ROTATES_OPPOSITE, "opposite", "follower turns against the base (s = -1)")

/* The meshing-loss models; the Rack & Pinion takes three of them. */
#define GS_OPTION_FRICTION_NONE_(O)     O(GS_FRICTION_NONE, "none", "no meshing losses")
#define GS_OPTION_FRICTION_CONSTANT_(O) O(GS_FRICTION_CONSTANT_EFFICIENCY, "constant_efficiency", "constant efficiency")
#define GS_OPTION_FRICTION_TEMPERATURE_(O)                                              \
    O(GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY, "temperature_dependent_efficiency", \
      "efficiency table over temperature")
#define GS_OPTIONS_FrictionModel(O)                                                               \
    GS_OPTION_FRICTION_NONE_(O)                                                                   \
    GS_OPTION_FRICTION_CONSTANT_(O)                                                               \
    O(GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY, "load_dependent_efficiency",                         \
      "idle torque plus load-proportional Coulomb torque")                                        \
    GS_OPTION_FRICTION_TEMPERATURE_(O)                                                            \
    O(GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY, "temperature_load_dependent_efficiency", \
      "efficiency table over temperature and base load")
#define GS_OPTIONS_RackFrictionModel(O) \
    GS_OPTION_FRICTION_NONE_(O) GS_OPTION_FRICTION_CONSTANT_(O) GS_OPTION_FRICTION_TEMPERATURE_(O)

#define GS_OPTIONS_LossSmoothing(O)                                          \
    O(GS_SMOOTHING_PASSIVE, "passive", "never produces negative loss power") \
    O(GS_SMOOTHING_SIMSCAPE, "simscape", "eq. 2.1 as published (slightly active near zero power)")

#define GS_OPTIONS_HardStopModel(O)                                                                          \
    O(GS_HARD_STOP_SMOOTH, "smooth", "stiffness and damping through the transition region, damped rebound")  \
    O(GS_HARD_STOP_FULL_UNDAMPED, "full_undamped", "full stiffness and damping at bounds, undamped rebound") \
    O(GS_HARD_STOP_FULL_DAMPED, "full_damped", "full stiffness and damping at bounds, damped rebound")

#define GS_OPTIONS_Parameterization(O)                                       \
    O(GS_PARAMETERIZE_PINION_RADIUS, "pinion_radius", "r_P = pinion_radius") \
    O(GS_PARAMETERIZE_TOOTH_PARAMETERS, "tooth_parameters", "r_P = teeth_count*spacing/(2*pi)")

#define GS_OPTIONS_RackDirectionality(O)                                                       \
    O(GS_RACK_POSITIVE, "positive", "positive pinion rotation moves the rack in + (s_R = +1)") \
    O(GS_RACK_NEGATIVE, "negative", "positive pinion rotation moves the rack in - (s_R = -1)")

#define GS_OPTIONS_BaseDrive(O)                                                          \
    O(GS_BASE_SPEED_DRIVEN, "speed",                                                     \
      "the drive holds the base_speed input; the base_torque output is what it applies") \
    O(GS_BASE_TORQUE_DRIVEN, "torque", "the base_torque input acts on base_inertia; the speeds are outputs")

#define GS_OPTIONS_TemperatureSource(O)                                         \
    O(GS_TEMPERATURE_FROM_MODEL, "model", "the thermal state (physics.md 5.1)") \
    O(GS_TEMPERATURE_FROM_INPUT, "input", "the measured_temperature input overrides the thermal state")

/* Every option list, for the run-time tables: S(name). */
/* clang-format off: clang-format 14 re-wraps this list on every pass (it never settles) */
#define GS_OPTION_LISTS(S) \
    S(OutputShaftRotates)  \
    S(FrictionModel)       \
    S(RackFrictionModel)   \
    S(LossSmoothing)       \
    S(HardStopModel)       \
    S(Parameterization)    \
    S(RackDirectionality)  \
    S(BaseDrive)           \
    S(TemperatureSource)
/* clang-format on */

/* ---- parameter lists */

/* Shared by both blocks, at the same place in each struct. */
#define GS_LOSS_LAW_PARAMS_(X)                                                                  \
    X(OPTION, gs_loss_smoothing, loss_smoothing, 1, "loss_smoothing", "", LossSmoothing, FIXED, \
      "power-threshold smoothing of the efficiency laws")                                       \
    X(REAL, gs_real, efficiency_const, 1, "efficiency_const", "", NONE, TUNABLE, "constant efficiency, 0 < eta <= 1")

#define GS_TEMPERATURE_TABLE_PARAMS_(X)                                                                      \
    X(COUNT, int, temperature_count, 1, "temperature_count", "", NONE, FIXED,                                \
      "entries used in temperature_vector and efficiency_vector (and the rows of efficiency_matrix), 2..10") \
    X(TABLE, gs_real, temperature_vector_K, temperature_count, "temperature_vector", "K", NONE, TUNABLE,     \
      "temperature breakpoints, strictly increasing")                                                        \
    X(TABLE, gs_real, efficiency_vector, temperature_count, "efficiency_vector", "", NONE, TUNABLE,          \
      "efficiency at each temperature, in (0, 1]")

#define GS_THERMAL_MASS_PARAMS_(X)                                              \
    X(REAL, gs_real, thermal_mass_J_K, 1, "thermal_mass", "J/K", NONE, TUNABLE, \
      "thermal mass (> 0; temperature-dependent models)")                       \
    X(REAL, gs_real, initial_temperature_K, 1, "initial_temperature", "K", NONE, FIXED, "initial temperature (> 0)")

/* gs_backlash_params: the hard stop of both blocks. For the Rack & Pinion
 * the gap is measured along the rack and base_radius_m is unused. */
#define GS_BACKLASH_PARAM_LIST(X)                                                                                    \
    X(BOOL, int, enabled, 1, "backlash_enabled", "", NONE, FIXED, "enable backlash (off: rigid mesh)")               \
    X(OPTION, gs_hard_stop_model, hard_stop_model, 1, "hard_stop_model", "", HardStopModel, FIXED,                   \
      "hard-stop contact law")                                                                                       \
    X(REAL, gs_real, linear_backlash_m, 1, "linear_backlash", "m", NONE, FIXED,                                      \
      "total free travel b at the pitch line, along the rack for the Rack & Pinion (> 0)")                           \
    X(REAL, gs_real, base_radius_m, 1, "base_radius", "m", NONE, GEAR_ONLY,                                          \
      "base gear pitch radius r_B (> 0; Simple Gear only)")                                                          \
    X(REAL, gs_real, transition_region_m, 1, "transition_region", "m", NONE, FIXED,                                  \
      "transition region d of the smooth model (> 0)")                                                               \
    X(REAL, gs_real, stiffness_N_m, 1, "stiffness", "N/m", NONE, FIXED, "contact stiffness K (> 0)")                 \
    X(REAL, gs_real, damping_N_s_m, 1, "damping", "N*s/m", NONE, FIXED, "contact damping D (>= 0)")                  \
    X(REAL, gs_real, initial_position_m, 1, "initial_backlash_position", "m", NONE, FIXED,                           \
      "initial backlash position x0 in [-b/2, b/2]")                                                                 \
    X(BOOL, int, no_pull, 1, "contact_no_pull", "", NONE, FIXED, "the contact force never pulls the teeth together") \
    X(BOOL, int, lock_enabled, 1, "contact_lock_enabled", "", NONE, FIXED, "static contact lock (physics.md 4)")     \
    X(REAL, gs_real, contact_speed_threshold_m_s, 1, "contact_speed_threshold", "m/s", NONE, FIXED,                  \
      "lock mode: static contact speed threshold v_th (> 0)")                                                        \
    X(REAL, gs_real, contact_release_force_N, 1, "contact_release_force", "N", NONE, FIXED,                          \
      "lock mode: static contact release force threshold f_th (>= 0)")

/* gs_simple_gear_params (docs/physics.md section 9). */
#define GS_SIMPLE_GEAR_PARAM_LIST(X)                                                                                   \
    X(REAL, gs_real, teeth_ratio, 1, "teeth_ratio", "", NONE, FIXED, "follower-to-base teeth ratio g = N_F/N_B (> 0)") \
    X(OPTION, gs_output_rotation, output_shaft_rotates, 1, "output_shaft_rotates", "", OutputShaftRotates, FIXED,      \
      "follower rotation relative to the base")                                                                        \
    X(OPTION, gs_friction_model, friction_model, 1, "friction_model", "", FrictionModel, FIXED, "meshing-loss model")  \
    GS_LOSS_LAW_PARAMS_(X)                                                                                             \
    X(REAL, gs_real, power_threshold_W, 1, "power_threshold", "W", NONE, TUNABLE,                                      \
      "follower power threshold p_th of the efficiency smoothing (> 0)")                                               \
    X(REAL, gs_real, idle_torque_Nm, 1, "idle_torque", "N*m", NONE, TUNABLE, "base shaft torque at no load (>= 0)")    \
    X(REAL, gs_real, nominal_output_torque_Nm, 1, "nominal_output_torque", "N*m", NONE, TUNABLE,                       \
      "nominal output torque (> 0)")                                                                                   \
    X(REAL, gs_real, efficiency_nominal, 1, "efficiency_nominal", "", NONE, TUNABLE,                                   \
      "efficiency at the nominal output torque, 0 < eta < 1")                                                          \
    X(REAL, gs_real, speed_threshold_rad_s, 1, "speed_threshold", "rad/s", NONE, TUNABLE,                              \
      "follower angular velocity threshold of the load-dependent loss (> 0)")                                          \
    GS_TEMPERATURE_TABLE_PARAMS_(X)                                                                                    \
    X(COUNT, int, load_count, 1, "load_count", "", NONE, FIXED,                                                        \
      "entries used in load_vector and the columns of efficiency_matrix, 2..10")                                       \
    X(TABLE, gs_real, load_vector_Nm, load_count, "load_vector", "N*m", NONE, TUNABLE,                                 \
      "base-gear load breakpoints, >= 0, strictly increasing")                                                         \
    X(MATRIX, gs_real, efficiency_matrix, (temperature_count, load_count), "efficiency_matrix", "", NONE, TUNABLE,     \
      "efficiency [temperature row, load column], in (0, 1]")                                                          \
    X(GROUP, gs_backlash_params, backlash, 1, "backlash", "", NONE, FIXED, "backlash (gs_backlash_params)")            \
    X(ARRAY, gs_real, viscous_coefficients, 2, "viscous_coefficients", "N*m*s/rad", NONE, TUNABLE,                     \
      "viscous coefficients [mu_B, mu_F] of the base and follower shafts (>= 0)")                                      \
    GS_THERMAL_MASS_PARAMS_(X)

/* gs_rack_pinion_params (docs/physics.md sections 6, 9, 10). */
#define GS_RACK_PINION_PARAM_LIST(X)                                                                           \
    X(OPTION, gs_rack_parameterization, parameterization, 1, "parameterization", "", Parameterization, FIXED,  \
      "pinion radius given directly or by tooth parameters")                                                   \
    X(REAL, gs_real, pinion_radius_m, 1, "pinion_radius", "m", NONE, FIXED, "pinion radius r_P (> 0)")         \
    X(REAL, gs_real, teeth_count, 1, "teeth_count", "", NONE, FIXED, "number of pinion teeth N_P (> 0)")       \
    X(REAL, gs_real, spacing_m, 1, "spacing", "m", NONE, FIXED, "rack tooth spacing x_R (> 0)")                \
    X(OPTION, gs_rack_direction, rack_directionality, 1, "rack_directionality", "", RackDirectionality, FIXED, \
      "rack direction for positive pinion rotation")                                                           \
    X(OPTION, gs_friction_model, friction_model, 1, "friction_model", "", RackFrictionModel, FIXED,            \
      "meshing-loss model (none, constant or temperature-dependent efficiency)")                               \
    GS_LOSS_LAW_PARAMS_(X)                                                                                     \
    GS_TEMPERATURE_TABLE_PARAMS_(X)                                                                            \
    X(REAL, gs_real, power_threshold_W, 1, "power_threshold", "W", NONE, TUNABLE,                              \
      "rack power threshold of the efficiency smoothing (> 0)")                                                \
    X(REAL, gs_real, pinion_viscous_coefficient, 1, "pinion_viscous_coefficient", "N*m*s/rad", NONE, TUNABLE,  \
      "pinion viscous coefficient (>= 0)")                                                                     \
    X(REAL, gs_real, rack_viscous_coefficient, 1, "rack_viscous_coefficient", "N*s/m", NONE, TUNABLE,          \
      "rack viscous coefficient (>= 0)")                                                                       \
    GS_THERMAL_MASS_PARAMS_(X)                                                                                 \
    X(GROUP, gs_backlash_params, backlash, 1, "backlash", "", NONE, FIXED,                                     \
      "backlash along the rack (gs_backlash_params)")

/* gs_rig_params (docs/physics.md section 11). Driven-side quantities are
 * N*m, rad/s in the gear rig and N, m/s in the rack rig. */
#define GS_RIG_PARAM_LIST(X)                                                                                           \
    X(REAL, gs_real, dt_s, 1, "dt", "dt", "s", "s", NONE, FIXED,                                                       \
      "fixed step (> 0); an FMU's communication steps are whole multiples of it")                                      \
    X(OPTION, gs_base_drive, base_drive, 1, "base_drive", "base_drive", "", "", BaseDrive, FIXED,                      \
      "how the base (pinion) shaft is driven: speed-driven (base_speed input) or torque-driven (base_torque input)")   \
    X(REAL, gs_real, base_inertia_kg_m2, 1, "base_inertia", "base_inertia", "kg*m**2", "kg*m**2", NONE, FIXED,         \
      "base (pinion) shaft inertia J_B: > 0 when torque-driven; speed-driven (>= 0) adds J_B*alpha_B to base_torque")  \
    X(REAL, gs_real, initial_base_speed_rad_s, 1, "initial_base_speed", "initial_base_speed", "rad/s", "rad/s", NONE,  \
      FIXED, "torque-driven: base speed at the start")                                                                 \
    X(REAL, gs_real, driven_inertia, 1, "follower_inertia", "rack_mass", "kg*m**2", "kg", NONE, FIXED,                 \
      "follower shaft inertia or rack mass (> 0)")                                                                     \
    X(REAL, gs_real, load_coulomb_friction, 1, "load_coulomb_friction", "load_coulomb_friction", "N*m", "N", NONE,     \
      TUNABLE, "constant Coulomb friction on the driven side, against the motion (>= 0)")                              \
    X(REAL, gs_real, load_coulomb_speed_threshold, 1, "load_coulomb_speed_threshold", "load_coulomb_speed_threshold",  \
      "rad/s", "m/s", NONE, TUNABLE,                                                                                   \
      "speed scale of the tanh(4 v/v_th) smoothing of load_coulomb_friction in the speed-driven rigid rig (> 0)")      \
    X(REAL, gs_real, load_offset, 1, "load_offset", "load_offset", "N*m", "N", NONE, TUNABLE,                          \
      "constant bias on the driven side (gravity, cable drag)")                                                        \
    X(BOOL, int, heat_path, 1, "heat_path", "heat_path", "", "", NONE, FIXED,                                          \
      "on: heat flows to the ambient_temperature input through thermal_resistance; off: adiabatic")                    \
    X(REAL, gs_real, thermal_resistance_K_W, 1, "thermal_resistance", "thermal_resistance", "K/W", "K/W", NONE,        \
      TUNABLE, "housing-to-ambient thermal resistance R_th (> 0 when heat_path)")                                      \
    X(BOOL, gs_temperature_source, temperature_source, 1, "temperature_input", "temperature_input", "", "",            \
      TemperatureSource, FIXED,                                                                                        \
      "temperature-dependent losses use the measured_temperature input instead of the thermal state")                  \
    X(REAL, gs_real, accel_filter_time_constant_s, 1, "accel_filter_time_constant", "accel_filter_time_constant", "s", \
      "s", NONE, FIXED,                                                                                                \
      "speed-driven: first-order low-pass on the base acceleration (>= 0; 0 = raw backward difference)")               \
    X(INT, int, contact_substeps, 1, "contact_substeps", "contact_substeps", "", "", NONE, FIXED,                      \
      "backlash: contact sub-steps per step, 1..64, 0 = chosen at init")                                               \
    X(REAL, gs_real, load_breakaway_friction, 1, "load_breakaway_friction", "load_breakaway_friction", "N*m", "N",     \
      NONE, TUNABLE, "Stribeck: driven-side friction at rest F_brk (0 = none, else >= load_coulomb_friction)")         \
    X(REAL, gs_real, load_stribeck_speed, 1, "load_stribeck_speed", "load_stribeck_speed", "rad/s", "m/s", NONE,       \
      TUNABLE, "Stribeck speed v_S: F_C + (F_brk - F_C)*exp(-(v/v_S)^2) (> 0)")                                        \
    X(REAL, gs_real, compliance_stiffness_Nm_rad, 1, "compliance_stiffness", "compliance_stiffness", "N*m/rad",        \
      "N*m/rad", NONE, FIXED,                                                                                          \
      "torsional stiffness k of the base shaft, drive to base gear "                                                   \
      "(0 = rigid; speed-driven base, no backlash; base_inertia 0 puts the spring at the mesh)")                       \
    X(REAL, gs_real, compliance_damping_Nm_s_rad, 1, "compliance_damping", "compliance_damping", "N*m*s/rad",          \
      "N*m*s/rad", NONE, FIXED, "torsional damping c of the base shaft (>= 0)")                                        \
    X(ARRAY, gs_real, ripple_revolution_amplitude_Nm, GS_RIPPLE_HARMONICS, "ripple_revolution_amplitude",              \
      "ripple_revolution_amplitude", "N*m", "N*m", NONE, TUNABLE,                                                      \
      "base-side ripple amplitudes A_i of the harmonics i = 1, 2 per revolution (>= 0)")                               \
    X(ARRAY, gs_real, ripple_revolution_phase_rad, GS_RIPPLE_HARMONICS, "ripple_revolution_phase",                     \
      "ripple_revolution_phase", "rad", "rad", NONE, TUNABLE, "phases phi_i of the per-revolution ripple harmonics")   \
    X(ARRAY, gs_real, ripple_mesh_amplitude_Nm, GS_RIPPLE_HARMONICS, "ripple_mesh_amplitude", "ripple_mesh_amplitude", \
      "N*m", "N*m", NONE, TUNABLE, "base-side ripple amplitudes M_j of the harmonics j = 1, 2 per tooth mesh (>= 0)")  \
    X(ARRAY, gs_real, ripple_mesh_phase_rad, GS_RIPPLE_HARMONICS, "ripple_mesh_phase", "ripple_mesh_phase", "rad",     \
      "rad", NONE, TUNABLE, "phases psi_j of the per-tooth ripple harmonics")                                          \
    X(INT, int, ripple_mesh_teeth, 1, "ripple_mesh_teeth", "ripple_mesh_teeth", "", "", NONE, FIXED,                   \
      "teeth Z of the base gear or pinion per revolution (>= 1 with a mesh ripple)")                                   \
    X(BOOL, int, load_friction_regularised, 1, "load_friction_regularised", "load_friction_regularised", "", "", NONE, \
      FIXED,                                                                                                           \
      "on: a freely moving driven side's friction is F*tanh(4 v/load_coulomb_speed_threshold) and the meshing "        \
      "loss takes its smoothing's strength: both creep (no stiction); off: set-valued laws")                           \
    X(BOOL, int, base_speed_ramp, 1, "base_speed_ramp", "base_speed_ramp", "", "", NONE, FIXED,                        \
      "speed-driven rigid mesh, on: the speed terms at the step's mean speed (the samples' linear ramp), so every "    \
      "torque is a step mean; off: at this sample")

/* ---- expanders */

/* An option list as enumerators (values 0, 1, ... in list order). */
#define GS_OPTION_ENUMERATOR_(enumerator, name, doc) enumerator,

/* A parameter as a struct member, by kind. */
#define GS_PARAM_DECLARE_REAL(type, member, count)   type member;
#define GS_PARAM_DECLARE_INT(type, member, count)    type member;
#define GS_PARAM_DECLARE_BOOL(type, member, count)   type member;
#define GS_PARAM_DECLARE_OPTION(type, member, count) type member;
#define GS_PARAM_DECLARE_COUNT(type, member, count)  type member;
#define GS_PARAM_DECLARE_GROUP(type, member, count)  type member;
#define GS_PARAM_DECLARE_ARRAY(type, member, count)  type member[count];
#define GS_PARAM_DECLARE_TABLE(type, member, count)  type member[GS_TABLE_MAX];
#define GS_PARAM_DECLARE_MATRIX(type, member, count) type member[GS_TABLE_MAX][GS_TABLE_MAX];
#define GS_PARAM_MEMBER_(kind, type, member, count, key, unit, options, flags, doc) \
    GS_PARAM_DECLARE_##kind(type, member, count)
#define GS_RIG_PARAM_MEMBER_(kind, type, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc) \
    GS_PARAM_DECLARE_##kind(type, member, count)

/* Entries of a list. */
#define GS_PARAM_COUNT_(kind, type, member, count, key, unit, options, flags, doc)                               +1
#define GS_RIG_PARAM_COUNT_(kind, type, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc) +1

#endif /* GEARSIM_PARAMETERS_H */
