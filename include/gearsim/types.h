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
#include "gearsim/parameters.h"
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
#define GS_R(x)                 (x##f)
#define GS_PRECISION_NAME(name) name##_f32
#else
typedef double gs_real;
#define GS_R(x)                 (x)
#define GS_PRECISION_NAME(name) name
#endif

/* Capacity of every interpolation table (temperature, load, efficiency). */
#define GS_TABLE_MAX 10

/* Status codes: 0 is success, every error is negative. Each validity rule of
 * docs/physics.md section 9 maps to one status; gs_error names the parameter. */
typedef enum {
    GS_OK = 0,
    GS_E_NULL = -1,                  /* a required pointer argument is NULL */
    GS_E_NOT_FINITE = -2,            /* a parameter is NaN or infinite */
    GS_E_NOT_POSITIVE = -3,          /* must be > 0 */
    GS_E_NEGATIVE = -4,              /* must be >= 0 */
    GS_E_EFFICIENCY_RANGE = -5,      /* efficiency must lie in (0, 1] */
    GS_E_NOMINAL_EFFICIENCY = -6,    /* nominal efficiency must lie in (0, 1) */
    GS_E_IDLE_TORQUE_TOO_LARGE = -7, /* k < 0: g*tau_idle > tau_nom*(1/eta_nom - 1) (eq. 2.5) */
    GS_E_OPTION = -8,                /* enum value outside its option list */
    GS_E_TABLE_LENGTH = -9,          /* table length < 2 or > GS_TABLE_MAX */
    GS_E_TABLE_NOT_INCREASING = -10, /* breakpoints must be strictly increasing */
    GS_E_TABLE_SIZE_MISMATCH = -11,  /* data length differs from its breakpoints */
    GS_E_BACKLASH_POSITION = -12,    /* initial position outside [-b/2, b/2] */
    GS_E_TRANSITION_REGION = -13,    /* smooth model: 0 < d required */
    GS_E_STEP_SIZE = -14,            /* rig step dt must be > 0 and finite */
    GS_E_SUBSTEPS = -15,             /* contact sub-step count out of [0, GS_MAX_SUBSTEPS] */
    GS_E_MAGNITUDE = -16,            /* so small that its reciprocal overflows gs_real */
    GS_E_BREAKAWAY = -17,            /* breakaway friction > 0 but below the Coulomb friction */
    GS_E_COMBINATION = -18           /* not available with the other options (compliance:
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

/* The option enums shared by both blocks, from the option lists of
 * gearsim/parameters.h (names, meaning). Meshing-loss models: the Rack &
 * Pinion accepts NONE, CONSTANT and TEMPERATURE only. Power-threshold
 * smoothing (docs/physics.md 2.1/2.2): PASSIVE (default) never produces
 * negative loss power; SIMSCAPE reproduces eq. 2.1. Hard-stop contact laws:
 * docs/physics.md eqs 4.3-4.5. */
typedef enum { GS_OPTIONS_FrictionModel(GS_OPTION_ENUMERATOR_) } gs_friction_model;
typedef enum { GS_OPTIONS_LossSmoothing(GS_OPTION_ENUMERATOR_) } gs_loss_smoothing;
typedef enum { GS_OPTIONS_HardStopModel(GS_OPTION_ENUMERATOR_) } gs_hard_stop_model;

/* Backlash parameters, shared by both blocks (gearsim/parameters.h
 * GS_BACKLASH_PARAM_LIST). For the Rack & Pinion the gap is measured along
 * the rack and base_radius_m is ignored (the pinion radius is used). */
typedef struct {
    GS_BACKLASH_PARAM_LIST(GS_PARAM_MEMBER_)
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

/* What a parameter is (gearsim/parameters.h): how its member is stored and
 * how the layers above present it. */
typedef enum {
    GS_PARAM_REAL = 0,   /* one gs_real */
    GS_PARAM_INT = 1,    /* one int */
    GS_PARAM_BOOL = 2,   /* 0/1: an int, or a two-valued enum with options */
    GS_PARAM_OPTION = 3, /* an enum, one of its options */
    GS_PARAM_ARRAY = 4,  /* length gs_real, all used */
    GS_PARAM_TABLE = 5,  /* GS_TABLE_MAX gs_real, the used length in the member count */
    GS_PARAM_MATRIX = 6, /* GS_TABLE_MAX x GS_TABLE_MAX gs_real: rows count, columns count2 */
    GS_PARAM_COUNT = 7,  /* an int: the used length of the tables that name it */
    GS_PARAM_GROUP = 8   /* a nested params struct, described by members */
} gs_param_kind;

/* When a parameter may change, and where it is used (distinct bits). */
typedef enum {
    GS_PARAM_FIXED = 0,    /* set before init; fixed while the rig runs */
    GS_PARAM_TUNABLE = 1,  /* may change between the steps of a running rig (re-tuning) */
    GS_PARAM_GEAR_ONLY = 2 /* fixed, and used by the Simple Gear only */
} gs_param_flag;

/* One option of an option parameter. */
typedef struct {
    const char *enumerator; /* the C enumerator, e.g. "GS_FRICTION_NONE" */
    const char *name;       /* the option string, e.g. "none" */
    const char *doc;        /* one-line description */
    int value;              /* the enumerator's value */
} gs_param_option;

/* An option list. */
typedef struct {
    const char *name;             /* e.g. "FrictionModel"; "" for a parameter without options */
    const gs_param_option *items; /* count entries in enum order, NULL when count is 0 */
    size_t count;
} gs_param_options;

/* One entry of the run-time parameter tables (gs_rig_param_info, ...): what
 * gearsim/parameters.h declares, with the member's offset and size for
 * generic access. */
typedef struct gs_param_info_ {
    const char *key;       /* program name: Python keyword, model-file key, FMU
                                             variable, gs_error.parameter (in the gear rig) */
    const char *rack_key;  /* the name in the Rack & Pinion rig */
    const char *member;    /* the C member */
    const char *gear_unit; /* SI unit in pint syntax ("" = dimensionless or not a number) */
    const char *rack_unit; /* the unit in the Rack & Pinion rig */
    const char *doc;       /* one line: meaning and valid range */
    gs_param_kind kind;
    gs_param_flag flags;                  /* FIXED, TUNABLE or GEAR_ONLY */
    size_t offset;                        /* byte offset of the member in its struct */
    size_t size;                          /* sizeof the member (the whole array) */
    size_t length;                        /* values along the first index: 1 for a scalar */
    size_t columns;                       /* values along the second index: 1 unless a matrix */
    const char *count;                    /* TABLE: the COUNT member with its used length; MATRIX:
                                             the rows' count; else "" */
    const char *count2;                   /* MATRIX: the columns' count; else "" */
    const struct gs_param_info_ *members; /* GROUP: the nested struct's table, else NULL */
    size_t member_count;
    const gs_param_options *options; /* the option list (count 0 without options) */
} gs_param_info;

/* Every entry of gs_backlash_params, in member order (GS_BACKLASH_PARAM_FIELDS). */
#define GS_BACKLASH_PARAM_FIELDS (0 GS_BACKLASH_PARAM_LIST(GS_PARAM_COUNT_))
GS_API extern const gs_param_info gs_backlash_param_info[GS_BACKLASH_PARAM_FIELDS];

/* Storage of the constants a block's init derives (opaque: the layout is
 * internal and may change between versions; the size is part of the ABI).
 * Plain data without pointers: init once, then read-only, so it may be
 * const-qualified, copied, or placed in flash as an image of an initialised
 * block (same precision and target ABI). Like GS_RIG_CONSTS_REALS, the count
 * is checked to be exact when the library is compiled. */
#ifdef GS_SINGLE_PRECISION
#define GS_BLOCK_CONSTS_REALS 150
#else
#define GS_BLOCK_CONSTS_REALS 146
#endif

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_TYPES_H */
