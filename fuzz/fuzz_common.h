/* fuzz_common.h - helpers shared by the gearsim libFuzzer targets.
 *
 * Built with clang -fsanitize=fuzzer,address,undefined (scripts/hardening.sh,
 * docs/hardening.md), in double and in float (-DGS_SINGLE_PRECISION).
 * The input bytes are read as a sequence of small records; running out of
 * bytes yields zeros, so every input is valid. */
#ifndef GEARSIM_FUZZ_COMMON_H
#define GEARSIM_FUZZ_COMMON_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gearsim/gearsim.h"

#ifdef GS_SINGLE_PRECISION
#define FZ_EPS    ((double)FLT_EPSILON)
#define FZ_MAX    FLT_MAX
#define FZ_MIN    FLT_MIN
#define FZ_DENORM 1.40129846e-45f
#else
#define FZ_EPS    DBL_EPSILON
#define FZ_MAX    DBL_MAX
#define FZ_MIN    DBL_MIN
#define FZ_DENORM 4.9406564584124654e-324
#endif

/* Violations of a property: print what and where, then abort so that
 * libFuzzer records the input as a crash. */
#define FZ_CHECK(cond, ...)                                                    \
    do {                                                                       \
        if (!(cond)) {                                                         \
            fprintf(stderr, "gearsim fuzz: property violated: %s\n  ", #cond); \
            fprintf(stderr, __VA_ARGS__);                                      \
            fprintf(stderr, "\n");                                             \
            abort();                                                           \
        }                                                                      \
    } while (0)

typedef struct {
    const uint8_t *p;
    size_t n;
} fz_reader;

static inline uint8_t fz_u8(fz_reader *r)
{
    if (r->n == 0) {
        return 0;
    }
    --r->n;
    return *r->p++;
}

static inline void fz_bytes(fz_reader *r, void *dst, size_t n)
{
    uint8_t *d = (uint8_t *)dst;
    for (size_t i = 0; i < n; ++i) {
        d[i] = fz_u8(r);
    }
}

static inline uint32_t fz_u32(fz_reader *r)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
        v |= (uint32_t)fz_u8(r) << (8 * i);
    }
    return v;
}

/* A value in [lo, hi] from 2 bytes (uniform). */
static inline double fz_range(fz_reader *r, double lo, double hi)
{
    const double u = (double)((unsigned)fz_u8(r) | ((unsigned)fz_u8(r) << 8)) / 65535.0;
    return lo + (hi - lo) * u;
}

/* A value in [lo, hi] (lo > 0) from 2 bytes, uniform in log10. */
static inline double fz_log_range(fz_reader *r, double lo, double hi)
{
    return lo * pow(hi / lo, fz_range(r, 0.0, 1.0));
}

/* FZ_VERBOSE is set in the environment: read once, as it is asked for every
 * record and every step. */
static inline int fz_verbose(void)
{
    static int verbose = -1;
    if (verbose < 0) {
        verbose = getenv("FZ_VERBOSE") != NULL;
    }
    return verbose;
}

static inline int fz_finite(gs_real x)
{
    return isfinite(x) != 0;
}

/* Values at the edges of the real type and of the parameters' validity. */
static inline gs_real fz_interesting(unsigned i)
{
    static const gs_real table[] = {(gs_real)0.0,
                                    (gs_real)-0.0,
                                    (gs_real)1.0,
                                    (gs_real)-1.0,
                                    (gs_real)0.5,
                                    (gs_real)2.0,
                                    (gs_real)1e-3,
                                    (gs_real)1e3,
                                    (gs_real)1e-6,
                                    (gs_real)1e6,
                                    (gs_real)1e9,
                                    (gs_real)1e-9,
                                    (gs_real)1e-30,
                                    (gs_real)1e30,
                                    FZ_MIN,
                                    FZ_MAX,
                                    -FZ_MAX,
                                    FZ_DENORM,
                                    (gs_real)INFINITY,
                                    (gs_real)-INFINITY,
                                    (gs_real)NAN,
                                    (gs_real)(1.0 - FZ_EPS),
                                    (gs_real)(1.0 + FZ_EPS),
                                    (gs_real)300.0,
                                    (gs_real)280.0,
                                    (gs_real)1e-4,
                                    (gs_real)0.98,
                                    (gs_real)0.05,
                                    (gs_real)1e12,
                                    (gs_real)1e-12,
                                    (gs_real)1e-20,
                                    (gs_real)1e20,
                                    (gs_real)-1e-3,
                                    (gs_real)0.1};
    return table[i % (sizeof table / sizeof table[0])];
}

