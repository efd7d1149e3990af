/*
 * gearsim-hil, the C HIL runner (docs/hil-runner.md): what its parts share.
 *
 *   cli.c      the command line; starts a replay or a live run
 *   session.c  the rig and its bridge from the parameter file; the report
 *              printed at the end; output files that must not be inputs
 *   replay.c   the bridge driven by a candump log, in log time
 *   live.c     the bridge paced on absolute deadlines over a transport
 *   campaign.c a scenario file on the bridge, its JUnit verdict, the
 *              recording (recorder.c: a ring and a writer thread)
 *
 * One runner value holds the whole state of a run. cli.c allocates it once
 * before anything runs, so the paced loop touches no heap and no part keeps
 * state of its own.
 */
#ifndef GEARSIM_HIL_RUNNER_RUNNER_H
#define GEARSIM_HIL_RUNNER_RUNNER_H

#include <stdint.h>
#include <time.h>

#include "gearsim/hil.h"
#include "loop_stats.h"
#include "params.h"
#include "recorder.h"
#include "transport.h"

#define RUNNER_EXIT_BAD_INPUT      2
#define RUNNER_EXIT_VERDICT_FAILED 3 /* the run ended; an expectation of the scenario failed */

typedef struct {
    const char *params_path;
    double period_s, timeout_s, duration_s, tail_s, max_gap_s, max_lag_s;
    long substeps;
    const char *transport, *rx, *tx, *channel, *listen;
    long spin_us, fifo_priority, cpu;
    int mlock, json, duration_given, wait_client;
    const char *replay, *out;
    const char *scenario, *junit, *log;
} runner_options;

/* What the end-of-run report adds to the bridge's counters. */
typedef struct {
    int live;
    double wall_s, cpu_s;
    uint64_t frames_in, frames_out, malformed_lines, write_errors;
    uint64_t client_connects, client_disconnects; /* socketcand */
    uint64_t log_written;
} runner_report;

typedef struct {
    runner_options options;
    runner_params params;
    gs_rig_consts consts;
    gs_rig_state state;
    gs_hil_bridge bridge;
    runner_report report;
    gs_hil_scenario scenario; /* with --scenario */
    recorder log;             /* with --log */
    /* live runs only */
    transport bus;
    loop_stats stats;
    double wall_now_s; /* CLOCK_REALTIME at the current period: the stamp of the frames it sends */
} runner;

/* One line "gearsim-hil: ..." on stderr, exit status 2 (bad input). */
#ifdef __GNUC__
void runner_die(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
#else
void runner_die(const char *fmt, ...);
#endif

/* The rig from --params and its bridge, sending through send(context, ...);
 * dies with one line on a bad parameter file or bridge configuration. live:
 * parameter requests are prepared by the loop between periods. */
void runner_init_rig(runner *r, gs_hil_send_fn send, void *context, int live);

/* campaign.c: the outputs checked, --scenario read and attached (dies with
 * one line naming the file, line and key). */
void runner_campaign_start(runner *r);
/* --log opened and its writer thread started (last thing before the run);
 * abandon: stopped and its file removed (a run that ends on bad input). */
void runner_campaign_open_log(runner *r);
void runner_campaign_abandon(runner *r);
/* A frame into the recording: received (stamped with the start of the period
 * that applies it) or sent (its own rig-time stamp). Never blocks. */
void runner_record_received(runner *r, const gs_hil_frame *frame);
void runner_record_sent(runner *r, const gs_hil_frame *frame);
/* The end of a run: the scenario closed, --junit and --log written. Returns
 * the exit status: 0, or RUNNER_EXIT_VERDICT_FAILED. */
int runner_campaign_finish(runner *r);

/* The counters, reasons, simulated time and (live) loop timing, on stderr:
 * text, or one JSON object with --json. */
void runner_print_summary(const runner *r);

double runner_cpu_seconds(void);
double runner_seconds_of(clockid_t clock);

/* Both paths name the same existing file; regular files only for the second. */
int runner_same_file(const char *a, const char *b);
int runner_same_regular_file(const char *a, const char *b);

/* The path ends in .log (the runner reads and writes candump logs only). */
int runner_has_log_suffix(const char *path);

int runner_replay(runner *r); /* replay.c */
int runner_live(runner *r);   /* live.c */

#endif
