/*
 * gearsim-hil: the C HIL runner (docs/hil-runner.md).
 *
 *   gearsim-hil --params rig.params [--period S] [--substeps N] [--timeout S]
 *       live:   [--transport candump|socketcan] [--rx PATH] [--tx PATH] [--channel IF]
 *               [--duration S] [--spin-us US] [--fifo PRIO] [--mlockall] [--cpu N] [--json]
 *       replay: --replay LOG.log [-o ANSWERS.log] [--tail S] [--max-gap S] [--json]
 *
 * Live, it paces frame periods on absolute CLOCK_MONOTONIC deadlines
 * (clock_nanosleep TIMER_ABSTIME, timer slack 1 ns, an optional bounded
 * final spin); inside the loop there is no heap, no stdio and no blocking
 * call. Replay drives the same bridge from a candump log in log time, as
 * fast as possible. Bad input: one line on stderr, exit status 2.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gearsim/hil.h"
#include "gearsim/hil_dbc.h"
#include "loop_stats.h"
#include "params.h"
#include "transport.h"

#define EXIT_BAD_INPUT 2

typedef struct {
    const char *params_path;
    double period_s, timeout_s, duration_s, tail_s, max_gap_s, max_lag_s;
    long substeps;
    const char *transport, *rx, *tx, *channel;
    long spin_us, fifo_priority, cpu;
    int mlock, json;
    const char *replay, *out;
} options;

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int signo)
{
    (void)signo;
    stop_requested = 1;
}

static void die(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
static void die(const char *fmt, ...)
{
    va_list ap;
    fputs("gearsim-hil: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(EXIT_BAD_INPUT);
}

static const char usage[] =
    "usage: gearsim-hil --params FILE [--period S] [--substeps N] [--timeout S] [--json]\n"
    "  live:   [--transport candump|socketcan] [--rx PATH|-] [--tx PATH|-] [--channel IF]\n"
    "          [--duration S] [--spin-us US] [--max-lag S] [--fifo PRIO] [--mlockall] [--cpu N]\n"
    "  replay: --replay LOG.log [-o ANSWERS.log] [--tail S] [--max-gap S]\n"
    "  --list-params: the keys of the parameter file; --version: version and precision.\n"
    "  docs/hil-runner.md has the details.\n";

static double number_option(const char *name, const char *text, double low, int low_inclusive)
{
    char *end = NULL;
    errno = 0;
    double x = strtod(text, &end);
    if (end == text || *end != '\0' || errno != 0 || !isfinite(x) || x < low || (!low_inclusive && x <= low)) {
        die("%s %s: expected a number %s %g", name, text, low_inclusive ? ">=" : ">", low);
    }
    return x;
}

static long integer_option(const char *name, const char *text, long low, long high)
{
    char *end = NULL;
    errno = 0;
    long x = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno != 0 || x < low || x > high) {
        die("%s %s: expected an integer in [%ld, %ld]", name, text, low, high);
    }
    return x;
}

static void parse_args(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->period_s = 1e-3;
    o->substeps = 1;
    o->timeout_s = 0.1;
    o->max_gap_s = 60.0;
    o->max_lag_s = 0.1;
    o->transport = "candump";
    o->rx = "-";
    o->tx = "-";
    o->channel = "can0";
    o->spin_us = -1; /* automatic: see spin_ns_for */
    o->fifo_priority = 0;
    o->cpu = -1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage, stdout);
            exit(0);
        }
        if (strcmp(a, "--version") == 0) {
            /* the precision matters: only a double runner matches the Python bindings bit for bit */
            printf("gearsim-hil %s %s\n", GS_VERSION_STRING, sizeof(gs_real) == sizeof(double) ? "double" : "float");
            exit(0);
        }
        if (strcmp(a, "--list-params") == 0) {
            runner_params_list(stdout);
            exit(0);
        }
        if (strcmp(a, "--mlockall") == 0) {
            o->mlock = 1;
            continue;
        }
        if (strcmp(a, "--json") == 0) {
            o->json = 1;
            continue;
        }
        if (i + 1 >= argc) {
            die("%s: %s", a, a[0] == '-' ? "needs a value (or is unknown; see --help)" : "unexpected argument");
        }
        const char *v = argv[++i];
        if (strcmp(a, "--params") == 0) {
            o->params_path = v;
        } else if (strcmp(a, "--period") == 0) {
            o->period_s = number_option(a, v, 0.0, 0);
        } else if (strcmp(a, "--substeps") == 0) {
            o->substeps = integer_option(a, v, 1, 1000000);
        } else if (strcmp(a, "--timeout") == 0) {
            o->timeout_s = number_option(a, v, 0.0, 0);
        } else if (strcmp(a, "--duration") == 0) {
            o->duration_s = number_option(a, v, 0.0, 1);
        } else if (strcmp(a, "--tail") == 0) {
            o->tail_s = number_option(a, v, 0.0, 1);
        } else if (strcmp(a, "--max-gap") == 0) {
            o->max_gap_s = number_option(a, v, 0.0, 0);
        } else if (strcmp(a, "--max-lag") == 0) {
            o->max_lag_s = number_option(a, v, 0.0, 0);
        } else if (strcmp(a, "--transport") == 0) {
            if (strcmp(v, "candump") != 0 && strcmp(v, "socketcan") != 0) {
                die("--transport %s: expected candump or socketcan", v);
            }
            o->transport = v;
        } else if (strcmp(a, "--rx") == 0) {
            o->rx = v;
        } else if (strcmp(a, "--tx") == 0) {
            o->tx = v;
        } else if (strcmp(a, "--channel") == 0) {
            o->channel = v;
        } else if (strcmp(a, "--spin-us") == 0) {
            o->spin_us = integer_option(a, v, 0, 100000);
        } else if (strcmp(a, "--fifo") == 0) {
            o->fifo_priority = integer_option(a, v, 1, 99);
        } else if (strcmp(a, "--cpu") == 0) {
            o->cpu = integer_option(a, v, 0, CPU_SETSIZE - 1);
        } else if (strcmp(a, "--replay") == 0) {
            o->replay = v;
        } else if (strcmp(a, "-o") == 0 || strcmp(a, "--out") == 0) {
            o->out = v;
        } else {
            die("%s: unknown option (see --help)", a);
        }
    }
    if (o->params_path == NULL) {
        die("--params: required (the rig's parameter file; see --help)");
    }
    if (o->out != NULL && o->replay == NULL) {
        die("-o %s: only with --replay (live answers go to --tx)", o->out);
    }
}

