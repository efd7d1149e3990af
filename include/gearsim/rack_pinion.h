/*
 * gearsim/rack_pinion.h - the Rack & Pinion block (pinion P, rack R).
 *
 * Kinematics v_R = s_R*r_P*omega_P (docs/physics.md section 6); tau_P and F_R
 * are what the outside applies to the block. Three meshing-loss models with
 * the rack power threshold, pinion and rack viscous losses, thermal mass, and
 * backlash along the rack (an extension beyond the seed, physics.md 10).
 */
#ifndef GEARSIM_RACK_PINION_H
#define GEARSIM_RACK_PINION_H

#include "gearsim/types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define gs_rack_pinion_init GS_PRECISION_NAME(gs_rack_pinion_init)

typedef enum {
    GS_PARAMETERIZE_PINION_RADIUS = 0,   /* default */
    GS_PARAMETERIZE_TOOTH_PARAMETERS = 1 /* r_P = N_P*x_R/(2*pi) */
} gs_rack_parameterization;

typedef enum {
    GS_RACK_POSITIVE = 0,  /* s_R = +1: positive pinion rotation moves the rack + (default) */
    GS_RACK_NEGATIVE = 1   /* s_R = -1 */
} gs_rack_direction;

typedef struct {
    gs_rack_parameterization parameterization;  /* default pinion radius */
    gs_real pinion_radius_m;                    /* (> 0), default 0.1 */
    gs_real teeth_count;                        /* N_P (> 0), default 20 */
    gs_real spacing_m;                          /* x_R (> 0), default 0.005 */
    gs_rack_direction rack_directionality;      /* default positive */
    gs_friction_model friction_model;           /* NONE (default), CONSTANT, TEMPERATURE */
    gs_loss_smoothing loss_smoothing;           /* default passive */
    gs_real efficiency_const;                   /* (0, 1], default 0.8 */
    int temperature_count;
    gs_real temperature_vector_K[GS_TABLE_MAX]; /* default [280 300 320] */
    gs_real efficiency_vector[GS_TABLE_MAX];    /* default [0.95 0.90 0.85] */
    gs_real power_threshold_W;                  /* rack power threshold (> 0), default 1e-3 */
    gs_real pinion_viscous_coefficient;         /* N*m/(rad/s) (>= 0), default 0 */
    gs_real rack_viscous_coefficient;           /* N/(m/s) (>= 0), default 0 */
    gs_real thermal_mass_J_K;                   /* (> 0), default 50 */
    gs_real initial_temperature_K;              /* (> 0), default 300 */
    gs_backlash_params backlash;                /* gap along the rack; base_radius_m unused */
} gs_rack_pinion_params;

/* What init derives from the parameters (opaque, see GS_BLOCK_CONSTS_REALS);
 * the step only reads it. The state is a gs_block_state. */
typedef struct {
    gs_real opaque_[GS_BLOCK_CONSTS_REALS];
} gs_rack_pinion_consts;

/* Port inputs: rigid mesh uses pinion_speed and rack_force (form A); backlash
 * uses pinion_speed and rack_velocity (form C). */
typedef struct {
    gs_real pinion_speed_rad_s;
    gs_real rack_velocity_m_s;      /* backlash only */
    gs_real rack_force_N;           /* rigid only: force the outside applies at R */
    gs_real heat_flow_W;
    gs_real temperature_K;
    int use_temperature_input;
} gs_rack_ports_in;

typedef struct {
    gs_real pinion_torque_Nm;       /* tau_P applied by the outside at P */
    gs_real rack_force_N;           /* F_R applied by the outside at R */
    gs_real rack_velocity_m_s;
    gs_real mesh_loss_force_N;      /* F_Coul, sign of v_R */
    gs_real mesh_loss_power_W;
    gs_real loss_power_W;
    gs_real temperature_K;
    gs_real backlash_position_m;
    gs_real contact_force_N;
} gs_rack_ports_out;

GS_API gs_rack_pinion_params gs_rack_pinion_params_default(void);

/* Pinion radius in use (m): the parameter, or N_P*x_R/(2*pi). */
GS_API gs_real gs_rack_pinion_radius(const gs_rack_pinion_params *params);

/* As gs_simple_gear_init, gs_simple_gear_reset and gs_simple_gear_step. */
GS_API gs_status gs_rack_pinion_init(gs_rack_pinion_consts *consts, gs_block_state *state,
                                     const gs_rack_pinion_params *params, gs_error *err);
GS_API void gs_rack_pinion_reset(const gs_rack_pinion_consts *consts, gs_block_state *state);
GS_API void gs_rack_pinion_step(const gs_rack_pinion_consts *consts, gs_block_state *state,
                                gs_real dt_s, const gs_rack_ports_in *in, gs_rack_ports_out *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_RACK_PINION_H */
