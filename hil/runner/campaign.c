/*
 * A test campaign in the runner (docs/hil-runner.md, "Scenarios and
 * recording"): --scenario read into the library's scenario and attached to
 * the bridge, --junit written at the end (atomically), --log recorded through
 * the recorder's ring. Everything here runs before or after the paced loop,
 * except runner_record_*, which only copy into the ring.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "runner.h"

#define SCENARIO_MAX_BYTES (1u << 20)

/* The scenario file's text (at most 1 MiB), or death with one line. */
static char *read_text(const char *path, size_t *length)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        runner_die("--scenario %s: %s", path, strerror(errno));
    }
    char *text = malloc(SCENARIO_MAX_BYTES + 1u);
    if (text == NULL) {
        runner_die("--scenario %s: out of memory", path);
    }
    size_t n = fread(text, 1, SCENARIO_MAX_BYTES + 1u, f);
    int bad = ferror(f);
    fclose(f);
    if (bad || n > SCENARIO_MAX_BYTES) {
        runner_die("--scenario %s: %s", path, bad ? "read error" : "longer than 1 MiB");
    }
    *length = n;
    return text;
}

static void check_output(const runner *r, const char *option, const char *path)
{
    const runner_options *o = &r->options;
    const char *inputs[] = {o->params_path, o->replay, o->scenario, o->rx};
    for (size_t i = 0; i < sizeof inputs / sizeof inputs[0]; ++i) {
        if (inputs[i] != NULL && strcmp(inputs[i], "-") != 0 && runner_same_regular_file(path, inputs[i])) {
            runner_die("%s %s: is an input of the command; choose another file", option, path);
        }
    }
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        runner_die("%s %s: is a directory", option, path);
    }
}

void runner_campaign_start(runner *r)
{
    const runner_options *o = &r->options;
    if (o->junit != NULL && o->scenario == NULL) {
        runner_die("--junit %s: only with --scenario (the verdict is the scenario's)", o->junit);
    }
    if (o->junit != NULL) {
        check_output(r, "--junit", o->junit);
    }
    if (o->log != NULL) {
        check_output(r, "--log", o->log);
        if (!runner_has_log_suffix(o->log)) {
            runner_die("--log %s: the runner records candump .log files", o->log);
        }
        if ((o->out != NULL && runner_same_file(o->log, o->out)) ||
            (o->junit != NULL && strcmp(o->log, o->junit) == 0)) {
            runner_die("--log %s: is another output of the command", o->log);
        }
    }
    if (o->scenario != NULL) {
        size_t length = 0;
        char *text = read_text(o->scenario, &length);
        gs_hil_error err;
        gs_hil_status status =
            gs_hil_scenario_parse(&r->scenario, text, length, o->scenario, r->bridge.config.dbc, r->params.block, &err);
        free(text);
        if (status != GS_HIL_OK || gs_hil_attach_scenario(&r->bridge, &r->scenario, &err) != GS_HIL_OK) {
            runner_die("%s", err.message);
        }
    }
}

void runner_campaign_open_log(runner *r)
{
    const runner_options *o = &r->options;
    if (o->log != NULL) {
        char message[512];
        if (recorder_open(&r->log, o->log, o->channel, o->cpu, message, sizeof message) != 0) {
            runner_die("%s", message);
        }
    }
}

void runner_campaign_abandon(runner *r)
{
    if (r->log.running) {
        recorder_close(&r->log, 0);
    }
}

static void record(runner *r, const gs_hil_frame *frame, double stamp_s, char direction)
{
    if (r->log.running && recorder_put(&r->log, frame, stamp_s, direction) != 0) {
        r->bridge.counters.count[GS_HIL_COUNT_LOG_DROPPED] += 1u; /* flag log_overflow */
    }
}

void runner_record_received(runner *r, const gs_hil_frame *frame)
{
    const gs_hil_bridge *b = &r->bridge;
    /* rig time: the start of the period that applies it (replay's rule reads it back) */
    double t = b->config.stamp_origin_s + (double)b->counters.count[GS_HIL_COUNT_PERIODS] * b->period_s;
    record(r, frame, t, 'R');
}

void runner_record_sent(runner *r, const gs_hil_frame *frame)
{
    record(r, frame, frame->timestamp_s, 'T');
}

/* The verdict to --junit, through a temporary file beside it. */
static void write_junit(runner *r)
{
    const char *path = r->options.junit;
    size_t n = gs_hil_junit(&r->bridge, NULL, 0);
    char *xml = malloc(n + 1u);
    if (xml == NULL) {
        runner_die("--junit %s: out of memory", path);
    }
    gs_hil_junit(&r->bridge, xml, n + 1u);
    char tmp[PATH_MAX + 64];
    const char *slash = strrchr(path, '/');
    int dir_len = slash == NULL ? 0 : (int)(slash - path + 1);
    snprintf(tmp, sizeof tmp, "%.*s.gearsim-tmp-XXXXXX.xml", dir_len, path);
    int fd = mkstemps(tmp, 4);
    if (fd < 0) {
        runner_die("--junit %s: cannot write there: %s", path, strerror(errno));
    }
    mode_t mask = umask(0);
    umask(mask);
    (void)fchmod(fd, 0666 & ~mask);
    FILE *f = fdopen(fd, "w");
    int bad = f == NULL || fwrite(xml, 1, n, f) != n;
    bad |= f != NULL && fclose(f) != 0;
    free(xml);
    if (bad || rename(tmp, path) != 0) {
        unlink(tmp);
        runner_die("--junit %s: write failed", path);
    }
}

int runner_campaign_finish(runner *r)
{
    const runner_options *o = &r->options;
    if (o->log != NULL) {
        r->report.log_written = r->log.written;
        if (recorder_close(&r->log, 1) != 0) {
            runner_die("--log %s: write failed", o->log);
        }
        r->report.log_written = r->log.written;
    }
    if (o->scenario == NULL) {
        return 0;
    }
    gs_hil_finish_scenario(&r->bridge);
    if (o->junit != NULL) {
        write_junit(r);
    }
    unsigned passed, failed, pending;
    gs_hil_verdict_counts(&r->bridge, &passed, &failed, &pending);
    return failed + pending > 0u ? RUNNER_EXIT_VERDICT_FAILED : 0;
}