/* ---- the rig ------------------------------------------------------------------ */

typedef struct {
    runner_params params;
    gs_rig_consts consts;
    gs_rig_state state;
    gs_hil_bridge bridge;
} runner_rig;

static runner_rig rig; /* static: nothing of the loop's state lives on the heap */

static void init_rig(const options *o, gs_hil_send_fn send, void *context, double stamp_origin_s)
{
    char message[512];
    if (runner_params_load(o->params_path, &rig.params, message, sizeof message) != 0) {
        die("%s", message);
    }
    runner_params *p = &rig.params;
    p->rig.dt_s = (gs_real)(o->period_s / (double)o->substeps); /* as the Python bridge: dt = period / substeps */
    gs_error err;
    gs_status status = p->block == GS_RIG_SIMPLE_GEAR ? gs_rig_init_gear(&rig.consts, &rig.state, &p->gear, &p->rig, &err)
                                                      : gs_rig_init_rack(&rig.consts, &rig.state, &p->rack, &p->rig, &err);
    if (status != GS_OK) {
        die("%s: %s: %s", o->params_path, err.parameter ? err.parameter : "?", err.message ? err.message : gs_status_str(status));
    }
    if (!(isfinite(p->ambient_temperature_K) && p->ambient_temperature_K > 0)) {
        die("%s: run.ambient_temperature_K: must be a finite temperature > 0 K", o->params_path);
    }
    gs_hil_config config;
    memset(&config, 0, sizeof config);
    config.dbc = p->block == GS_RIG_SIMPLE_GEAR ? &gs_hil_dbc_gear_rig : &gs_hil_dbc_rack_rig;
    config.base_drive = p->rig.base_drive;
    config.dt_s = p->rig.dt_s;
    config.substeps = (unsigned)o->substeps;
    config.timeout_s = o->timeout_s;
    config.ambient_temperature_K = p->ambient_temperature_K;
    config.stamp_origin_s = stamp_origin_s;
    config.send = send;
    config.send_context = context;
    gs_hil_error herr;
    if (gs_hil_bridge_init(&rig.bridge, &config, p->block, &rig.consts, &rig.state, &herr) != GS_HIL_OK) {
        die("--%s: %s", herr.parameter, herr.message);
    }
}

