/*
 * gearsim_bench - timing and instruction-count benchmark of the gearsim rigs.
 *
 * Every configuration (bench_common.h) is a speed-driven rig stepped at
 * dt = 1 ms on the same realistic input: a sinusoidal base speed with
 * reversals (two tones, +-24 rad/s peak) and a load that also changes sign, so
 * the loss laws, their power-flow branches, the tables and the backlash contact
 * are all exercised. The input is a precomputed table of one full period (4000
 * samples, 4 s) that is cycled; it joins seamlessly.
 *
 * Usage:
 *   gearsim_bench [--runs N] [--steps N] [--config NAME]... [--json FILE]
 *       Times every configuration (or those named), one call at a time
 *       (gs_rig_step) and in batches (gs_rig_run over the 4000-sample
 *       table): --runs runs of --steps steps each, after a warm-up run, taken round
 *       robin over the configurations; the rig is reset before every run.
 *       Prints median/min/max/IQR of ns per step, the median steps per
 *       second and the median thread CPU time per step. Never asserts a time.
 *   gearsim_bench --count NAME step|run STEPS
 *       Sets NAME up and steps it STEPS times (STEPS may be 0), nothing else:
 *       the mode for `valgrind --tool=callgrind`, whose total Ir difference
 *       between STEPS and 0 steps, divided by STEPS, is the instruction count
 *       of one step (scripts/bench.sh does this).
 *   gearsim_bench --dump NAME STEPS FILE
 *       Steps NAME STEPS times and writes every gs_rig_output (raw gs_real
 *       values, GS_RIG_OUTPUT_FIELDS per step) to FILE: for comparing builds
 *       (e.g. a candidate optimisation of src/ against the current one).
 *   gearsim_bench --list
 *       Prints the configuration names, one a line.
 *
 * Timing: clock_gettime(CLOCK_MONOTONIC), plus the thread CPU time
 * (CLOCK_THREAD_CPUTIME_ID) as a noise indicator. The outputs are accumulated
 * into a checksum that is printed, so no step can be optimised away.
 */
#define _POSIX_C_SOURCE 199309L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gearsim/gearsim.h"
#include "bench_common.h"

#define MAX_RUNS       101
#define MAX_SELECTED   64
#define PERIOD_SAMPLES BENCH_PERIOD
#define DT_S           BENCH_DT_S

/* The input period of each configuration (the rack's load depends on its
 * radius) and an output buffer for the batch mode. */
static gs_rig_input g_tables[N_CONFIGS][PERIOD_SAMPLES];
static gs_rig_output g_outputs[PERIOD_SAMPLES];

/* The configuration called name, or NULL after saying it is unknown. */
static const bench_config *find_config(const char *name)
{
    for (size_t i = 0; i < N_CONFIGS; ++i) {
        if (strcmp(CONFIGS[i].name, name) == 0) {
            return &CONFIGS[i];
        }
    }
    fprintf(stderr, "gearsim_bench: unknown configuration %s\n", name);
    return NULL;
}

static gs_rig_input *table_of(const bench_config *c)
{
    return g_tables[c - CONFIGS];
}

/* A rig of the benchmark: the constants init derives (read-only afterwards)
 * and the state a step updates. */
typedef struct {
    gs_rig_consts consts;
    gs_rig_state state;
} bench_rig;

/* Initialises the rig and the input table of one configuration. */
static int setup(const bench_config *c, bench_rig *rig)
{
    gs_error err;
    const gs_status s = bench_setup(c, &rig->consts, &rig->state, table_of(c), &err);
    if (s != GS_OK) {
        fprintf(stderr, "gearsim_bench: %s: init failed: %s (%s)\n", c->name, gs_status_str(s), err.parameter);
        return -1;
    }
    return 0;
}

/* Looks up and sets up the configuration called name (the --count and --dump
 * modes): 0, or the exit status (2 unknown name, 1 init failed). */
static int setup_named(const char *name, bench_rig *rig, const bench_config **c)
{
    *c = find_config(name);
    if (*c == NULL) {
        return 2;
    }
    return setup(*c, rig) != 0 ? 1 : 0;
}

/* Checksum of everything a step returns that depends on the state. */
static double sink;

static double steps_one_by_one(bench_rig *rig, const gs_rig_input *inputs, long steps)
{
    gs_rig_output out;
    double acc = 0.0;
    int k = 0;
    for (long i = 0; i < steps; ++i) {
        gs_rig_step(&rig->consts, &rig->state, &inputs[k], &out);
        acc += (double)out.base_torque;
        if (++k == PERIOD_SAMPLES) {
            k = 0;
        }
    }
    return acc;
}

