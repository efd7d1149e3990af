/*
 * gearsim/rig.h - a block between two shafts: what firmware, HIL rigs and
 * measurements step (docs/physics.md section 11).
 *
 * Base side (the pinion for the rack rig): speed-driven (a drive holds the
 * measured speed, the rig returns the torque it must apply) or torque-driven
 * (a motor torque acts on base_inertia, the rig returns the speeds).
 * Driven side: the follower shaft with follower_inertia (kg*m^2), or the rack
 * with rack_mass (kg), under an external load plus rig-level Coulomb friction
 * and a constant offset. "Driven-side" quantities are N*m, rad/s and rad for
 * the gear rig and N, m/s and m for the rack rig.
 *
 * Without backlash the mesh is rigid and the rig has one degree of freedom;
 * with backlash the driven side has its own speed and the contact is
 * integrated implicitly (backward Euler on the contact, a fixed number of
 * sub-steps), so stiff contact stays bounded at any dt.
 *
 * Wherever a shaft moves freely (torque-driven base, backlash, compliant
 * shaft), load_coulomb_friction is a true Coulomb friction integrated
 * implicitly: it holds the driven side at rest while the applied torque stays
 * within it and never reverses the motion. The meshing loss is a friction of
 * the same kind there: the law at full strength while the gear turns, and at
 * rest it holds while neither side can drive the other (physics.md 11). In
 * the speed-driven rigid rig the speed is imposed, the meshing loss is the
 * smoothed law and the Coulomb friction is tanh-smoothed on
 * load_coulomb_speed_threshold.
 *
 * Three rig terms model what real rigs add (physics.md 11), each off by
 * default: a Stribeck hump on the driven side's friction (it then holds at
 * rest up to the breakaway level), a compliant base shaft (spring and damper
 * from the drive to the base gear, which turns with base_inertia; speed-driven
 * base and rigid mesh only; base_torque is then the shaft torque and
 * base_speed/base_angle the base gear's; with base_inertia 0 the spring acts
 * at the mesh), and a torque ripple on the base side, periodic in the base
 * angle per revolution and per tooth. Two switches, also off by default:
 * load_friction_regularised makes a freely moving driven side's friction and
 * meshing loss the smooth laws of the speed-driven rigid rig (they creep, no
 * stiction), and
 * base_speed_ramp evaluates the speed-driven rigid rig at the step's mean
 * speed.
 */
#ifndef GEARSIM_RIG_H
#define GEARSIM_RIG_H

#include "gearsim/simple_gear.h"
#include "gearsim/rack_pinion.h"