/* One real from a record: mode byte + 8 payload bytes.
 *   0: the raw bit pattern of a gs_real (anything: NaN, inf, subnormal);
 *   1: an interesting value;
 *   2: +-10^(k/8), k in [-128, 127] (1e-16 .. 1e16);
 *   3: k/256 for a 16-bit signed k. */
static inline gs_real fz_real(uint8_t mode, const uint8_t payload[8])
{
    switch (mode & 3U) {
    case 0: {
        gs_real v;
        memcpy(&v, payload, sizeof v);
        return v;
    }
    case 1:
        return fz_interesting(payload[0]);
    case 2: {
        const double v = pow(10.0, (double)(int8_t)payload[0] / 8.0);
        return (gs_real)((payload[1] & 1U) ? -v : v);
    }
    default:
        return (gs_real)((double)(int16_t)(payload[0] | (payload[1] << 8)) / 256.0);
    }
}

/* One int (counts, flags, enums) from a record. */
static inline int fz_int(uint8_t mode, const uint8_t payload[8])
{
    if ((mode & 3U) == 0) {
        int32_t v;
        memcpy(&v, payload, sizeof v);
        return (int)v;
    }
    return (int)payload[0] - 4; /* -4 .. 251 */
}

/* The outputs of a rig step as an array of GS_RIG_OUTPUT_FIELDS reals (every
 * member is a gs_real, gearsim/rig.h), in the order of gs_rig_output_info,
 * which names them for the checks' messages. */
static inline const gs_real *fz_rig_output_values(const gs_rig_output *o)
{
    return (const gs_real *)(const void *)o;
}

/* ---- parameter field tables: every field of the params structs, with its
 * offset, kind and element count, so that records patch fields by index and
 * a corpus means the same in double and float builds. */
typedef enum { FZ_REAL, FZ_INT, FZ_ENUM } fz_kind;

typedef struct {
    size_t offset;
    fz_kind kind;
    int count;
    size_t elem_size;
    const char *name;
} fz_field;

#define FZ_F(type, member, kind)                                              \
    {                                                                         \
        offsetof(type, member), kind, 1, sizeof(((type *)0)->member), #member \
    }
#define FZ_A(type, member, n)                                        \
    {                                                                \
        offsetof(type, member), FZ_REAL, n, sizeof(gs_real), #member \
    }

#define FZ_BACKLASH_FIELDS(type)                                                                        \
    FZ_F(type, backlash.enabled, FZ_INT), FZ_F(type, backlash.hard_stop_model, FZ_ENUM),                \
        FZ_F(type, backlash.linear_backlash_m, FZ_REAL), FZ_F(type, backlash.base_radius_m, FZ_REAL),   \
        FZ_F(type, backlash.transition_region_m, FZ_REAL), FZ_F(type, backlash.stiffness_N_m, FZ_REAL), \
        FZ_F(type, backlash.damping_N_s_m, FZ_REAL), FZ_F(type, backlash.initial_position_m, FZ_REAL),  \
        FZ_F(type, backlash.no_pull, FZ_INT), FZ_F(type, backlash.lock_enabled, FZ_INT),                \
        FZ_F(type, backlash.contact_speed_threshold_m_s, FZ_REAL),                                      \
        FZ_F(type, backlash.contact_release_force_N, FZ_REAL)

