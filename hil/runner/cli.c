/*
 * gearsim-hil: the C HIL runner's command line (docs/hil-runner.md).
 *
 *   gearsim-hil --params rig.params [--period S] [--substeps N] [--timeout S]
 *       [--scenario S.toml [--junit VERDICT.xml]] [--log RECORDING.log]
 *       live:   [--transport candump|socketcan|socketcand] [--rx PATH] [--tx PATH] [--channel IF]
 *               [--listen HOST:PORT] [--wait-client] [--duration S] [--spin-us US] [--fifo PRIO]
 *               [--mlockall] [--cpu N]
 *       replay: --replay LOG.log [-o ANSWERS.log] [--tail S] [--max-gap S]
 *
 * Bad input: one line on stderr, exit status 2.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gearsim/hil_dbc.h"
#include "runner.h"

static const char usage[] =
    "usage: gearsim-hil --params FILE [--period S] [--substeps N] [--timeout S] [--json]\n"
    "          [--scenario S.toml [--junit VERDICT.xml]] [--log RECORDING.log]\n"
    "  live:   [--transport candump|socketcan|socketcand] [--rx PATH|-] [--tx PATH|-] [--channel IF]\n"
    "          [--listen HOST:PORT] [--wait-client] [--duration S] [--spin-us US] [--max-lag S]\n"
    "          [--fifo PRIO] [--mlockall] [--cpu N]\n"
    "  replay: --replay LOG.log [-o ANSWERS.log] [--tail S] [--max-gap S]\n"
    "  exit status: 0, 2 bad input, 3 a scenario expectation failed\n"
    "  --list-params: the keys of the parameter file; --list-tunable: the parameters a\n"
    "  parameter frame may change, by index; --check-dbc: check the built-in DBC\n"
    "  tables; --version: version and precision. docs/hil-runner.md has the details.\n";

static double number_option(const char *name, const char *text, double low, int low_inclusive)
{
    char *end = NULL;
    errno = 0;
    double x = strtod(text, &end);
    if (end == text || *end != '\0' || errno != 0 || !isfinite(x) || x < low || (!low_inclusive && x <= low)) {
        runner_die("%s %s: expected a number %s %g", name, text, low_inclusive ? ">=" : ">", low);
    }
    return x;
}

static long integer_option(const char *name, const char *text, long low, long high)
{
    char *end = NULL;
    errno = 0;
    long x = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno != 0 || x < low || x > high) {
        runner_die("%s %s: expected an integer in [%ld, %ld]", name, text, low, high);
    }
    return x;
}

/* The frame tables built into the runner follow the library's rules (the
 * build runs this, so a DBC that breaks one fails the build). */
static int check_builtin_dbcs(void)
{
    const gs_hil_dbc *tables[] = {&gs_hil_dbc_gear_rig, &gs_hil_dbc_rack_rig};
    for (size_t i = 0; i < sizeof tables / sizeof tables[0]; ++i) {
        gs_hil_error err;
        if (gs_hil_dbc_check(tables[i], &err) != GS_HIL_OK) {
            runner_die("hil/dbc/%s.dbc: %s", tables[i]->name, err.message);
        }
        printf("%s: %u frames, ok\n", tables[i]->name, tables[i]->frame_count);
    }
    return 0;
}

/* The parameters a parameter frame or a scenario may change: rig, index, key. */
static void list_tunable(void)
{
    static const gs_rig_block blocks[] = {GS_RIG_SIMPLE_GEAR, GS_RIG_RACK_PINION};
    static const char *const names[] = {"simple_gear", "rack_pinion"};
    for (size_t b = 0; b < 2; ++b) {
        for (unsigned i = 0; i < gs_hil_param_count(blocks[b]); ++i) {
            printf("%s %u %s\n", names[b], i, gs_hil_param_key(blocks[b], i));
        }
    }
}

static void set_defaults(runner_options *o)
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
    o->listen = "127.0.0.1:29536"; /* socketcand's port */
    o->spin_us = -1;               /* automatic: live.c */
    o->cpu = -1;
}

/* Options that take no value; 1 when a was one of them (or answered and exited). */
static int flag_option(const char *a, runner_options *o)
{
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
    if (strcmp(a, "--check-dbc") == 0) {
        exit(check_builtin_dbcs());
    }
    if (strcmp(a, "--list-tunable") == 0) {
        list_tunable();
        exit(0);
    }
    if (strcmp(a, "--mlockall") == 0) {
        o->mlock = 1;
        return 1;
    }
    if (strcmp(a, "--json") == 0) {
        o->json = 1;
        return 1;
    }
    if (strcmp(a, "--wait-client") == 0) {
        o->wait_client = 1;
        return 1;
    }
    return 0;
}

static void value_option(const char *a, const char *v, runner_options *o)
{
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
        o->duration_given = 1;
    } else if (strcmp(a, "--tail") == 0) {
        o->tail_s = number_option(a, v, 0.0, 1);
    } else if (strcmp(a, "--max-gap") == 0) {
        o->max_gap_s = number_option(a, v, 0.0, 0);
    } else if (strcmp(a, "--max-lag") == 0) {
        o->max_lag_s = number_option(a, v, 0.0, 0);
    } else if (strcmp(a, "--transport") == 0) {
        if (strcmp(v, "candump") != 0 && strcmp(v, "socketcan") != 0 && strcmp(v, "socketcand") != 0) {
            runner_die("--transport %s: expected candump, socketcan or socketcand", v);
        }
        o->transport = v;
    } else if (strcmp(a, "--listen") == 0) {
        o->listen = v;
    } else if (strcmp(a, "--scenario") == 0) {
        o->scenario = v;
    } else if (strcmp(a, "--junit") == 0) {
        o->junit = v;
    } else if (strcmp(a, "--log") == 0) {
        o->log = v;
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
        runner_die("%s: unknown option (see --help)", a);
    }
}

static void parse_args(int argc, char **argv, runner_options *o)
{
    set_defaults(o);
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (flag_option(a, o)) {
            continue;
        }
        if (i + 1 >= argc) {
            runner_die("%s: %s", a, a[0] == '-' ? "needs a value (or is unknown; see --help)" : "unexpected argument");
        }
        value_option(a, argv[++i], o);
    }
    if (o->params_path == NULL) {
        runner_die("--params: required (the rig's parameter file; see --help)");
    }
    if (o->wait_client && strcmp(o->transport, "socketcand") != 0) {
        runner_die("--wait-client: only with --transport socketcand");
    }
    if (o->out != NULL && o->replay == NULL) {
        runner_die("-o %s: only with --replay (live answers go to --tx)", o->out);
    }
}

int main(int argc, char **argv)
{
    /* the whole state of the run, allocated once: the paced loop never allocates */
    runner *r = calloc(1, sizeof *r);
    if (r == NULL) {
        runner_die("out of memory (%zu bytes of runner state)", sizeof *r);
    }
    parse_args(argc, argv, &r->options);
    int status = r->options.replay != NULL ? runner_replay(r) : runner_live(r);
    free(r);
    return status;
}
