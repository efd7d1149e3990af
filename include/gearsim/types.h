/*
 * gearsim/types.h - shared types of the gearsim C core.
 *
 * Real type, status codes, the validation error report, table capacities and
 * the option enums shared by both blocks. Sign convention and equations:
 * docs/physics.md (the reference; docs/model.md
 * in this repository records the choices made where it says "proposal").
 */
#ifndef GEARSIM_TYPES_H
#define GEARSIM_TYPES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GS_VERSION_MAJOR 0
#define GS_VERSION_MINOR 1
#define GS_VERSION_PATCH 0
#define GS_VERSION_STRING "0.1.0"

/* Real type: double by default; float when the library is built with the CMake
 * option GEARSIM_SINGLE_PRECISION (which defines GS_SINGLE_PRECISION for the
 * library and for every consumer through the CMake target / pkg-config). A
 * consumer compiled with the other precision fails to link: the init
 * functions carry an _f32 suffix in the float build (GS_PRECISION_NAME). */
#ifdef GS_SINGLE_PRECISION
typedef float gs_real;
#define GS_R(x) (x##f)
#define GS_PRECISION_NAME(name) name##_f32
#else
typedef double gs_real;
#define GS_R(x) (x)
#define GS_PRECISION_NAME(name) name
#endif

/* Capacity of every interpolation table (temperature, load, efficiency). */
#define GS_TABLE_MAX 10

/* Status codes: 0 is success, every error is negative. Each validity rule of
 * docs/physics.md section 9 maps to one status; gs_error names the parameter. */
typedef enum {
    GS_OK = 0,
    GS_E_NULL = -1,                 /* a required pointer argument is NULL */
    GS_E_NOT_FINITE = -2,           /* a parameter is NaN or infinite */
    GS_E_NOT_POSITIVE = -3,         /* must be > 0 */
    GS_E_NEGATIVE = -4,             /* must be >= 0 */
    GS_E_EFFICIENCY_RANGE = -5,     /* efficiency must lie in (0, 1] */
    GS_E_NOMINAL_EFFICIENCY = -6,   /* nominal efficiency must lie in (0, 1) */
    GS_E_IDLE_TORQUE_TOO_LARGE = -7,/* k < 0: g*tau_idle > tau_nom*(1/eta_nom - 1) (eq. 2.5) */
    GS_E_OPTION = -8,               /* enum value outside its option list */
    GS_E_TABLE_LENGTH = -9,         /* table length < 2 or > GS_TABLE_MAX */
    GS_E_TABLE_NOT_INCREASING = -10,/* breakpoints must be strictly increasing */
    GS_E_TABLE_SIZE_MISMATCH = -11, /* data length differs from its breakpoints */
    GS_E_BACKLASH_POSITION = -12,   /* initial position outside [-b/2, b/2] */
    GS_E_TRANSITION_REGION = -13,   /* smooth model: 0 < d required */
    GS_E_STEP_SIZE = -14,           /* rig step dt must be > 0 and finite */
    GS_E_SUBSTEPS = -15,            /* contact sub-step count out of [0, GS_MAX_SUBSTEPS] */
    GS_E_MAGNITUDE = -16            /* so small that its reciprocal overflows gs_real */
} gs_status;

/* The most negative status: every status lies in [GS_STATUS_MIN, GS_OK]. */
#define GS_STATUS_MIN GS_E_MAGNITUDE

/* Returns a static, human-readable description of a status (never NULL). */
const char *gs_status_str(gs_status status);

/* Filled by every *_init: which rule failed and for which parameter.
 * parameter is the program name of docs/physics.md section 9 (e.g.
 * "teeth_ratio", "efficiency_vector"), or "" when status is GS_OK.
 * Both strings are static. */
typedef struct {
    gs_status status;
    const char *parameter;
    const char *message;
} gs_error;

/* Meshing-loss (friction) models. Rack & Pinion accepts NONE, CONSTANT and
 * TEMPERATURE only. */
typedef enum {
    GS_FRICTION_NONE = 0,
    GS_FRICTION_CONSTANT_EFFICIENCY = 1,
    GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY = 2,
    GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY = 3,
    GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY = 4
} gs_friction_model;

/* Power-threshold smoothing of the efficiency laws (docs/physics.md 2.1/2.2).
 * PASSIVE (default) never produces negative loss power; SIMSCAPE reproduces
 * eq. 2.1, which is slightly active for 0 < p << p_th. */
typedef enum {
    GS_SMOOTHING_PASSIVE = 0,
    GS_SMOOTHING_SIMSCAPE = 1
} gs_loss_smoothing;

/* Hard-stop contact laws of the backlash (docs/physics.md eqs 4.3-4.5). */
typedef enum {
    GS_HARD_STOP_SMOOTH = 0,        /* stiffness and damping through the transition region, damped rebound */
    GS_HARD_STOP_FULL_UNDAMPED = 1, /* full stiffness and damping at bounds, undamped rebound */
    GS_HARD_STOP_FULL_DAMPED = 2    /* full stiffness and damping at bounds, damped rebound */
} gs_hard_stop_model;

