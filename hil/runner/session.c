/*
 * The runner's rig and its bridge (from the parameter file and the options),
 * the report printed at the end of a run, and the checks that keep outputs
 * off the inputs (docs/hil-runner.md).
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "gearsim/hil_dbc.h"
#include "runner.h"

void runner_die(const char *fmt, ...)
{
    va_list ap;
    fputs("gearsim-hil: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(RUNNER_EXIT_BAD_INPUT);
}

void runner_init_rig(runner *r, gs_hil_send_fn send, void *context, int live)
{
    const runner_options *o = &r->options;
    char message[512];
    if (runner_params_load(o->params_path, &r->params, message, sizeof message) != 0) {
        runner_die("%s", message);
    }
    runner_params *p = &r->params;
    p->rig.dt_s = (gs_real)(o->period_s / (double)o->substeps); /* as the Python bridge: dt = period / substeps */
    gs_error err;
    gs_status status = p->block == GS_RIG_SIMPLE_GEAR
                           ? gs_rig_init_gear(&r->consts, &r->state, &p->gear, &p->rig, &err)
                           : gs_rig_init_rack(&r->consts, &r->state, &p->rack, &p->rig, &err);
    if (status != GS_OK) {
        runner_die("%s: %s: %s", o->params_path, err.parameter ? err.parameter : "?",
                   err.message ? err.message : gs_status_str(status));
    }
    if (!(isfinite(p->ambient_temperature_K) && p->ambient_temperature_K > 0)) {
        runner_die("%s: run.ambient_temperature_K: must be a finite temperature > 0 K", o->params_path);
    }
    gs_hil_config config;
    memset(&config, 0, sizeof config);
    config.dbc = p->block == GS_RIG_SIMPLE_GEAR ? &gs_hil_dbc_gear_rig : &gs_hil_dbc_rack_rig;
    config.base_drive = p->rig.base_drive;
    config.dt_s = p->rig.dt_s;
    config.substeps = (unsigned)o->substeps;
    config.timeout_s = o->timeout_s;
    config.ambient_temperature_K = p->ambient_temperature_K;
    config.send = send;
    config.send_context = context;
    /* parameter changes at run time start from these (kept in r->params) */
    config.gear_params = &p->gear;
    config.rack_params = &p->rack;
    config.rig_params = &p->rig;
    config.deferred_prepare = live; /* the paced loop derives them after its flush */
    gs_hil_error herr;
    if (gs_hil_bridge_init(&r->bridge, &config, p->block, &r->consts, &r->state, &herr) != GS_HIL_OK) {
        runner_die("--%s: %s", herr.parameter, herr.message);
    }
}

/* ---- the report ------------------------------------------------------------- */

/* A double as the shortest of %.15g / %.17g that reads back exactly (0.1, not 0.10000000000000001). */
static const char *exact(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    double back = strtod(buf, NULL);
    if (back < x || back > x) { /* not the same double */
        snprintf(buf, size, "%.17g", x);
    }
    return buf;
}

static void print_text(const runner *r)
{
    const gs_hil_bridge *b = &r->bridge;
    const gs_hil_counters *c = &b->counters;
    FILE *out = stderr;
    for (int k = 0; k < GS_HIL_COUNTS; ++k) {
        fprintf(out, "%-22s %llu\n", gs_hil_count_name((gs_hil_count)k), (unsigned long long)c->count[k]);
    }
    for (int k = 1; k < GS_HIL_REASONS; ++k) {
        if (c->reasons[k] != 0u) {
            fprintf(out, "  %-20s %llu\n", gs_hil_reason_name((gs_hil_reason)k), (unsigned long long)c->reasons[k]);
        }
    }
    fprintf(out, "%-22s %.6f s\n", "simulated_time", (double)c->count[GS_HIL_COUNT_PERIODS] * b->period_s);
    if (b->scenario != NULL) {
        unsigned passed, failed, pending;
        gs_hil_verdict_counts(b, &passed, &failed, &pending);
        fprintf(out, "%-22s %u passed, %u failed (%s)\n", "verdict", passed, failed + pending, b->scenario->name);
    }
    if (r->options.log != NULL) {
        fprintf(out, "%-22s %llu frames (%llu dropped)\n", "log", (unsigned long long)r->report.log_written,
                (unsigned long long)c->count[GS_HIL_COUNT_LOG_DROPPED]);
    }
    if (r->bus.kind == TRANSPORT_SOCKETCAND && r->report.live) {
        fprintf(out, "%-22s %llu connects, %llu disconnects\n", "socketcand_clients",
                (unsigned long long)r->report.client_connects, (unsigned long long)r->report.client_disconnects);
    }
    if (r->report.live) {
        const loop_histogram *late = &r->stats.lateness;
        fprintf(out, "%-22s %.3f / %.3f / %.3f us (median / p99 / max)\n", "lateness",
                loop_histogram_quantile_us(late, 0.5), loop_histogram_quantile_us(late, 0.99),
                (double)late->max_ns / 1e3);
        fprintf(out, "%-22s %.1f %%\n", "cpu_share",
                r->report.wall_s > 0 ? 100.0 * r->report.cpu_s / r->report.wall_s : 0.0);
    }
}

