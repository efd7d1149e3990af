/*
 * The live loop (docs/hil-runner.md, "Pacing"): frame periods on absolute
 * CLOCK_MONOTONIC deadlines (clock_nanosleep TIMER_ABSTIME, timer slack
 * 1 ns, a bounded final spin), the transport polled and flushed around each.
 * Inside the loop there is no heap, no stdio and no blocking call.
 * SIGINT and SIGTERM are blocked and looked for once a period
 * (sigpending), so that no handler and no flag outside the runner are
 * needed: the loop stops at the next period boundary.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#include "runner.h"

static void live_handle(void *context, const gs_hil_frame *frame)
{
    runner *r = context;
    r->report.frames_in++;
    runner_record_received(r, frame);
    gs_hil_handle(&r->bridge, frame);
}

static int live_send(void *context, const gs_hil_frame *frame)
{
    runner *r = context;
    if (transport_send(&r->bus, frame, r->wall_now_s) != 0) {
        return -1;
    }
    runner_record_sent(r, frame);
    r->report.frames_out++;
    return 0;
}

static void real_time_setup(const runner_options *o)
{
    /* default slack (50 us) would make every wake-up late by up to that */
    if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) != 0) {
        runner_die("prctl(PR_SET_TIMERSLACK): %s", strerror(errno));
    }
    if (o->cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET((size_t)o->cpu, &set);
        if (sched_setaffinity(0, sizeof set, &set) != 0) {
            runner_die("--cpu %ld: cannot pin the runner there: %s", o->cpu, strerror(errno));
        }
    }
    if (o->mlock && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        runner_die("--mlockall: not permitted: %s (needs CAP_IPC_LOCK or a large enough ulimit -l)", strerror(errno));
    }
    if (o->fifo_priority > 0) {
        struct sched_param sp;
        memset(&sp, 0, sizeof sp);
        sp.sched_priority = (int)o->fifo_priority;
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            runner_die("--fifo %ld: SCHED_FIFO not permitted: %s (needs root, CAP_SYS_NICE or ulimit -r >= %ld)",
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

/* SIGINT or SIGTERM arrived (they are blocked: they wait here). */
static int stop_requested(void)
{
    sigset_t pending;
    return sigpending(&pending) == 0 && (sigismember(&pending, SIGINT) == 1 || sigismember(&pending, SIGTERM) == 1);
}

/* One period's start: its lateness, the period error, overruns and resyncs;
 * returns the deadline after it. */
static int64_t start_period(runner *r, int64_t start, int64_t deadline, int64_t *previous_start, int64_t period_ns)
{
    const int64_t max_lag_ns = (int64_t)llround(r->options.max_lag_s * 1e9);
    uint64_t *count = r->bridge.counters.count;
    int64_t late = start - deadline;
    loop_histogram_add(&r->stats.lateness, late);
    if (*previous_start >= 0) {
        int64_t err = start - *previous_start - period_ns;
        loop_histogram_add(&r->stats.period_error, err < 0 ? -err : err);
    }
    *previous_start = start;
    if (late > period_ns) {
        count[GS_HIL_COUNT_OVERRUNS]++;
    }
    if (late > max_lag_ns) {
        count[GS_HIL_COUNT_RESYNCS]++;
        return start;
    }
    return deadline;
}

/* The paced loop: clock reads, clock_nanosleep, non-blocking read/write,
 * sigpending and the bridge. */
static void paced_loop(runner *r, uint64_t end_period)
{
    gs_hil_bridge *b = &r->bridge;
    const int64_t period_ns = (int64_t)llround(b->period_s * 1e9);
    const int64_t spin_ns = spin_ns_for(r->options.spin_us, period_ns);
    int64_t deadline = now_ns();
    int64_t previous_start = -1;
    while (!stop_requested() && (end_period == 0u || b->counters.count[GS_HIL_COUNT_PERIODS] < end_period)) {
        if (deadline - spin_ns > now_ns()) {
            sleep_until_ns(deadline - spin_ns);
        }
        int64_t start = now_ns();
        while (start < deadline) { /* bounded by spin_ns (plus the sleep's own lateness) */
            start = now_ns();
        }
        deadline = start_period(r, start, deadline, &previous_start, period_ns);
        r->wall_now_s = runner_seconds_of(CLOCK_REALTIME);
        transport_poll(&r->bus, r->wall_now_s, live_handle, r);
        gs_hil_advance(b, 1);
        transport_flush(&r->bus);
        gs_hil_prepare(b); /* parameter requests: derived after the answers are out, swapped next period */
        loop_histogram_add(&r->stats.work, now_ns() - start);
        deadline += period_ns;
    }
}

static void open_transport(runner *r)
{
    const runner_options *o = &r->options;
    char message[512];
    int opened = strcmp(o->transport, "socketcan") == 0
                     ? transport_open_socketcan(&r->bus, o->channel, message, sizeof message)
                 : strcmp(o->transport, "socketcand") == 0
                     ? transport_open_socketcand(&r->bus, o->listen, o->channel, message, sizeof message)
                     : transport_open_candump(&r->bus, o->rx, o->tx, message, sizeof message);
    if (opened != 0) {
        runner_die("%s", message);
    }
    if (r->bus.kind == TRANSPORT_SOCKETCAND) {
        /* the address a client connects to (a port of 0 chose a free one) */
        fprintf(stderr, "gearsim-hil: socketcand on %s, bus %s\n", r->bus.listen_on, o->channel);
        fflush(stderr);
    }
}

/* --wait-client: the run starts when the first frame of a socketcand client
 * arrives (SIGINT or SIGTERM while waiting: 1, stop). That frame is handled
 * before period 0, so the recording starts at the run's start and replays to
 * it. */
static int wait_for_client(runner *r)
{
    while (r->report.frames_in == 0u) {
        if (stop_requested()) {
            return 1;
        }
        /* the handshake, then the first frames: handled, the first period applies them */
        transport_poll(&r->bus, runner_seconds_of(CLOCK_REALTIME), live_handle, r);
        struct timespec pause = {0, 5000000};
        nanosleep(&pause, NULL);
    }
    return 0;
}

int runner_live(runner *r)
{
    const runner_options *o = &r->options;
    if (strcmp(o->tx, "-") != 0 && (runner_same_regular_file(o->tx, o->params_path) ||
                                    (strcmp(o->rx, "-") != 0 && runner_same_regular_file(o->tx, o->rx)))) {
        runner_die("--tx %s: is an input of the command; choose another file", o->tx);
    }
    runner_init_rig(r, live_send, r, 1);
    runner_campaign_start(r);
    open_transport(r);
    sigset_t stop;
    sigemptyset(&stop);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGTERM);
    sigprocmask(SIG_BLOCK, &stop, NULL); /* looked for once a period: stop_requested */
    signal(SIGPIPE, SIG_IGN);            /* a closed reader: EPIPE, counted, not a crash */
    real_time_setup(o);
    memset(&r->stats, 0, sizeof r->stats); /* touch the histograms before the loop (page faults) */
    double period = r->bridge.period_s;
    uint64_t end = o->duration_s > 0.0 ? (uint64_t)nearbyint(o->duration_s / period) : 0u;
    if (o->duration_s > 0.0 && end == 0u) {
        end = 1u;
    }
    if (!o->duration_given && o->scenario != NULL) {
        end = gs_hil_scenario_end(&r->bridge); /* a scenario runs its duration */
    }
    r->bridge.config.stamp_origin_s = runner_seconds_of(CLOCK_REALTIME); /* the recording's rig time */
    runner_campaign_open_log(r);
    int stopped = o->wait_client && wait_for_client(r) != 0; /* before it started: no period runs */
    double start = runner_seconds_of(CLOCK_MONOTONIC), cpu0 = runner_cpu_seconds();
    if (!stopped) {
        paced_loop(r, end);
    }
    r->report.live = 1;
    r->report.wall_s = runner_seconds_of(CLOCK_MONOTONIC) - start;
    r->report.cpu_s = runner_cpu_seconds() - cpu0;
    gs_hil_close(&r->bridge);
    transport_drain(&r->bus, 1000);
    r->report.malformed_lines = r->bus.malformed_lines;
    r->report.write_errors = r->bus.write_errors;
    r->report.client_connects = r->bus.connects;
    r->report.client_disconnects = r->bus.disconnects;
    transport_close(&r->bus);
    int status = runner_campaign_finish(r);
    runner_print_summary(r);
    return status;
}
