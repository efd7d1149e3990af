/*
 * tests/c/test_common.h - helpers shared by the gearsim C tests (cmocka).
 *
 * Expected values in the tests are computed by hand from docs/physics.md in
 * double precision, from the gs_real parameters actually passed to the library
 * (cast to double), so the float build is checked against the same formulas
 * with float-appropriate tolerances.
 */
#ifndef GEARSIM_TEST_COMMON_H
#define GEARSIM_TEST_COMMON_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "gearsim/gearsim.h"

/* Tolerances per precision.
 * TOL_REL    closed-form quantities (a handful of roundings),
 * TOL_ACC    quantities accumulated over hundreds or thousands of steps,
 * TOL_ENERGY relative slack of per-step energy inequalities (rounding only),
 * GS_EPS     machine epsilon of gs_real. */
#ifdef GS_SINGLE_PRECISION
#define TOL_REL    3e-5
#define TOL_ACC    3e-3
#define TOL_ENERGY 1e-4
#define GS_EPS     1.1920928955078125e-07
#else
#define TOL_REL    1e-11
#define TOL_ACC    1e-8
#define TOL_ENERGY 1e-10
#define GS_EPS     2.220446049250313e-16
#endif

#define TEST_PI 3.14159265358979323846

/* Converts a double computed in a test to gs_real (explicitly, so that the
 * float build stays -Wconversion clean). */
#define R(x) ((gs_real)(x))

static inline double sgn(double x)
{
    return (x > 0.0) ? 1.0 : ((x < 0.0) ? -1.0 : 0.0);
}

static inline int is_zero(double x)
{
    return !(x < 0.0) && !(x > 0.0);
}

static inline double dmax(double a, double b)
{
    return a > b ? a : b;
}

/* |got - want| <= atol + rtol*max(|got|, |want|), and got finite. */
static inline int near_enough(double got, double want, double rtol, double atol)
{
    double scale = dmax(fabs(got), fabs(want));
    return isfinite(got) && fabs(got - want) <= atol + rtol * scale;
}

static inline void assert_near_impl(double got, double want, double rtol, double atol, const char *expr,
                                    const char *file, int line)
{
    if (!near_enough(got, want, rtol, atol)) {
        print_error("%s:%d: %s = %.17g, expected %.17g (diff %.3g, rtol %.3g, atol %.3g)\n", file, line, expr, got,
                    want, fabs(got - want), rtol, atol);
        _fail(file, line);
    }
}