static const fz_field fz_gear_fields[] = {
    FZ_F(gs_simple_gear_params, teeth_ratio, FZ_REAL),
    FZ_F(gs_simple_gear_params, output_shaft_rotates, FZ_ENUM),
    FZ_F(gs_simple_gear_params, friction_model, FZ_ENUM),
    FZ_F(gs_simple_gear_params, loss_smoothing, FZ_ENUM),
    FZ_F(gs_simple_gear_params, efficiency_const, FZ_REAL),
    FZ_F(gs_simple_gear_params, power_threshold_W, FZ_REAL),
    FZ_F(gs_simple_gear_params, idle_torque_Nm, FZ_REAL),
    FZ_F(gs_simple_gear_params, nominal_output_torque_Nm, FZ_REAL),
    FZ_F(gs_simple_gear_params, efficiency_nominal, FZ_REAL),
    FZ_F(gs_simple_gear_params, speed_threshold_rad_s, FZ_REAL),
    FZ_F(gs_simple_gear_params, temperature_count, FZ_INT),
    FZ_A(gs_simple_gear_params, temperature_vector_K, GS_TABLE_MAX),
    FZ_A(gs_simple_gear_params, efficiency_vector, GS_TABLE_MAX),
    FZ_F(gs_simple_gear_params, load_count, FZ_INT),
    FZ_A(gs_simple_gear_params, load_vector_Nm, GS_TABLE_MAX),
    FZ_A(gs_simple_gear_params, efficiency_matrix, GS_TABLE_MAX *GS_TABLE_MAX),
    FZ_BACKLASH_FIELDS(gs_simple_gear_params),
    FZ_A(gs_simple_gear_params, viscous_coefficients, 2),
    FZ_F(gs_simple_gear_params, thermal_mass_J_K, FZ_REAL),
    FZ_F(gs_simple_gear_params, initial_temperature_K, FZ_REAL),
};

static const fz_field fz_rack_fields[] = {
    FZ_F(gs_rack_pinion_params, parameterization, FZ_ENUM),
    FZ_F(gs_rack_pinion_params, pinion_radius_m, FZ_REAL),
    FZ_F(gs_rack_pinion_params, teeth_count, FZ_REAL),
    FZ_F(gs_rack_pinion_params, spacing_m, FZ_REAL),
    FZ_F(gs_rack_pinion_params, rack_directionality, FZ_ENUM),
    FZ_F(gs_rack_pinion_params, friction_model, FZ_ENUM),
    FZ_F(gs_rack_pinion_params, loss_smoothing, FZ_ENUM),
    FZ_F(gs_rack_pinion_params, efficiency_const, FZ_REAL),
    FZ_F(gs_rack_pinion_params, temperature_count, FZ_INT),
    FZ_A(gs_rack_pinion_params, temperature_vector_K, GS_TABLE_MAX),
    FZ_A(gs_rack_pinion_params, efficiency_vector, GS_TABLE_MAX),
    FZ_F(gs_rack_pinion_params, power_threshold_W, FZ_REAL),
    FZ_F(gs_rack_pinion_params, pinion_viscous_coefficient, FZ_REAL),
    FZ_F(gs_rack_pinion_params, rack_viscous_coefficient, FZ_REAL),
    FZ_F(gs_rack_pinion_params, thermal_mass_J_K, FZ_REAL),
    FZ_F(gs_rack_pinion_params, initial_temperature_K, FZ_REAL),
    FZ_BACKLASH_FIELDS(gs_rack_pinion_params),
};