static double steps_batched(bench_rig *rig, const gs_rig_input *inputs, long steps)
{
    double acc = 0.0;
    long done = 0;
    while (done < steps) {
        const long left = steps - done;
        const size_t n = (size_t)(left < PERIOD_SAMPLES ? left : PERIOD_SAMPLES);
        gs_rig_run(&rig->consts, &rig->state, n, inputs, g_outputs);
        acc += (double)g_outputs[n - 1].base_torque;
        done += (long)n;
    }
    return acc;
}

static double clock_ns(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Quantile of sorted data, linear between order statistics. */
static double quantile(const double *sorted, int n, double q)
{
    const double pos = q * (double)(n - 1);
    const int i = (int)pos;
    if (i + 1 >= n) {
        return sorted[n - 1];
    }
    return sorted[i] + (pos - (double)i) * (sorted[i + 1] - sorted[i]);
}

typedef struct {
    double median, min, max, q1, q3; /* wall clock (CLOCK_MONOTONIC), ns per step */
    double cpu_median;               /* thread CPU time, ns per step */
} stats;

/* One timed run from the initial state: wall-clock and thread CPU ns per step.
 * Wall-clock time is what a real-time loop sees; the thread's CPU time leaves
 * out most of the time the thread waited for a core while other processes
 * ran (not hypervisor steal time), so the two together show machine noise. */
static void time_run(bench_rig *rig, const gs_rig_input *inputs, int batched, long steps, double *wall_ns,
                     double *cpu_ns)
{
    gs_rig_reset(&rig->consts, &rig->state);
    const double c0 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    const double t0 = clock_ns(CLOCK_MONOTONIC);
    sink += batched ? steps_batched(rig, inputs, steps) : steps_one_by_one(rig, inputs, steps);
    const double t1 = clock_ns(CLOCK_MONOTONIC);
    const double c1 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
    *wall_ns = (t1 - t0) / (double)steps;
    *cpu_ns = (c1 - c0) / (double)steps;
}

static stats summarise(double *ns, double *cpu, int runs)
{
    qsort(ns, (size_t)runs, sizeof ns[0], cmp_double);
    qsort(cpu, (size_t)runs, sizeof cpu[0], cmp_double);
    stats s;
    s.median = quantile(ns, runs, 0.5);
    s.min = ns[0];
    s.max = ns[runs - 1];
    s.q1 = quantile(ns, runs, 0.25);
    s.q3 = quantile(ns, runs, 0.75);
    s.cpu_median = quantile(cpu, runs, 0.5);
    return s;
}

static int count_mode(const char *name, const char *mode, long steps)
{
    const bench_config *c;
    bench_rig rig;
    const int status = setup_named(name, &rig, &c);
    if (status != 0) {
        return status;
    }
    const int batched = strcmp(mode, "run") == 0;
    if (!batched && strcmp(mode, "step") != 0) {
        fprintf(stderr, "gearsim_bench: mode must be step or run\n");
        return 2;
    }
    const gs_rig_input *inputs = table_of(c);
    const double acc = batched ? steps_batched(&rig, inputs, steps) : steps_one_by_one(&rig, inputs, steps);
    printf("%s %s %ld steps checksum %.17g\n", name, mode, steps, acc);
    return 0;
}

static int dump_mode(const char *name, long steps, const char *path)
{
    const bench_config *c;
    bench_rig rig;
    const int status = setup_named(name, &rig, &c);
    if (status != 0) {
        return status;
    }
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        perror(path);
        return 1;
    }
    gs_rig_output out;
    int k = 0;
    for (long i = 0; i < steps; ++i) {
        gs_rig_step(&rig.consts, &rig.state, &table_of(c)[k], &out);
        if (fwrite(&out, sizeof out, 1, f) != 1) {
            perror(path);
            fclose(f);
            return 1;
        }
        if (++k == PERIOD_SAMPLES) {
            k = 0;
        }
    }
    return fclose(f) == 0 ? 0 : 1;
}

static void usage(void)
{
    fprintf(stderr, "usage: gearsim_bench [--runs N] [--steps N] [--config NAME]... [--json FILE]\n"
                    "       gearsim_bench --count NAME step|run STEPS\n"
                    "       gearsim_bench --dump NAME STEPS FILE\n"
                    "       gearsim_bench --list\n");
}

