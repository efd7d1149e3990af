/*
 * Replay (docs/hil-runner.md, "Replay"): a candump -L log drives the bridge
 * in log time, as fast as possible and deterministically, the rule of
 * gs_hil_advance_to, which gearsim hil replay follows too. The answers go to
 * -o atomically, through a temporary file beside it.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "candump.h"
#include "runner.h"

typedef struct {
    FILE *out;
    uint64_t frames_out;
    int failed;
    runner *r;
} replay_sink;

static int replay_send(void *context, const gs_hil_frame *frame)
{
    replay_sink *sink = context;
    runner_record_sent(sink->r, frame);
    char line[128];
    size_t n = candump_format_line(frame, frame->timestamp_s, "vcan0", line, sizeof line);
    sink->frames_out++;
    if (sink->out != NULL && (n == 0 || fwrite(line, 1, n, sink->out) != n)) {
        sink->failed = 1;
    }
    return 0;
}

/* The temporary file the answers go to (its name in tmp), or NULL without -o. */
static FILE *open_answers(const runner_options *o, char *tmp, size_t tmp_size)
{
    if (o->out == NULL) {
        return NULL;
    }
    if (!runner_has_log_suffix(o->out)) {
        runner_die("-o %s: the runner writes candump .log files (python-can converts: python -m can.logconvert)",
                   o->out);
    }
    if (runner_same_file(o->out, o->replay) || runner_same_file(o->out, o->params_path)) {
        runner_die("-o %s: is an input of the command; choose another file", o->out);
    }
    struct stat st;
    if (stat(o->out, &st) == 0 && S_ISDIR(st.st_mode)) {
        runner_die("-o %s: is a directory", o->out);
    }
    const char *slash = strrchr(o->out, '/');
    int dir_len = slash == NULL ? 0 : (int)(slash - o->out + 1);
    snprintf(tmp, tmp_size, "%.*s.gearsim-tmp-XXXXXX.log", dir_len, o->out);
    int fd = mkstemps(tmp, 4);
    if (fd < 0) {
        runner_die("-o %s: cannot write there: %s", o->out, strerror(errno));
    }
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, stat(o->out, &st) == 0 ? (st.st_mode & 07777) : (0666 & ~mask));
    FILE *f = fdopen(fd, "w");
    if (f == NULL) {
        runner_die("-o %s: %s", o->out, strerror(errno));
    }
    return f;
}

/* Stop on bad input: the temporary answers go, one line, exit 2. */
static void abandon(replay_sink *sink, const char *tmp)
{
    runner_campaign_abandon(sink->r);
    if (sink->out != NULL) {
        fclose(sink->out);
        unlink(tmp);
    }
}

/* Every frame of the log into the bridge, each at its log time. */
static void drive(runner *r, FILE *log, replay_sink *sink, const char *tmp)
{
    const runner_options *o = &r->options;
    gs_hil_bridge *b = &r->bridge;
    double origin = 0.0, previous = 0.0;
    unsigned long line_no = 0;
    char line[4096];
    while (fgets(line, sizeof line, log) != NULL) {
        line_no++;
        size_t len = strlen(line);
        gs_hil_frame frame;
        if (candump_is_blank(line, len)) {
            continue;
        }
        if ((len == sizeof line - 1 && line[len - 1] != '\n') || candump_parse_line(line, len, &frame) != 0) {
            abandon(sink, tmp);
            runner_die("--replay %s: line %lu: not a candump -L frame", o->replay, line_no);
        }
        r->report.frames_in++;
        if (r->report.frames_in > 1u && fabs(frame.timestamp_s - previous) > o->max_gap_s) {
            abandon(sink, tmp);
            runner_die("--replay %s: frame %llu (line %lu): time jumps by %.6g s, more than --max-gap %g s", o->replay,
                       (unsigned long long)r->report.frames_in, line_no, fabs(frame.timestamp_s - previous),
                       o->max_gap_s);
        }
        previous = frame.timestamp_s;
        if (r->report.frames_in == 1u) {
            origin = frame.timestamp_s;
            b->config.stamp_origin_s = origin; /* answers in the log's time base */
        }
        uint64_t end = gs_hil_scenario_end(b);
        if (end > 0u && gs_hil_period_at(b, frame.timestamp_s - origin) > end) {
            r->report.frames_in--;
            break; /* after the scenario's end: the run it describes is over */
        }
        gs_hil_advance_to(b, frame.timestamp_s - origin);
        runner_record_received(r, &frame);
        gs_hil_handle(b, &frame);
    }
}

int runner_replay(runner *r)
{
    const runner_options *o = &r->options;
    if (!runner_has_log_suffix(o->replay)) {
        runner_die("--replay %s: the runner reads candump .log files (python-can converts: python -m can.logconvert)",
                   o->replay);
    }
    char tmp[PATH_MAX + 64];
    replay_sink sink = {NULL, 0, 0, r};
    /* the parameters first (the bridge's errors name them), then the log and the output */
    runner_init_rig(r, replay_send, &sink, 0);
    FILE *log = fopen(o->replay, "r");
    if (log == NULL) {
        runner_die("--replay %s: %s", o->replay, strerror(errno));
    }
    if (o->log != NULL && runner_same_file(o->log, o->replay)) {
        runner_die("--log %s: is an input of the command; choose another file", o->log);
    }
    runner_campaign_start(r);
    sink.out = open_answers(o, tmp, sizeof tmp);
    runner_campaign_open_log(r);
    gs_hil_bridge *b = &r->bridge;
    double start = runner_seconds_of(CLOCK_MONOTONIC), cpu0 = runner_cpu_seconds();
    drive(r, log, &sink, tmp);
    fclose(log);
    uint64_t end = gs_hil_scenario_end(b);
    if (end == 0u) {
        gs_hil_advance(b, 1u + gs_hil_periods_in(b, o->tail_s)); /* the last command acts, then the tail */
    } else if (end > b->counters.count[GS_HIL_COUNT_PERIODS]) {
        gs_hil_advance(b, end - b->counters.count[GS_HIL_COUNT_PERIODS]); /* a scenario: its duration, as live */
    }
    gs_hil_close(b);
    r->report.wall_s = runner_seconds_of(CLOCK_MONOTONIC) - start;
    r->report.cpu_s = runner_cpu_seconds() - cpu0;
    r->report.frames_out = sink.frames_out;
    int used = b->counters.count[GS_HIL_COUNT_RX_USED] != 0u;
    int status = 0;
    if (used) {
        status = runner_campaign_finish(r);
    } else {
        runner_campaign_abandon(r);
    }
    if (sink.out != NULL) {
        int bad = sink.failed || fclose(sink.out) != 0;
        if (bad || !used || rename(tmp, o->out) != 0) {
            unlink(tmp);
            if (bad) {
                runner_die("-o %s: write failed", o->out);
            }
        }
    }
    runner_print_summary(r);
    if (!used) {
        runner_die("--replay %s: none of the %llu frames was a command the model could use (a log of another rig, or "
                   "the wrong --params?)",
                   o->replay, (unsigned long long)r->report.frames_in);
    }
    return status;
}
