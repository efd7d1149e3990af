/*
 * gearsim/fields.h - the one table of the rig's inputs, outputs and state.
 *
 * Each field is declared here once, as X(type, name, gear_unit, rack_unit,
 * doc): its C type, its name in every layer (C struct member, Python, FMU
 * variable, firmware CSV column), its unit in the Simple Gear rig and in the
 * Rack & Pinion rig (the follower side is a shaft in one, the rack in the
 * other), and a one-line description. The structs of rig.h and
 * simple_gear.h, the run-time tables gs_rig_*_info (which the Python package
 * reads), the FMU's variables and the firmware's output columns are all
 * expanded from these lists. Units are written as pint parses them.
 *
 * "follower" is the driven side throughout: the follower shaft of the Simple
 * Gear, the rack of the Rack & Pinion. The measurement files' column names
 * (follower_speed / rack_velocity, ...) are an external mapping onto these
 * names, kept in the Python package (docs/measurement-format.md).
 */
#ifndef GEARSIM_FIELDS_H
#define GEARSIM_FIELDS_H

/* Per-step inputs of a rig, all gs_real. */
#define GS_RIG_INPUT_LIST(X)                                                                                  \
    X(gs_real, base_speed, "rad/s", "rad/s", "speed-driven: the base (pinion) speed the drive holds")         \
    X(gs_real, base_torque, "N*m", "N*m", "torque-driven: the motor torque on the base inertia")              \
    X(gs_real, load, "N*m", "N", "external load on the follower, + along + follower rotation or rack travel") \
    X(gs_real, ambient_temperature, "K", "K", "ambient temperature, used with the heat path")                 \
    X(gs_real, measured_temperature, "K", "K", "block temperature, used when temperature_source is the input")

/* Per-step outputs of a rig, all gs_real. Torques, powers and the contact
 * force are means over the step's contact sub-steps; speeds, angles,
 * positions and the temperature are values at the end of the step. */
#define GS_RIG_OUTPUT_LIST(X)                                                                                           \
    X(gs_real, base_torque, "N*m", "N*m",                                                                               \
      "torque the drive applies to the base shaft (speed-driven: port torque + J_B*alpha_B; torque-driven: the input)") \
    X(gs_real, base_speed, "rad/s", "rad/s", "base (pinion) shaft speed")                                               \
    X(gs_real, base_angle, "rad", "rad", "base (pinion) shaft angle")                                                   \
    X(gs_real, follower_speed, "rad/s", "m/s", "follower shaft speed or rack velocity")                                 \
    X(gs_real, follower_position, "rad", "m", "follower shaft angle or rack position")                                  \
    X(gs_real, base_port_torque, "N*m", "N*m", "tau_B: what the base shaft applies to the block")                       \
    X(gs_real, follower_port_torque, "N*m", "N", "tau_F or F_R: what the follower side applies to the block")           \
    X(gs_real, mesh_loss_power, "W", "W", "meshing loss, >= 0")                                                         \
    X(gs_real, loss_power, "W", "W", "mesh + viscous + contact damping loss, >= 0")                                     \
    X(gs_real, port_power, "W", "W", "power into the block through both ports")                                         \
    X(gs_real, contact_energy, "J", "J", "energy in the backlash spring at the end of the step")                        \
    X(gs_real, temperature, "K", "K", "block temperature at the end of the step, or the measured input")                \
    X(gs_real, backlash_position, "m", "m", "backlash position x at the end of the step")                               \
    X(gs_real, contact_force, "N", "N", "backlash contact force, + when the base pushes the follower in +x")            \
    X(gs_real, follower_acceleration, "rad/s^2", "m/s^2", "follower shaft or rack acceleration over the step")

/* State of a block's mesh (also the first member of a rig's state). */
#define GS_BLOCK_STATE_LIST(X)                                                                                   \
    X(gs_real, temperature, "K", "K", "block temperature T_th (thermal state)")                                  \
    X(gs_real, backlash_position, "m", "m", "backlash position x")                                               \
    X(gs_real, contact_force, "N", "N", "contact force at the end of the last sub-step")                         \
    X(gs_real, follower_torque, "N*m", "N", "net follower torque T_F of the last step (seeds the meshing loss)") \
    X(int, contact_locked, "1", "1", "1 while the static-contact lock holds the teeth together")

/* State of a rig beyond its block's. */
#define GS_RIG_STATE_LIST(X)                                                                            \
    X(gs_real, base_speed, "rad/s", "rad/s", "base (pinion) shaft speed")                               \
    X(gs_real, base_angle, "rad", "rad", "base (pinion) shaft angle")                                   \
    X(gs_real, follower_speed, "rad/s", "m/s", "follower shaft speed or rack velocity")                 \
    X(gs_real, follower_position, "rad", "m", "follower shaft angle or rack position")                  \
    X(gs_real, base_speed_sample, "rad/s", "rad/s", "speed-driven: the last base speed input")          \
    X(gs_real, base_acceleration, "rad/s^2", "rad/s^2", "speed-driven: the filtered base acceleration") \
    X(gs_real, shaft_twist, "rad", "rad", "compliance: drive angle minus base gear angle")              \
    X(int, started, "1", "1", "0 until the first step after init or reset")

/* Expanders for the lists above. */
#define GS_FIELD_MEMBER_(type, name, gear_unit, rack_unit, doc) type name;
#define GS_FIELD_COUNT_(type, name, gear_unit, rack_unit, doc)  +1

#endif /* GEARSIM_FIELDS_H */
