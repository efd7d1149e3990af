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
 * Wherever the driven side moves freely (torque-driven base, or backlash),
 * load_coulomb_friction is a true Coulomb friction integrated implicitly: it
 * holds the driven side at rest while the applied torque stays within it and
 * never reverses the motion; the meshing loss can likewise stop the follower
 * but not reverse it. In the speed-driven rigid rig the speed is imposed and
 * the Coulomb friction is tanh-smoothed on load_coulomb_speed_threshold.
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

#define GS_MAX_SUBSTEPS 64
/* The automatic sub-step count (contact_substeps = 0) stops here; see gs_rig_info. */
#define GS_AUTO_SUBSTEPS_MAX 16

typedef enum {
    GS_BASE_SPEED_DRIVEN = 0,
    GS_BASE_TORQUE_DRIVEN = 1
} gs_base_drive;

typedef enum {
    GS_TEMPERATURE_FROM_MODEL = 0,  /* thermal state (5.1) */
    GS_TEMPERATURE_FROM_INPUT = 1   /* measured_temperature_K overrides the state */
} gs_temperature_source;

typedef enum {
    GS_RIG_SIMPLE_GEAR = 0,
    GS_RIG_RACK_PINION = 1
} gs_rig_block;

typedef struct {
    gs_real dt_s;                          /* fixed step (> 0), default 1e-3 */
    gs_base_drive base_drive;              /* default speed-driven */
    gs_real base_inertia_kg_m2;            /* torque-driven: > 0; speed-driven: >= 0 and adds J_B*alpha_B to base_torque; default 0 */
    gs_real initial_base_speed_rad_s;      /* torque-driven start speed, default 0 */
    gs_real driven_inertia;                /* follower_inertia kg*m^2 or rack_mass kg (> 0), default 0.05 */
    gs_real load_coulomb_friction;         /* N*m or N (>= 0), default 0 */
    gs_real load_coulomb_speed_threshold;  /* rad/s or m/s (> 0), tanh(4 w/w_th) smoothing of the
                                              speed-driven rigid rig, default 1e-3 */
    gs_real load_offset;                   /* N*m or N, constant bias on the driven side, default 0 */
    int heat_path;                         /* 1: Q_H = (T_amb - T)/R_th; 0: adiabatic (default 0) */
    gs_real thermal_resistance_K_W;        /* R_th (> 0 when heat_path), default 2 */
    gs_temperature_source temperature_source; /* default from model */
    gs_real accel_filter_time_constant_s;  /* speed-driven: first-order low-pass on the
                                              backward-difference base acceleration (>= 0; 0 = raw), default 0 */
    int contact_substeps;                  /* backlash: sub-steps per step, 1..GS_MAX_SUBSTEPS, 0 = choose at init */
} gs_rig_params;

/* Per-step inputs. All fields are gs_real, so an array of N inputs is an
 * N x 5 array of reals. Unused fields are ignored. */
typedef struct {
    gs_real base_speed_rad_s;       /* speed-driven: held base (pinion) speed */
    gs_real base_torque_Nm;         /* torque-driven: motor torque on the base inertia */
    gs_real load;                   /* external load on the driven side, + along + follower rotation / rack direction */
    gs_real ambient_temperature_K;  /* used when heat_path */
    gs_real measured_temperature_K; /* used when temperature_source = FROM_INPUT */
} gs_rig_input;

#define GS_RIG_INPUT_FIELDS 5

/* Per-step outputs, all gs_real (an N x 15 array of reals). Torques, powers
 * and the contact force are means over the step's sub-steps; speeds, angles,
 * temperature and positions are values at the end of the step. */
typedef struct {
    gs_real base_torque_Nm;         /* torque the drive applies to the base shaft (speed-driven:
                                       base_port_torque + J_B*alpha_B; torque-driven: the input) */
    gs_real base_speed_rad_s;
    gs_real base_angle_rad;
    gs_real follower_speed;           /* follower rad/s or rack m/s */
    gs_real follower_position;        /* follower rad or rack m */
    gs_real base_port_torque_Nm;    /* tau_B: what the base shaft applies to the block */
    gs_real follower_port_torque;     /* tau_F (N*m) or F_R (N): what the driven side applies to the block */
    gs_real mesh_loss_power_W;      /* meshing loss, >= 0 */
    gs_real loss_power_W;           /* mesh + viscous + contact damping, >= 0 */
    gs_real port_power_W;           /* power into the block through both ports */
    gs_real contact_energy_J;       /* energy stored in the backlash spring at the end of the step */
    gs_real temperature_K;          /* block temperature at the end of the step (state, or the input) */
    gs_real backlash_position_m;
    gs_real contact_force_N;
    gs_real follower_acceleration;    /* follower rad/s^2 or rack m/s^2 */
} gs_rig_output;