/* ---- summary ---------------------------------------------------------------------- */

typedef struct {
    int live;
    double wall_s, cpu_s;
    uint64_t frames_in, frames_out, malformed_lines, write_errors;
    const loop_stats *stats;
} run_report;

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

static void print_summary(const options *o, const run_report *r)
{
    const gs_hil_bridge *b = &rig.bridge;
    const gs_hil_counters *c = &b->counters;
    FILE *out = stderr;
    if (!o->json) {
        for (int k = 0; k < GS_HIL_COUNTS; ++k) {
            fprintf(out, "%-22s %llu\n", gs_hil_count_name((gs_hil_count)k), (unsigned long long)c->count[k]);
        }
        for (int k = 1; k < GS_HIL_REASONS; ++k) {
            if (c->reasons[k] != 0u) {
                fprintf(out, "  %-20s %llu\n", gs_hil_reason_name((gs_hil_reason)k), (unsigned long long)c->reasons[k]);
            }
        }
        fprintf(out, "%-22s %.6f s\n", "simulated_time", (double)c->count[GS_HIL_COUNT_PERIODS] * b->period_s);
        if (r->live) {
            fprintf(out, "%-22s %.3f / %.3f / %.3f us (median / p99 / max)\n", "lateness",
                    loop_histogram_quantile_us(&r->stats->lateness, 0.5),
                    loop_histogram_quantile_us(&r->stats->lateness, 0.99), (double)r->stats->lateness.max_ns / 1e3);
            fprintf(out, "%-22s %.1f %%\n", "cpu_share", r->wall_s > 0 ? 100.0 * r->cpu_s / r->wall_s : 0.0);
        }
        return;
    }
    fputs("{", out);
    for (int k = 0; k < GS_HIL_COUNTS; ++k) {
        fprintf(out, "\"%s\": %llu, ", gs_hil_count_name((gs_hil_count)k), (unsigned long long)c->count[k]);
    }
    fputs("\"reasons\": {", out);
    const char *sep = "";
    for (int k = 1; k < GS_HIL_REASONS; ++k) {
        if (c->reasons[k] != 0u) {
            fprintf(out, "%s\"%s\": %llu", sep, gs_hil_reason_name((gs_hil_reason)k), (unsigned long long)c->reasons[k]);
            sep = ", ";
        }
    }
    char t1[32], t2[32], t3[32];
    fprintf(out, "}, \"steps\": %llu, \"pending\": %u, \"simulated_time\": %s, \"period\": %s, "
                 "\"substeps\": %ld, \"timeout\": %s, ",
            (unsigned long long)c->steps, gs_hil_pending(b),
            exact((double)c->count[GS_HIL_COUNT_PERIODS] * b->period_s, t1, sizeof t1), exact(b->period_s, t2, sizeof t2),
            o->substeps, exact((double)b->timeout_periods * b->period_s, t3, sizeof t3));
    /* the state flags are the first three of gs_hil_flag (b->flag_state) */
    fputs("\"state\": {", out);
    for (int k = GS_HIL_FLAG_CMD_TIMEOUT; k <= GS_HIL_FLAG_DRIVE_DISABLED; ++k) {
        fprintf(out, "%s\"%s\": %s", k > GS_HIL_FLAG_CMD_TIMEOUT ? ", " : "", gs_hil_flag_name((gs_hil_flag)k),
                b->flag_state[k] ? "true" : "false");
    }
    fputs("}, ", out);
    fprintf(out, "\"frames_in\": %llu, \"frames_out\": %llu, \"malformed_lines\": %llu, \"write_errors\": %llu, "
                 "\"wall_time\": %.6f, \"cpu_time\": %.6f",
            (unsigned long long)r->frames_in, (unsigned long long)r->frames_out, (unsigned long long)r->malformed_lines,
            (unsigned long long)r->write_errors, r->wall_s, r->cpu_s);
    if (r->live) {
        fprintf(out, ", \"cpu_share\": %.6f, \"loop\": {", r->wall_s > 0 ? r->cpu_s / r->wall_s : 0.0);
        loop_histogram_json(out, "lateness", &r->stats->lateness);
        fputs(", ", out);
        loop_histogram_json(out, "period_error", &r->stats->period_error);
        fputs(", ", out);
        loop_histogram_json(out, "work", &r->stats->work);
        fputs("}", out);
    }
    fputs("}\n", out);
}

