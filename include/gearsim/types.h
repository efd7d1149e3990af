/*
 * gearsim/types.h - shared types of the gearsim C core.
 *
 * Real type, export macro, status codes, the validation error report, table
 * capacity, the option enums shared by both blocks and the backlash
 * parameters. Sign convention and equations: docs/physics.md.
 */
#ifndef GEARSIM_TYPES_H
#define GEARSIM_TYPES_H

#include <stddef.h>

#include "gearsim/fields.h"
#include "gearsim/version.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Marks the public API. The library is built with hidden visibility, so only
 * what carries GS_API is exported from the shared library. A consumer may
 * predefine GS_API (e.g. empty). */
#ifndef GS_API
#if defined(__GNUC__) || defined(__clang__)
#define GS_API __attribute__((visibility("default")))
#else
#define GS_API
#endif
#endif

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
    GS_E_MAGNITUDE = -16,           /* so small that its reciprocal overflows gs_real */
    GS_E_BREAKAWAY = -17,           /* breakaway friction > 0 but below the Coulomb friction */
    GS_E_COMBINATION = -18          /* not available with the other options (compliance:
                                       speed-driven base and rigid mesh only) */
} gs_status;

/* The most negative status: every status lies in [GS_STATUS_MIN, GS_OK]. */
#define GS_STATUS_MIN GS_E_COMBINATION

/* Returns a static, human-readable description of a status (never NULL). */
GS_API const char *gs_status_str(gs_status status);

/* The version of the built library (GS_VERSION_STRING when it was compiled):
 * compare with the header's GS_VERSION_STRING to catch a stale library. */
GS_API const char *gs_version(void);

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

/* The state of a block's mesh (gearsim/fields.h GS_BLOCK_STATE_LIST): plain
 * data, a snapshot is a copy of it. *_init and *_reset set it; the step
 * updates it. */
typedef struct {
    GS_BLOCK_STATE_LIST(GS_FIELD_MEMBER_)
} gs_block_state;

/* One entry of the run-time field tables (gs_rig_input_info, ...): what
 * gearsim/fields.h declares, with the member's offset for generic access. */
typedef struct {
    const char *name;      /* the field's name in every layer */
    const char *gear_unit; /* unit in the Simple Gear rig (pint syntax) */
    const char *rack_unit; /* unit in the Rack & Pinion rig */
    const char *doc;       /* one-line description */
    size_t offset;         /* byte offset of the member in its struct */
    int is_integer;        /* 1: an int member, 0: a gs_real member */
} gs_field_info;

/* Storage of the constants a block's init derives (opaque: the layout is
 * internal and may change between versions; the size is part of the ABI).
 * Plain data without pointers: init once, then read-only, so it may be
 * const-qualified, copied, or placed in flash as an image of an initialised
 * block (same precision and target ABI). */
#ifdef GS_SINGLE_PRECISION
#define GS_BLOCK_CONSTS_REALS 150
#else
#define GS_BLOCK_CONSTS_REALS 146
#endif

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_TYPES_H */
