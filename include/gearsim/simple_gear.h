/*
 * gearsim/simple_gear.h - the Simple Gear block (base B, follower F).
 *
 * Kinematics omega_B = s*g*omega_F with g = N_F/N_B; torques are those the
 * outside world applies to the block at each port (docs/physics.md section 0).
 * Five meshing-loss models, viscous losses on both shafts, backlash through a
 * hard stop, thermal mass. Most users step a rig (gearsim/rig.h), which puts
 * the block between a driven base shaft and an inertia.
 */
#ifndef GEARSIM_SIMPLE_GEAR_H
#define GEARSIM_SIMPLE_GEAR_H

#include "gearsim/types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define gs_simple_gear_init GS_PRECISION_NAME(gs_simple_gear_init)

/* Output shaft direction (gearsim/parameters.h GS_OPTIONS_OutputShaftRotates):
 * SAME s = +1, OPPOSITE s = -1 (the default). */
typedef enum { GS_OPTIONS_OutputShaftRotates(GS_OPTION_ENUMERATOR_) } gs_output_rotation;

/* What the user sets: the members of gearsim/parameters.h
 * GS_SIMPLE_GEAR_PARAM_LIST (names, units, valid ranges), plain data in SI
 * units; defaults from gs_simple_gear_params_default() (docs/physics.md
 * section 9, docs/fmu.md lists them). Parameters of an inactive option (e.g.
 * the tables with constant efficiency) are not validated. */
typedef struct {
    GS_SIMPLE_GEAR_PARAM_LIST(GS_PARAM_MEMBER_)
} gs_simple_gear_params;

/* Every entry of gs_simple_gear_params, in member order (the backlash member
 * is one GROUP entry pointing at gs_backlash_param_info). */
#define GS_SIMPLE_GEAR_PARAM_FIELDS (0 GS_SIMPLE_GEAR_PARAM_LIST(GS_PARAM_COUNT_))
GS_API extern const gs_param_info gs_simple_gear_param_info[GS_SIMPLE_GEAR_PARAM_FIELDS];

/* What init derives from the parameters (opaque, see GS_BLOCK_CONSTS_REALS);
 * the step only reads it. The state is a gs_block_state. */
typedef struct {
    gs_real opaque_[GS_BLOCK_CONSTS_REALS];
} gs_simple_gear_consts;

/* Port inputs of one block step. Without backlash the mesh is rigid and the
 * step uses base_speed and follower_torque (causal form A of physics.md 8);
 * with backlash it uses base_speed and follower_speed (form C).
 * temperature_K is used by the temperature-dependent models only when
 * use_temperature_input is non-zero; otherwise the thermal state is used. */
typedef struct {
    gs_real base_speed_rad_s;
    gs_real follower_speed_rad_s; /* backlash only */
    gs_real follower_torque_Nm;   /* rigid only: torque the outside applies at F */
    gs_real heat_flow_W;          /* Q_H into the block through the thermal port */
    gs_real temperature_K;
    int use_temperature_input;
} gs_gear_ports_in;

typedef struct {
    gs_real base_torque_Nm;       /* tau_B applied by the outside at B */
    gs_real follower_torque_Nm;   /* tau_F applied by the outside at F */
    gs_real follower_speed_rad_s; /* rigid: s*omega_B/g; backlash: the input */
    gs_real mesh_loss_torque_Nm;  /* tau_mesh, follower-referred */
    gs_real mesh_loss_power_W;    /* tau_mesh*omega_F >= 0 (passive smoothing) */
    gs_real loss_power_W;         /* mesh + viscous + contact damping */
    gs_real temperature_K;        /* T_th after the step (or the input) */
    gs_real backlash_position_m;  /* x after the step */
    gs_real contact_force_N;      /* f, positive when B pushes F in +x */
} gs_gear_ports_out;

/* Defaults of every parameter (docs/physics.md section 9). Cost: O(table). */
GS_API gs_simple_gear_params gs_simple_gear_params_default(void);

/* Validates params, fills consts and sets state to the initial state.
 * Returns GS_OK or the status of the first rule broken; err (may be NULL)
 * receives the status, the parameter's program name and a message. consts
 * and state are left unchanged on failure. Never allocates. */
GS_API gs_status gs_simple_gear_init(gs_simple_gear_consts *consts, gs_block_state *state,
                                     const gs_simple_gear_params *params, gs_error *err);

/* Returns the state to its initial values (temperature, backlash position). */
GS_API void gs_simple_gear_reset(const gs_simple_gear_consts *consts, gs_block_state *state);

/* Advances the block by dt_s (> 0): evaluates the port torques and integrates
 * the backlash position and temperature. Cannot fail; O(1). The backlash
 * position uses explicit Euler here; the rigs integrate the contact
 * implicitly and are what stiff contact should be stepped with. */
GS_API void gs_simple_gear_step(const gs_simple_gear_consts *consts, gs_block_state *state, gs_real dt_s,
                                const gs_gear_ports_in *in, gs_gear_ports_out *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_SIMPLE_GEAR_H */