static void print_json_counters(FILE *out, const runner *r)
{
    const gs_hil_bridge *b = &r->bridge;
    const gs_hil_counters *c = &b->counters;
    for (int k = 0; k < GS_HIL_COUNTS; ++k) {
        fprintf(out, "\"%s\": %llu, ", gs_hil_count_name((gs_hil_count)k), (unsigned long long)c->count[k]);
    }
    fputs("\"reasons\": {", out);
    const char *sep = "";
    for (int k = 1; k < GS_HIL_REASONS; ++k) {
        if (c->reasons[k] != 0u) {
            fprintf(out, "%s\"%s\": %llu", sep, gs_hil_reason_name((gs_hil_reason)k),
                    (unsigned long long)c->reasons[k]);
            sep = ", ";
        }
    }
    char t1[32], t2[32], t3[32];
    double simulated_s = (double)c->count[GS_HIL_COUNT_PERIODS] * b->period_s;
    fprintf(out,
            "}, \"steps\": %llu, \"pending\": %u, \"simulated_time\": %s, \"period\": %s, "
            "\"substeps\": %ld, \"timeout\": %s, ",
            (unsigned long long)c->steps, gs_hil_pending(b), exact(simulated_s, t1, sizeof t1),
            exact(b->period_s, t2, sizeof t2), r->options.substeps,
            exact((double)b->timeout_periods * b->period_s, t3, sizeof t3));
    fputs("\"state\": {", out);
    for (int k = 0; k < GS_HIL_STATE_FLAGS; ++k) {
        fprintf(out, "%s\"%s\": %s", k > 0 ? ", " : "", gs_hil_flag_name((gs_hil_flag)k),
                b->flag_state[k] ? "true" : "false");
    }
    fputs("}, ", out);
}

static void print_json(const runner *r)
{
    const runner_report *rep = &r->report;
    FILE *out = stderr;
    fputs("{", out);
    print_json_counters(out, r);
    fprintf(out,
            "\"frames_in\": %llu, \"frames_out\": %llu, \"malformed_lines\": %llu, \"write_errors\": %llu, "
            "\"wall_time\": %.6f, \"cpu_time\": %.6f",
            (unsigned long long)rep->frames_in, (unsigned long long)rep->frames_out,
            (unsigned long long)rep->malformed_lines, (unsigned long long)rep->write_errors, rep->wall_s, rep->cpu_s);
    fprintf(out, ", \"client_connects\": %llu, \"client_disconnects\": %llu, \"log_written\": %llu",
            (unsigned long long)rep->client_connects, (unsigned long long)rep->client_disconnects,
            (unsigned long long)rep->log_written);
    if (r->bridge.scenario != NULL) {
        unsigned passed, failed, pending;
        gs_hil_verdict_counts(&r->bridge, &passed, &failed, &pending);
        fprintf(out, ", \"verdict\": {\"passed\": %u, \"failed\": %u}", passed, failed + pending);
    }
    if (rep->live) {
        fprintf(out, ", \"cpu_share\": %.6f, \"loop\": {", rep->wall_s > 0 ? rep->cpu_s / rep->wall_s : 0.0);
        loop_histogram_json(out, "lateness", &r->stats.lateness);
        fputs(", ", out);
        loop_histogram_json(out, "period_error", &r->stats.period_error);
        fputs(", ", out);
        loop_histogram_json(out, "work", &r->stats.work);
        fputs("}", out);
    }
    fputs("}\n", out);
}

void runner_print_summary(const runner *r)
{
    if (r->options.json) {
        print_json(r);
    } else {
        print_text(r);
    }
}

double runner_cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + (double)ru.ru_utime.tv_usec * 1e-6 + (double)ru.ru_stime.tv_sec +
           (double)ru.ru_stime.tv_usec * 1e-6;
}

double runner_seconds_of(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ---- output files: never an input ---------------------------------------------- */

int runner_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* Regular files only: /dev/null or a terminal may well be both ends. */
int runner_same_regular_file(const char *a, const char *b)
{
    struct stat st;
    return stat(a, &st) == 0 && S_ISREG(st.st_mode) && runner_same_file(a, b);
}

int runner_has_log_suffix(const char *path)
{
    size_t n = strlen(path);
    return n > 4 && strcasecmp(path + n - 4, ".log") == 0;
}