static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + (double)ru.ru_utime.tv_usec * 1e-6 + (double)ru.ru_stime.tv_sec +
           (double)ru.ru_stime.tv_usec * 1e-6;
}

static double seconds_of(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ---- output files: never an input, written atomically ------------------------------- */

static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* Regular files only: /dev/null or a terminal may well be both ends. */
static int same_regular_file(const char *a, const char *b)
{
    struct stat st;
    return stat(a, &st) == 0 && S_ISREG(st.st_mode) && same_file(a, b);
}

static int has_log_suffix(const char *path)
{
    size_t n = strlen(path);
    return n > 4 && strcasecmp(path + n - 4, ".log") == 0;
}

/* ---- replay --------------------------------------------------------------------------- */

typedef struct {
    FILE *out;
    uint64_t frames_out;
    int failed;
} replay_sink;

static int replay_send(void *context, const gs_hil_frame *frame)
{
    replay_sink *sink = context;
    char line[128];
    size_t n = candump_format_line(frame, frame->timestamp_s, "vcan0", line, sizeof line);
    sink->frames_out++;
    if (sink->out != NULL && (n == 0 || fwrite(line, 1, n, sink->out) != n)) {
        sink->failed = 1;
    }
    return 0;
}

static FILE *open_answers(const options *o, char *tmp, size_t tmp_size)
{
    if (o->out == NULL) {
        return NULL;
    }
    if (!has_log_suffix(o->out)) {
        die("-o %s: the runner writes candump .log files (python-can converts: python -m can.logconvert)", o->out);
    }
    if (same_file(o->out, o->replay) || same_file(o->out, o->params_path)) {
        die("-o %s: is an input of the command; choose another file", o->out);
    }
    struct stat st;
    if (stat(o->out, &st) == 0 && S_ISDIR(st.st_mode)) {
        die("-o %s: is a directory", o->out);
    }
    const char *slash = strrchr(o->out, '/');
    int dir_len = slash == NULL ? 0 : (int)(slash - o->out + 1);
    snprintf(tmp, tmp_size, "%.*s.gearsim-tmp-XXXXXX.log", dir_len, o->out);
    int fd = mkstemps(tmp, 4);
    if (fd < 0) {
        die("-o %s: cannot write there: %s", o->out, strerror(errno));
    }
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, stat(o->out, &st) == 0 ? (st.st_mode & 07777) : (0666 & ~mask));
    FILE *f = fdopen(fd, "w");
    if (f == NULL) {
        die("-o %s: %s", o->out, strerror(errno));
    }
    return f;
}