static const fz_field fz_rig_fields[] = {
    FZ_F(gs_rig_params, dt_s, FZ_REAL),
    FZ_F(gs_rig_params, base_drive, FZ_ENUM),
    FZ_F(gs_rig_params, base_inertia_kg_m2, FZ_REAL),
    FZ_F(gs_rig_params, initial_base_speed_rad_s, FZ_REAL),
    FZ_F(gs_rig_params, driven_inertia, FZ_REAL),
    FZ_F(gs_rig_params, load_coulomb_friction, FZ_REAL),
    FZ_F(gs_rig_params, load_coulomb_speed_threshold, FZ_REAL),
    FZ_F(gs_rig_params, load_offset, FZ_REAL),
    FZ_F(gs_rig_params, heat_path, FZ_INT),
    FZ_F(gs_rig_params, thermal_resistance_K_W, FZ_REAL),
    FZ_F(gs_rig_params, temperature_source, FZ_ENUM),
    FZ_F(gs_rig_params, accel_filter_time_constant_s, FZ_REAL),
    FZ_F(gs_rig_params, contact_substeps, FZ_INT),
    /* appended: the indices above keep their meaning for the seeds */
    FZ_F(gs_rig_params, load_breakaway_friction, FZ_REAL),
    FZ_F(gs_rig_params, load_stribeck_speed, FZ_REAL),
    FZ_F(gs_rig_params, compliance_stiffness_Nm_rad, FZ_REAL),
    FZ_F(gs_rig_params, compliance_damping_Nm_s_rad, FZ_REAL),
    FZ_A(gs_rig_params, ripple_revolution_amplitude_Nm, GS_RIPPLE_HARMONICS),
    FZ_A(gs_rig_params, ripple_revolution_phase_rad, GS_RIPPLE_HARMONICS),
    FZ_A(gs_rig_params, ripple_mesh_amplitude_Nm, GS_RIPPLE_HARMONICS),
    FZ_A(gs_rig_params, ripple_mesh_phase_rad, GS_RIPPLE_HARMONICS),
    FZ_F(gs_rig_params, ripple_mesh_teeth, FZ_INT),
    FZ_F(gs_rig_params, load_friction_regularised, FZ_INT),
    FZ_F(gs_rig_params, base_speed_ramp, FZ_INT),
};

#define FZ_COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* Applies one 11-byte record (field, element, mode, 8 payload bytes) to the
 * struct at base described by fields[]. Enum and int fields get the bytes of
 * an int (enums are int-sized on the fuzzing host). */
static inline void fz_patch(fz_reader *r, void *base, const fz_field *fields, size_t nfields)
{
    const uint8_t which = fz_u8(r);
    const uint8_t elem = fz_u8(r);
    const uint8_t mode = fz_u8(r);
    uint8_t payload[8];
    fz_bytes(r, payload, sizeof payload);
    const fz_field *f = &fields[which % nfields];
    unsigned char *dst = (unsigned char *)base + f->offset;
    const int verbose = fz_verbose();
    if (f->kind == FZ_REAL) {
        const gs_real v = fz_real(mode, payload);
        memcpy(dst + (size_t)(elem % (unsigned)f->count) * sizeof(gs_real), &v, sizeof v);
        if (verbose) {
            fprintf(stderr, "  set %s[%u] = %.17g\n", f->name, elem % (unsigned)f->count, (double)v);
        }
    } else {
        const int v = fz_int(mode, payload);
        memcpy(dst, &v, f->elem_size < sizeof v ? f->elem_size : sizeof v);
        if (verbose) {
            fprintf(stderr, "  set %s = %d\n", f->name, v);
        }
    }
}

/* Prints a params struct as C assignments (FZ_VERBOSE): turns a crash input
 * into a standalone reproducer. */
static inline void fz_dump(const char *var, const void *base, const fz_field *fields, size_t nfields)
{
    for (size_t i = 0; i < nfields; ++i) {
        const fz_field *f = &fields[i];
        const unsigned char *src = (const unsigned char *)base + f->offset;
        if (f->kind == FZ_REAL) {
            for (int j = 0; j < f->count; ++j) {
                gs_real v;
                memcpy(&v, src + (size_t)j * sizeof v, sizeof v);
                if (f->count == 1) {
                    fprintf(stderr, "    %s.%s = (gs_real)%.17g;\n", var, f->name, (double)v);
                } else if (v != (gs_real)0.0) {
                    fprintf(stderr, "    ((gs_real *)%s.%s)[%d] = (gs_real)%.17g;\n", var, f->name, j, (double)v);
                }
            }
        } else {
            int v = 0;
            memcpy(&v, src, f->elem_size < sizeof v ? f->elem_size : sizeof v);
            fprintf(stderr, "    %s.%s = %d;\n", var, f->name, v);
        }
    }
}

#endif /* GEARSIM_FUZZ_COMMON_H */