#ifdef __cplusplus
extern "C" {
#endif

#define gs_rig_init_gear GS_PRECISION_NAME(gs_rig_init_gear)
#define gs_rig_init_rack GS_PRECISION_NAME(gs_rig_init_rack)

#define GS_MAX_SUBSTEPS       64
/* The automatic sub-step count (contact_substeps = 0) is the smallest with
 * h*omega_n <= GS_AUTO_H_OMEGA_N_MAX, and stops at GS_AUTO_SUBSTEPS_MAX; see
 * gs_rig_info. */
#define GS_AUTO_H_OMEGA_N_MAX 1.0
#define GS_AUTO_SUBSTEPS_MAX  16
/* Harmonics of the torque ripple, per revolution and per tooth mesh. */
#define GS_RIPPLE_HARMONICS   2

/* How the base shaft is driven (GS_OPTIONS_BaseDrive; default speed) and
 * which temperature the losses use (GS_OPTIONS_TemperatureSource: the thermal
 * state (5.1), the default, or the measured_temperature input). */
typedef enum { GS_OPTIONS_BaseDrive(GS_OPTION_ENUMERATOR_) } gs_base_drive;
typedef enum { GS_OPTIONS_TemperatureSource(GS_OPTION_ENUMERATOR_) } gs_temperature_source;

typedef enum { GS_RIG_SIMPLE_GEAR = 0, GS_RIG_RACK_PINION = 1 } gs_rig_block;

/* What the user sets for the rig: the members of gearsim/parameters.h
 * GS_RIG_PARAM_LIST (name and unit in each rig, valid ranges); defaults from
 * gs_rig_params_default(), with every term of physics.md 11 off. */
typedef struct {
    GS_RIG_PARAM_LIST(GS_RIG_PARAM_MEMBER_)
} gs_rig_params;

/* Every entry of gs_rig_params, in member order: key and unit in each rig. */
#define GS_RIG_PARAM_FIELDS (0 GS_RIG_PARAM_LIST(GS_RIG_PARAM_COUNT_))
GS_API extern const gs_param_info gs_rig_param_info[GS_RIG_PARAM_FIELDS];

/* Per-step inputs and outputs (gearsim/fields.h: names, units, docs). All
 * members are gs_real, so an array of N inputs is an N x GS_RIG_INPUT_FIELDS
 * array of reals, and likewise for the outputs. Unused inputs are ignored. */
typedef struct {
    GS_RIG_INPUT_LIST(GS_FIELD_MEMBER_)
} gs_rig_input;

typedef struct {
    GS_RIG_OUTPUT_LIST(GS_FIELD_MEMBER_)
} gs_rig_output;

/* The state of a rig: everything a step changes, and nothing else. Plain
 * data, no pointers: a snapshot is a copy of it, copying it back restores
 * it; a state may be stepped with the constants of other parameters (to
 * re-tune a running rig). Its size is published as sizeof(gs_rig_state). */
typedef struct {
    gs_block_state block;
    GS_RIG_STATE_LIST(GS_FIELD_MEMBER_)
} gs_rig_state;

enum {
    GS_RIG_INPUT_FIELDS = 0 GS_RIG_INPUT_LIST(GS_FIELD_COUNT_),
    GS_RIG_OUTPUT_FIELDS = 0 GS_RIG_OUTPUT_LIST(GS_FIELD_COUNT_),
    /* fields of gs_rig_state, the block's included (gs_rig_state_info) */
    GS_RIG_STATE_FIELDS = 0 GS_BLOCK_STATE_LIST(GS_FIELD_COUNT_) GS_RIG_STATE_LIST(GS_FIELD_COUNT_)
};

/* The field tables, in member order: GS_RIG_INPUT_FIELDS, GS_RIG_OUTPUT_FIELDS
 * and GS_RIG_STATE_FIELDS entries (the state's offsets are within
 * gs_rig_state, block members first). */
GS_API extern const gs_field_info gs_rig_input_info[GS_RIG_INPUT_FIELDS];
GS_API extern const gs_field_info gs_rig_output_info[GS_RIG_OUTPUT_FIELDS];
GS_API extern const gs_field_info gs_rig_state_info[GS_RIG_STATE_FIELDS];

/* What init derives from the parameters (opaque; the layout is internal). A
 * step only reads it: init once, then it may be const, shared by several
 * states, or kept in flash as an image of an initialised rig. Its size is
 * part of the ABI (GS_RIG_CONSTS_REALS reals; on targets that pack enums the
 * internal layout uses a few bytes less). The count is exactly what the
 * internal layout needs on the hosts: the library does not compile with a
 * stale count, and the compiler's message gives the value to write here
 * (src/mesh.h, GS_CONSTS_REALS_CHECK_). */
#ifdef GS_SINGLE_PRECISION
#define GS_RIG_CONSTS_REALS 289
#else
#define GS_RIG_CONSTS_REALS 278
#endif
typedef struct {
    gs_real opaque_[GS_RIG_CONSTS_REALS];
} gs_rig_consts;

GS_API gs_rig_params gs_rig_params_default(void);

/* What init chose for the contact integration, and the kinematics, for the
 * user to read. */
typedef struct {
    int contact_substeps;         /* sub-steps per step (1 without backlash) */
    gs_real contact_h_omega_n;    /* h*omega_n, omega_n = sqrt(K/m_eff): the contact's
                                   accuracy figure (0 without backlash); <= GS_AUTO_H_OMEGA_N_MAX is the
                                   automatic target, about 0.05 resolves a rebound */
    int substeps_capped;          /* 1 when contact_substeps = 0 chose GS_AUTO_SUBSTEPS_MAX
                                   and h*omega_n is still above GS_AUTO_H_OMEGA_N_MAX: the contact is
                                   stable (backward Euler) but over-damped; lower dt or
                                   set contact_substeps */
    gs_real follower_per_base;    /* follower speed per base speed of the rigid mesh:
                                   s/g (rad/s per rad/s) or s_R*r_P (m/s per rad/s) */
    int compliance_substeps;      /* sub-steps of the compliant shaft (1 without compliance) */
    gs_real compliance_h_omega_n; /* h*omega_c, omega_c = sqrt(k/J_eff): <= 0.2 unless capped
                                     at GS_AUTO_SUBSTEPS_MAX (0 without compliance) */
} gs_rig_info;

/* Fills info for initialised constants. */
GS_API void gs_rig_get_info(const gs_rig_consts *consts, gs_rig_info *info);

/* Validate the block and rig parameters, fill consts and set state to the
 * initial state. err names the failing parameter (block names as in
 * docs/physics.md; rig names e.g. "follower_inertia", "rack_mass", "dt").
 * consts and state are left unchanged on failure. Never allocates. */
GS_API gs_status gs_rig_init_gear(gs_rig_consts *consts, gs_rig_state *state, const gs_simple_gear_params *gear,
                                  const gs_rig_params *params, gs_error *err);
GS_API gs_status gs_rig_init_rack(gs_rig_consts *consts, gs_rig_state *state, const gs_rack_pinion_params *rack,
                                  const gs_rig_params *params, gs_error *err);

/* Sets state to the initial state of consts (speeds, angles, temperature,
 * backlash). */
GS_API void gs_rig_reset(const gs_rig_consts *consts, gs_rig_state *state);

/* One fixed step of dt_s: reads consts, updates state. Cannot fail; bounded
 * cost (fixed sub-step and iteration counts). Inputs must be finite; the
 * outputs are then finite. Speed-driven: the first step after init/reset
 * takes its base speed as the initial state, with the follower geared to it
 * (teeth moving together, no acceleration); feed a zero-speed sample first to
 * start at rest. */
GS_API void gs_rig_step(const gs_rig_consts *consts, gs_rig_state *state, const gs_rig_input *in, gs_rig_output *out);

/* n steps over caller-owned arrays; bit-identical to n calls of gs_rig_step. */
GS_API void gs_rig_run(const gs_rig_consts *consts, gs_rig_state *state, size_t n, const gs_rig_input *in,
                       gs_rig_output *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_RIG_H */