static int run_replay(const options *o)
{
    if (!has_log_suffix(o->replay)) {
        die("--replay %s: the runner reads candump .log files (python-can converts: python -m can.logconvert)", o->replay);
    }
    char tmp[PATH_MAX + 64];
    replay_sink sink = {NULL, 0, 0};
    double origin = 0.0;
    int have_origin = 0;
    double previous = 0.0;
    uint64_t frames_in = 0;
    unsigned long line_no = 0;
    char line[4096];
    /* the parameters first (the bridge's errors name them), then the log and the output */
    init_rig(o, replay_send, &sink, 0.0);
    FILE *log = fopen(o->replay, "r");
    if (log == NULL) {
        die("--replay %s: %s", o->replay, strerror(errno));
    }
    sink.out = open_answers(o, tmp, sizeof tmp);
    gs_hil_bridge *b = &rig.bridge;
    double start = seconds_of(CLOCK_MONOTONIC), cpu0 = cpu_seconds();
    while (fgets(line, sizeof line, log) != NULL) {
        line_no++;
        size_t len = strlen(line);
        gs_hil_frame frame;
        size_t k = 0;
        while (k < len && (line[k] == ' ' || line[k] == '\t' || line[k] == '\r' || line[k] == '\n')) {
            ++k;
        }
        if (k == len) {
            continue;
        }
        if ((len == sizeof line - 1 && line[len - 1] != '\n') || candump_parse_line(line, len, &frame) != 0) {
            if (sink.out != NULL) {
                fclose(sink.out);
                unlink(tmp);
            }
            die("--replay %s: line %lu: not a candump -L frame", o->replay, line_no);
        }
        frames_in++;
        if (have_origin && fabs(frame.timestamp_s - previous) > o->max_gap_s) {
            if (sink.out != NULL) {
                fclose(sink.out);
                unlink(tmp);
            }
            die("--replay %s: frame %llu (line %lu): time jumps by %.6g s, more than --max-gap %g s", o->replay,
                (unsigned long long)frames_in, line_no, fabs(frame.timestamp_s - previous), o->max_gap_s);
        }
        previous = frame.timestamp_s;
        if (!have_origin) {
            origin = frame.timestamp_s;
            have_origin = 1;
            b->config.stamp_origin_s = origin;
        }
        gs_hil_advance_to(b, frame.timestamp_s - origin);
        gs_hil_handle(b, &frame);
    }
    fclose(log);
    gs_hil_advance(b, 1u + gs_hil_periods_in(b, o->tail_s));
    gs_hil_close(b);
    run_report report = {0, seconds_of(CLOCK_MONOTONIC) - start, cpu_seconds() - cpu0, frames_in, sink.frames_out, 0, 0, NULL};
    int used = b->counters.count[GS_HIL_COUNT_RX_USED] != 0u;
    if (sink.out != NULL) {
        int bad = sink.failed || fclose(sink.out) != 0;
        if (bad || !used || rename(tmp, o->out) != 0) {
            unlink(tmp);
            if (bad) {
                die("-o %s: write failed", o->out);
            }
        }
    }
    print_summary(o, &report);
    if (!used) {
        die("--replay %s: none of the %llu frames was a command the model could use (a log of another rig, or "
            "the wrong --params?)", o->replay, (unsigned long long)frames_in);
    }
    return 0;
}

/* ---- live ------------------------------------------------------------------------------ */

static transport bus;      /* static: fixed buffers, no heap */
static loop_stats stats;
static double wall_now_s;  /* CLOCK_REALTIME of the current period: stamps of sent frames */
static uint64_t live_frames_in, live_frames_out;

static void live_handle(void *context, const gs_hil_frame *frame)
{
    (void)context;
    live_frames_in++;
    gs_hil_handle(&rig.bridge, frame);
}

static int live_send(void *context, const gs_hil_frame *frame)
{
    (void)context;
    if (transport_send(&bus, frame, wall_now_s) != 0) {
        return -1;
    }
    live_frames_out++;
    return 0;
}

static void real_time_setup(const options *o)
{
    /* default slack (50 us) would make every wake-up late by up to that */
    if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) != 0) {
        die("prctl(PR_SET_TIMERSLACK): %s", strerror(errno));
    }
    if (o->cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET((size_t)o->cpu, &set);
        if (sched_setaffinity(0, sizeof set, &set) != 0) {
            die("--cpu %ld: cannot pin the runner there: %s", o->cpu, strerror(errno));
        }
    }
    if (o->mlock && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        die("--mlockall: not permitted: %s (needs CAP_IPC_LOCK or a large enough ulimit -l)", strerror(errno));
    }
    if (o->fifo_priority > 0) {
        struct sched_param sp;
        memset(&sp, 0, sizeof sp);
        sp.sched_priority = (int)o->fifo_priority;
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            die("--fifo %ld: SCHED_FIFO not permitted: %s (needs root, CAP_SYS_NICE or ulimit -r >= %ld)",
                o->fifo_priority, strerror(errno), o->fifo_priority);
        }
    }
}

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void sleep_until_ns(int64_t t)
{
    struct timespec ts = {(time_t)(t / 1000000000), (long)(t % 1000000000)};
    /* EINTR (a signal): the loop checks the stop flag */
    (void)clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
}