#define GS_RIG_OUTPUT_FIELDS 15

typedef struct {
    gs_mesh_ mesh;
    gs_rig_block block;
    /* constants */
    gs_real dt;
    gs_base_drive base_drive;
    gs_real base_inertia;
    gs_real initial_base_speed;
    gs_real driven_inertia;
    gs_real load_coulomb;
    gs_real inv_load_speed_threshold;
    gs_real load_offset;
    int heat_path;
    gs_real inv_thermal_resistance;
    gs_temperature_source temperature_source;
    gs_real accel_gain;            /* dt/(tau + dt) */
    int substeps;
    gs_real inv_eff_mass_contact;  /* 1/m_eff at the pitch line, 1/kg */
    gs_real substep;               /* h = dt/substeps, s */
    gs_real inv_substeps;          /* 1/substeps */
    gs_real inv_driven_inertia_sub;/* 1/(J_F + h*mu_F): the implicit viscous term */
    gs_real inv_base_inertia_sub;  /* 1/(J_B + h*mu_B) (torque-driven base) */
    gs_contact_step_ contact;      /* backward-Euler contact constants for h */
    gs_contact_step_ contact_stuck;/* the same with the driven side held by its friction
                                      (torque-driven base: the base inertia alone) */
    int substeps_capped;           /* 1: the automatic count stopped at GS_AUTO_SUBSTEPS_MAX */
    gs_real contact_h_omega_n;     /* h*omega_n of the contact at the chosen sub-step */
    /* state */
    int started;
    gs_real base_speed;
    gs_real base_angle;
    gs_real follower_speed;
    gs_real follower_position;
    gs_real previous_base_speed_input;
    gs_real base_acceleration;
} gs_rig;

gs_rig_params gs_rig_params_default(void);

/* What init chose for the contact integration, for the user to read. */
typedef struct {
    int contact_substeps;       /* sub-steps per step (1 without backlash) */
    gs_real contact_h_omega_n;  /* h*omega_n, omega_n = sqrt(K/m_eff): the contact's
                                   accuracy figure (0 without backlash); <= 0.5 is the
                                   automatic target, about 0.05 resolves a rebound */
    int substeps_capped;        /* 1 when contact_substeps = 0 chose GS_AUTO_SUBSTEPS_MAX
                                   and h*omega_n is still above 0.5: the contact is
                                   stable (backward Euler) but over-damped; lower dt or
                                   set contact_substeps */
} gs_rig_info;

/* Fills info for an initialised rig. */
void gs_rig_get_info(const gs_rig *rig, gs_rig_info *info);

/* Validate the block and rig parameters and fill rig. err names the failing
 * parameter (block names as in docs/physics.md; rig names e.g.
 * "follower_inertia", "rack_mass", "dt"). Never allocates. */
gs_status gs_rig_init_gear(gs_rig *rig, const gs_simple_gear_params *gear,
                           const gs_rig_params *params, gs_error *err);
gs_status gs_rig_init_rack(gs_rig *rig, const gs_rack_pinion_params *rack,
                           const gs_rig_params *params, gs_error *err);

/* Back to the initial state (speeds, angles, temperature, backlash). */
void gs_rig_reset(gs_rig *rig);

/* Copies the state (speeds, angles, temperature, backlash, filters: what
 * gs_rig_reset sets) of `from` into `to`, keeping the constants of `to`. For
 * re-tuning a running rig: init a new rig from the new parameters, then copy
 * the old one's state into it. */
void gs_rig_copy_state(gs_rig *to, const gs_rig *from);

/* One fixed step of dt_s. Cannot fail; bounded cost per instance (fixed
 * sub-step and iteration counts). Inputs must be finite; the outputs are then
 * finite. Speed-driven: the first step after init/reset takes its base speed
 * as the initial state, with the follower geared to it (teeth moving
 * together, no acceleration); feed a zero-speed sample first to start at
 * rest. */
void gs_rig_step(gs_rig *rig, const gs_rig_input *in, gs_rig_output *out);

/* n steps over caller-owned arrays; bit-identical to n calls of gs_rig_step. */
void gs_rig_run(gs_rig *rig, size_t n, const gs_rig_input *in, gs_rig_output *out);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_RIG_H */