int main(int argc, char **argv)
{
    int runs = 15;
    long steps = 200000;
    const char *json_path = NULL;
    const bench_config *selected[MAX_SELECTED];
    size_t n_selected = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--list") == 0) {
            for (size_t k = 0; k < N_CONFIGS; ++k) {
                printf("%s\n", CONFIGS[k].name);
            }
            return 0;
        } else if (strcmp(argv[i], "--count") == 0 && i + 3 < argc) {
            return count_mode(argv[i + 1], argv[i + 2], atol(argv[i + 3]));
        } else if (strcmp(argv[i], "--dump") == 0 && i + 3 < argc) {
            return dump_mode(argv[i + 1], atol(argv[i + 2]), argv[i + 3]);
        } else if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
            runs = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
            steps = atol(argv[++i]);
        } else if (strcmp(argv[i], "--json") == 0 && i + 1 < argc) {
            json_path = argv[++i];
        } else if (strcmp(argv[i], "--config") == 0 && i + 1 < argc && n_selected < MAX_SELECTED) {
            const bench_config *c = find_config(argv[++i]);
            if (c == NULL) {
                return 2;
            }
            selected[n_selected++] = c;
        } else {
            usage();
            return 2;
        }
    }
    if (runs < 1 || runs > MAX_RUNS || steps < 1) {
        fprintf(stderr, "gearsim_bench: need 1 <= runs <= %d and steps >= 1\n", MAX_RUNS);
        return 2;
    }
    if (n_selected == 0) {
        for (size_t k = 0; k < N_CONFIGS; ++k) {
            selected[n_selected++] = &CONFIGS[k];
        }
    }
    FILE *json = NULL;
    if (json_path != NULL) {
        json = fopen(json_path, "w");
        if (json == NULL) {
            perror(json_path);
            return 1;
        }
        fprintf(json,
                "{\n  \"precision\": \"%s\",\n  \"runs\": %d,\n  \"steps_per_run\": %ld,\n"
                "  \"dt_s\": %g,\n  \"results\": [\n",
                sizeof(gs_real) == sizeof(double) ? "double" : "float", runs, steps, DT_S);
    }
    printf("gearsim %s, gs_real = %s; %d runs x %ld steps per configuration and mode "
           "(median [min..max], IQR; ns per step)\n",
           GS_VERSION_STRING, sizeof(gs_real) == sizeof(double) ? "double" : "float", runs, steps);
    printf("%-26s %-5s %9s %21s %17s %12s %9s\n", "configuration", "mode", "median", "[min..max]", "IQR", "steps/s",
           "cpu med");
    /* Round robin: run r of every configuration and mode comes before run r+1 of
     * any, so a burst of load on the machine spreads over all of them instead
     * of spoiling one configuration's runs. */
    static bench_rig rigs[MAX_SELECTED];
    static double wall[MAX_SELECTED][2][MAX_RUNS];
    static double cpu[MAX_SELECTED][2][MAX_RUNS];
    for (size_t k = 0; k < n_selected; ++k) {
        if (setup(selected[k], &rigs[k]) != 0) {
            return 1;
        }
    }
    for (int r = -1; r < runs; ++r) { /* r = -1: warm-up */
        for (size_t k = 0; k < n_selected; ++k) {
            for (int batched = 0; batched < 2; ++batched) {
                double w, c;
                time_run(&rigs[k], table_of(selected[k]), batched, steps, &w, &c);
                if (r >= 0) {
                    wall[k][batched][r] = w;
                    cpu[k][batched][r] = c;
                }
            }
        }
    }
    int first = 1;
    for (size_t k = 0; k < n_selected; ++k) {
        const bench_config *c = selected[k];
        gs_rig_info info;
        gs_rig_get_info(&rigs[k].consts, &info);
        for (int batched = 0; batched < 2; ++batched) {
            const stats s = summarise(wall[k][batched], cpu[k][batched], runs);
            const char *mode = batched ? "run" : "step";
            printf("%-26s %-5s %9.1f   [%7.1f..%7.1f]   %6.1f..%6.1f %12.3e %9.1f\n", c->name, mode, s.median, s.min,
                   s.max, s.q1, s.q3, 1e9 / s.median, s.cpu_median);
            if (json != NULL) {
                fprintf(json,
                        "%s    {\"config\": \"%s\", \"description\": \"%s\", \"mode\": \"%s\", "
                        "\"substeps\": %d, \"median_ns\": %.3f, \"min_ns\": %.3f, \"max_ns\": %.3f, "
                        "\"q1_ns\": %.3f, \"q3_ns\": %.3f, \"steps_per_s\": %.1f, \"cpu_median_ns\": %.3f}",
                        first ? "" : ",\n", c->name, c->description, mode, info.contact_substeps, s.median, s.min,
                        s.max, s.q1, s.q3, 1e9 / s.median, s.cpu_median);
                first = 0;
            }
        }
    }
    if (json != NULL) {
        fprintf(json, "\n  ],\n  \"checksum\": %.17g\n}\n", sink);
        fclose(json);
    }
    fprintf(stderr, "checksum %.17g\n", sink);
    return 0;
}