/* Backlash parameters, shared by both blocks. For the Rack & Pinion the gap is
 * measured along the rack and base_radius_m is ignored (the pinion radius is
 * used). */
typedef struct {
    int enabled;                          /* 0 = rigid mesh, 1 = backlash */
    gs_hard_stop_model hard_stop_model;   /* default GS_HARD_STOP_SMOOTH */
    gs_real linear_backlash_m;            /* b, total free travel at the pitch line (> 0), default 1e-3 */
    gs_real base_radius_m;                /* r_B (> 0), default 0.1 (Simple Gear only) */
    gs_real transition_region_m;          /* d (> 0, smooth model), default 1e-4 */
    gs_real stiffness_N_m;                /* K (> 0), default 1e6 */
    gs_real damping_N_s_m;                /* D (>= 0), default 1e3 */
    gs_real initial_position_m;           /* x0 in [-b/2, b/2], default 0 (centred) */
    int no_pull;                          /* 1 (default): contact force never pulls the teeth together */
    int lock_enabled;                     /* 1: static contact lock (physics.md 4, PROP), default 0 */
    gs_real contact_speed_threshold_m_s;  /* v_th (> 0, lock mode), default 1e-3 */
    gs_real contact_release_force_N;      /* f_th (>= 0, lock mode), default 0 */
} gs_backlash_params;

/* ---- Internal model state. Plain data, no pointers: copying a model or rig
 * is a snapshot, copying it back restores it. Read the outputs, not these. */
typedef struct {
    gs_real x[GS_TABLE_MAX];
    gs_real y[GS_TABLE_MAX];
    int n;
} gs_table1_;

typedef struct {
    gs_real x[GS_TABLE_MAX];       /* rows: temperature, K */
    gs_real y[GS_TABLE_MAX];       /* columns: base load, N*m */
    gs_real z[GS_TABLE_MAX][GS_TABLE_MAX];
    int nx;
    int ny;
} gs_table2_;

/* The mesh shared by both blocks: omega_B = ratio * omega_F, where ratio =
 * s*g (Simple Gear) or s_R/r_P (Rack & Pinion, follower = rack). */
typedef struct {
    /* constants */
    gs_real ratio;              /* omega_B / omega_F (signed) */
    gs_real inv_ratio;          /* omega_F / omega_B */
    gs_real base_radius;        /* r_B or r_P, m (backlash geometry) */
    gs_real follower_radius;    /* r_F (m) or 1 for the rack */
    gs_real direction;          /* s or s_R, +1 or -1 */
    gs_real mu_base;            /* viscous, N*m/(rad/s) */
    gs_real mu_follower;        /* viscous, N*m/(rad/s) or N/(m/s) */
    gs_friction_model friction;
    gs_loss_smoothing smoothing;
    gs_real eta;                /* constant efficiency */
    gs_real power_threshold;    /* W */
    gs_real inv_power_threshold;
    gs_real coulomb_idle;       /* g*tau_idle, follower-referred, N*m */
    gs_real load_slope;         /* k of eq. 2.5 */
    gs_real inv_speed_threshold;/* 1/omega_th */
    gs_real base_load_scale;    /* |T_F| -> base load: 1/g */
    gs_table1_ eta_of_T;
    gs_table2_ eta_of_T_load;
    int thermal_enabled;
    gs_real thermal_mass;       /* J/K */
    gs_real initial_temperature;/* K */
    /* backlash constants */
    int backlash;
    gs_hard_stop_model hard_stop;
    gs_real half_gap;           /* b/2, m */
    gs_real inv_transition;     /* 1/d */
    gs_real stiffness;
    gs_real damping;
    gs_real initial_position;
    int no_pull;
    int lock_enabled;
    gs_real lock_speed;
    gs_real lock_release_force;
    /* state */
    gs_real temperature;        /* T_th, K */
    gs_real position;           /* x, m */
    gs_real contact_force;      /* last f, N */
    gs_real last_follower_torque; /* T_F of the last step (linearisation seed) */
    int locked;
} gs_mesh_;

/* Constants of the backward-Euler contact for one sub-step length
 * (src/hard_stop.c), computed at init so that the step path divides little. */
typedef struct {
    gs_real h;                   /* sub-step, s */
    gs_real inv_h;               /* 1/h, 1/s */
    gs_real c;                   /* h/m_eff, s/kg */
    gs_real inv_c;               /* m_eff/h, kg/s */
    gs_real c_stiffness;         /* c*K, 1/s */
    gs_real inv_affine_damped;   /* 1/(1 + c*(K*h + D)) */
    gs_real inv_affine_undamped; /* 1/(1 + c*K*h) */
    gs_real draw_dv;             /* K*h + D: d(K*delta + D*v)/dv, N*s/m */
    gs_real dxi_dv;              /* h/d: d(delta/d)/dv for the smooth law, s/m */
    gs_real transition;          /* d, m (smooth law) */
    int law_force_conditioned;   /* kappa = c*(K*h + D) < 1: the law may give the root's force */
} gs_contact_step_;

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_TYPES_H */