#define ASSERT_NEAR(got, want, rtol, atol) \
    assert_near_impl((double)(got), (double)(want), (double)(rtol), (double)(atol), #got, __FILE__, __LINE__)

/* Asserts a <= b + slack, printing both sides on failure. */
static inline void assert_le_impl(double a, double b, double slack, const char *ea, const char *eb, const char *file,
                                  int line)
{
    if (!(a <= b + slack)) {
        print_error("%s:%d: expected %s <= %s (+%.3g): %.17g > %.17g\n", file, line, ea, eb, slack, a, b);
        _fail(file, line);
    }
}

#define ASSERT_LE(a, b, slack) assert_le_impl((double)(a), (double)(b), (double)(slack), #a, #b, __FILE__, __LINE__)

/* ---- Deterministic PRNG (xorshift64), independent of the C library. */
typedef struct {
    uint64_t s;
} test_rng;

static inline test_rng rng_seed(uint64_t seed)
{
    test_rng r;
    r.s = seed ? seed : 0x9E3779B97F4A7C15ULL;
    return r;
}

static inline uint64_t rng_next(test_rng *r)
{
    uint64_t x = r->s;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    r->s = x;
    return x;
}

/* Uniform in [0, 1). */
static inline double rng_unit(test_rng *r)
{
    return (double)(rng_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniform in [lo, hi). */
static inline double rng_range(test_rng *r, double lo, double hi)
{
    return lo + (hi - lo) * rng_unit(r);
}

/* ---- FNV-1a 64 over raw bytes. */
static inline uint64_t fnv1a64(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; ++i) {
        h ^= (uint64_t)p[i];
        h *= 0x100000001B3ULL;
    }
    return h;
}

#define FNV1A64_OFFSET 0xCBF29CE484222325ULL

/* ---- Initialisation helpers: fail the test with the reported parameter. */
static inline void report_init_failure(const char *what, gs_status st, const gs_error *err, const char *file, int line)
{
    print_error("%s:%d: %s failed: status %d (%s), parameter '%s', message '%s'\n", file, line, what, (int)st,
                gs_status_str(st), err->parameter ? err->parameter : "(null)", err->message ? err->message : "(null)");
    _fail(file, line);
}

/* Calls an init function (its gs_error * last) and fails the test, naming
 * the reported parameter, unless it returns GS_OK. */
#define INIT_OK(init, ...)                                                            \
    do {                                                                              \
        gs_error err_;                                                                \
        gs_status st_;                                                                \
        memset(&err_, 0, sizeof err_);                                                \
        st_ = init(__VA_ARGS__, &err_);                                               \
        if (st_ != GS_OK) report_init_failure(#init, st_, &err_, __FILE__, __LINE__); \
    } while (0)

/* A rig or block in the tests: the constants init derives (read-only
 * afterwards) and the state a step updates, side by side. The API takes
 * them apart: gs_rig_step(&rig.c, &rig.s, ...); a snapshot is a copy of .s. */
typedef struct {
    gs_rig_consts c;
    gs_rig_state s;
} test_rig;

typedef struct {
    gs_simple_gear_consts c;
    gs_block_state s;
} test_gear;

typedef struct {
    gs_rack_pinion_consts c;
    gs_block_state s;
} test_rack;

/* Each takes a pointer to a test_rig / test_gear / test_rack. */
#define INIT_GEAR_RIG(rig, gp, rp) INIT_OK(gs_rig_init_gear, &(rig)->c, &(rig)->s, (gp), (rp))
#define INIT_RACK_RIG(rig, pp, rp) INIT_OK(gs_rig_init_rack, &(rig)->c, &(rig)->s, (pp), (rp))
#define INIT_GEAR(gear, gp)        INIT_OK(gs_simple_gear_init, &(gear)->c, &(gear)->s, (gp))
#define INIT_RACK(rp_, pp)         INIT_OK(gs_rack_pinion_init, &(rp_)->c, &(rp_)->s, (pp))

static inline gs_rig_input rig_input_blank(void)
{
    gs_rig_input in;
    memset(&in, 0, sizeof in);
    in.ambient_temperature = R(300.0);
    in.measured_temperature = R(300.0);
    return in;
}

/* Speed-driven and torque-driven inputs. */
static inline gs_rig_input rig_speed_input(double base_speed, double load)
{
    gs_rig_input in = rig_input_blank();
    in.base_speed = R(base_speed);
    in.load = R(load);
    return in;
}

static inline gs_rig_input rig_torque_input(double motor_torque, double load)
{
    gs_rig_input in = rig_input_blank();
    in.base_torque = R(motor_torque);
    in.load = R(load);
    return in;
}

static inline double gear_sign(gs_output_rotation r)
{
    return (r == GS_ROTATES_SAME) ? 1.0 : -1.0;
}

static inline double rack_sign(gs_rack_direction d)
{
    return (d == GS_RACK_POSITIVE) ? 1.0 : -1.0;
}

/* Every output field must be finite. */
static inline int rig_output_finite(const gs_rig_output *o)
{
    const gs_real *v = (const gs_real *)(const void *)o;
    int i;
    for (i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
        if (!isfinite((double)v[i])) return 0;
    }
    return 1;
}

/* The n outputs of a and b are the same bits (determinism checks). */
static inline void assert_outputs_identical(const gs_rig_output *a, const gs_rig_output *b, size_t n, const char *what)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        if (memcmp(&a[k], &b[k], sizeof a[k]) != 0) {
            print_error("%s: outputs differ first at sample %lu\n", what, (unsigned long)k);
            fail();
        }
    }
}

#endif /* GEARSIM_TEST_COMMON_H */
