/*
 * gearsim/rack_pinion.h - the Rack & Pinion block (pinion P, rack R).
 *
 * Kinematics v_R = s_R*r_P*omega_P (docs/physics.md section 6); tau_P and F_R
 * are what the outside applies to the block. Three meshing-loss models with
 * the rack power threshold, pinion and rack viscous losses, thermal mass, and
 * backlash along the rack (physics.md 10).
 */
#ifndef GEARSIM_RACK_PINION_H
#define GEARSIM_RACK_PINION_H

#include "gearsim/types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define gs_rack_pinion_init GS_PRECISION_NAME(gs_rack_pinion_init)

/* How the pinion radius is given (GS_OPTIONS_Parameterization): the radius
 * (default) or r_P = N_P*x_R/(2*pi); the rack's direction
 * (GS_OPTIONS_RackDirectionality): POSITIVE s_R = +1 (default), NEGATIVE
 * s_R = -1. */
typedef enum { GS_OPTIONS_Parameterization(GS_OPTION_ENUMERATOR_) } gs_rack_parameterization;
typedef enum { GS_OPTIONS_RackDirectionality(GS_OPTION_ENUMERATOR_) } gs_rack_direction;

/* What the user sets: the members of gearsim/parameters.h
 * GS_RACK_PINION_PARAM_LIST, plain data in SI units; defaults from
 * gs_rack_pinion_params_default(). The backlash gap is measured along the
 * rack (base_radius_m unused). */
typedef struct {
    GS_RACK_PINION_PARAM_LIST(GS_PARAM_MEMBER_)
} gs_rack_pinion_params;

/* Every entry of gs_rack_pinion_params, in member order. */
#define GS_RACK_PINION_PARAM_FIELDS (0 GS_RACK_PINION_PARAM_LIST(GS_PARAM_COUNT_))
GS_API extern const gs_param_info gs_rack_pinion_param_info[GS_RACK_PINION_PARAM_FIELDS];

/* What init derives from the parameters (opaque, see GS_BLOCK_CONSTS_REALS);
 * the step only reads it. The state is a gs_block_state. */
typedef struct {
    gs_real opaque_[GS_BLOCK_CONSTS_REALS];
} gs_rack_pinion_consts;

/* Port inputs: rigid mesh uses pinion_speed and rack_force (form A); backlash
 * uses pinion_speed and rack_velocity (form C). */
typedef struct {
    gs_real pinion_speed_rad_s;
    gs_real rack_velocity_m_s; /* backlash only */
    gs_real rack_force_N;      /* rigid only: force the outside applies at R */
    gs_real heat_flow_W;
    gs_real temperature_K;
    int use_temperature_input;
} gs_rack_ports_in;

typedef struct {
    gs_real pinion_torque_Nm; /* tau_P applied by the outside at P */
    gs_real rack_force_N;     /* F_R applied by the outside at R */
    gs_real rack_velocity_m_s;
    gs_real mesh_loss_force_N; /* F_Coul, sign of v_R */
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
GS_API void gs_rack_pinion_step(const gs_rack_pinion_consts *consts, gs_block_state *state, gs_real dt_s,
                                const gs_rack_ports_in *in, gs_rack_ports_out *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_RACK_PINION_H */
