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

typedef enum {
    GS_ROTATES_SAME = 0,     /* s = +1 */
    GS_ROTATES_OPPOSITE = 1  /* s = -1 (default) */
} gs_output_rotation;

/* What the user sets. Plain data in SI units; defaults from
 * gs_simple_gear_params_default() (docs/physics.md section 9). Parameters of
 * an inactive option (e.g. the tables with constant efficiency) are not
 * validated. */
typedef struct {
    gs_real teeth_ratio;                      /* g = N_F/N_B (> 0), default 2 */
    gs_output_rotation output_shaft_rotates;  /* default GS_ROTATES_OPPOSITE */
    gs_friction_model friction_model;         /* default GS_FRICTION_NONE */
    gs_loss_smoothing loss_smoothing;         /* default GS_SMOOTHING_PASSIVE */
    gs_real efficiency_const;                 /* (0, 1], default 0.98 */
    gs_real power_threshold_W;                /* p_th (> 0), default 1e-3 */
    gs_real idle_torque_Nm;                   /* tau_idle on the base shaft (>= 0), default 0.01 */
    gs_real nominal_output_torque_Nm;         /* tau_nom (> 0), default 1 */
    gs_real efficiency_nominal;               /* (0, 1), default 0.95 */
    gs_real speed_threshold_rad_s;            /* omega_th (> 0), default 0.01 */
    int temperature_count;                    /* entries used in temperature_vector_K */
    gs_real temperature_vector_K[GS_TABLE_MAX];/* strictly increasing, default [280 300 320] */
    gs_real efficiency_vector[GS_TABLE_MAX];  /* per temperature, (0, 1], default [0.95 0.90 0.85] */
    int load_count;                           /* entries used in load_vector_Nm */
    gs_real load_vector_Nm[GS_TABLE_MAX];     /* base-gear load, >= 0, strictly increasing, default [0 50 100] */
    gs_real efficiency_matrix[GS_TABLE_MAX][GS_TABLE_MAX]; /* [temperature][load], (0, 1] */
    gs_backlash_params backlash;              /* default disabled */
    gs_real viscous_coefficients[2];          /* [mu_B, mu_F] N*m/(rad/s) (>= 0), default [0 0] */
    gs_real thermal_mass_J_K;                 /* (> 0), default 50 */
    gs_real initial_temperature_K;            /* (> 0), default 300 */
} gs_simple_gear_params;

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
    gs_real follower_speed_rad_s;   /* backlash only */
    gs_real follower_torque_Nm;     /* rigid only: torque the outside applies at F */
    gs_real heat_flow_W;            /* Q_H into the block through the thermal port */
    gs_real temperature_K;
    int use_temperature_input;
} gs_gear_ports_in;

typedef struct {
    gs_real base_torque_Nm;         /* tau_B applied by the outside at B */
    gs_real follower_torque_Nm;     /* tau_F applied by the outside at F */
    gs_real follower_speed_rad_s;   /* rigid: s*omega_B/g; backlash: the input */
    gs_real mesh_loss_torque_Nm;    /* tau_mesh, follower-referred */
    gs_real mesh_loss_power_W;      /* tau_mesh*omega_F >= 0 (passive smoothing) */
    gs_real loss_power_W;           /* mesh + viscous + contact damping */
    gs_real temperature_K;          /* T_th after the step (or the input) */
    gs_real backlash_position_m;    /* x after the step */
    gs_real contact_force_N;        /* f, positive when B pushes F in +x */
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
GS_API void gs_simple_gear_step(const gs_simple_gear_consts *consts, gs_block_state *state,
                                gs_real dt_s, const gs_gear_ports_in *in, gs_gear_ports_out *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_SIMPLE_GEAR_H */