/* The final busy-wait before each deadline. Automatic (no --spin-us): 200 us,
 * at most half the period. On this kind of VM a vCPU that idles for most of a
 * 1 ms period wakes up tens to hundreds of microseconds late even with 1 ns
 * timer slack; 200 us of spin absorbs that (measured p99 lateness at 1 kHz:
 * 54 us with a 50 us spin, 0.1 us with 200 us), at about 20 % of a core. */
static int64_t spin_ns_for(long spin_us, int64_t period_ns)
{
    if (spin_us >= 0) {
        return (int64_t)spin_us * 1000;
    }
    const int64_t automatic = 200000;
    return automatic < period_ns / 2 ? automatic : period_ns / 2;
}

/* The paced loop. Only clock reads, clock_nanosleep, non-blocking read/write
 * and the bridge run here. */
static void paced_loop(const options *o, uint64_t end_period)
{
    gs_hil_bridge *b = &rig.bridge;
    const int64_t period_ns = (int64_t)llround(b->period_s * 1e9);
    const int64_t spin_ns = spin_ns_for(o->spin_us, period_ns);
    const int64_t max_lag_ns = (int64_t)llround(o->max_lag_s * 1e9);
    int64_t deadline = now_ns();
    int64_t previous_start = -1;
    while (!stop_requested && (end_period == 0u || b->counters.count[GS_HIL_COUNT_PERIODS] < end_period)) {
        int64_t t = now_ns();
        if (deadline - spin_ns > t) {
            sleep_until_ns(deadline - spin_ns);
            if (stop_requested) {
                break;
            }
        }
        int64_t start = now_ns();
        while (start < deadline) { /* bounded by spin_ns (plus the sleep's own lateness) */
            start = now_ns();
        }
        int64_t late = start - deadline;
        loop_histogram_add(&stats.lateness, late);
        if (previous_start >= 0) {
            int64_t err = start - previous_start - period_ns;
            loop_histogram_add(&stats.period_error, err < 0 ? -err : err);
        }
        previous_start = start;
        if (late > period_ns) {
            b->counters.count[GS_HIL_COUNT_OVERRUNS]++;
        }
        if (late > max_lag_ns) {
            b->counters.count[GS_HIL_COUNT_RESYNCS]++;
            deadline = start;
        }
        wall_now_s = seconds_of(CLOCK_REALTIME);
        transport_poll(&bus, wall_now_s, live_handle, NULL);
        gs_hil_advance(b, 1);
        transport_flush(&bus);
        loop_histogram_add(&stats.work, now_ns() - start);
        deadline += period_ns;
    }
}

static int run_live(const options *o)
{
    char message[512];
    if (strcmp(o->tx, "-") != 0 &&
        (same_regular_file(o->tx, o->params_path) || (strcmp(o->rx, "-") != 0 && same_regular_file(o->tx, o->rx)))) {
        die("--tx %s: is an input of the command; choose another file", o->tx);
    }
    init_rig(o, live_send, NULL, 0.0);
    int opened = strcmp(o->transport, "socketcan") == 0 ? transport_open_socketcan(&bus, o->channel, message, sizeof message)
                                                        : transport_open_candump(&bus, o->rx, o->tx, message, sizeof message);
    if (opened != 0) {
        die("%s", message);
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: clock_nanosleep returns at once */
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN); /* a closed reader: EPIPE, counted, not a crash */
    real_time_setup(o);
    memset(&stats, 0, sizeof stats); /* touch the histograms before the loop (page faults) */
    double period = rig.bridge.period_s;
    uint64_t end = o->duration_s > 0.0 ? (uint64_t)nearbyint(o->duration_s / period) : 0u;
    if (o->duration_s > 0.0 && end == 0u) {
        end = 1u;
    }
    double start = seconds_of(CLOCK_MONOTONIC), cpu0 = cpu_seconds();
    paced_loop(o, end);
    double wall = seconds_of(CLOCK_MONOTONIC) - start, cpu = cpu_seconds() - cpu0;
    gs_hil_close(&rig.bridge);
    transport_drain(&bus, 1000);
    run_report report = {1, wall, cpu, live_frames_in, live_frames_out, bus.malformed_lines, bus.write_errors, &stats};
    transport_close(&bus);
    print_summary(o, &report);
    return 0;
}

int main(int argc, char **argv)
{
    options o;
    parse_args(argc, argv, &o);
    return o.replay != NULL ? run_replay(&o) : run_live(&o);
}
