/*
 * A scenario on a bridge (gearsim/hil.h, docs/hil.md "Scenarios"): its steps
 * at their periods (the scenario's load, parameter changes one period ahead
 * so that they take effect at their step, faults by their windows), its
 * expectations checked period by period on the commands the rig applied,
 * and the verdict as JUnit XML. Everything is in periods of the bridge's
 * simulated time, so a live run, a replay of its recording and the Python
 * bridge give the same verdict for the same frames.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "internal.h"

static gs_hil_status refuse(gs_hil_error *err, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static gs_hil_status refuse(gs_hil_error *err, const char *fmt, ...)
{
    if (err != NULL) {
        va_list ap;
        va_start(ap, fmt);
        err->parameter = "scenario";
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return GS_HIL_E_CONFIG;
}

static uint64_t at_least(uint64_t x, uint64_t low)
{
    return x > low ? x : low;
}

static gs_hil_status add_faults(gs_hil_bridge *b, const gs_hil_scenario *s, gs_hil_error *err)
{
    for (unsigned i = 0; i < s->fault_count; ++i) {
        const gs_hil_fault_def *d = &s->faults[i];
        gs_hil_fault_spec spec = d->spec;
        spec.start_period = gs_hil_period_at(b, d->at_s);
        spec.end_period = UINT64_MAX;
        if (isfinite(d->until_s)) {
            spec.end_period = gs_hil_period_at(b, d->until_s);
        } else if (d->duration_s > 0.0 && !spec.has_trigger) {
            spec.end_period = gs_hil_period_at(b, d->at_s + d->duration_s);
        }
        if (spec.has_trigger && d->duration_s > 0.0) {
            spec.duration_periods = at_least(gs_hil_periods_in(b, d->duration_s), 1u);
        }
        gs_hil_error e;
        if (gs_hil_add_fault(b, &spec, &e) != GS_HIL_OK) {
            return refuse(err, "%s:%u: %s: %s", s->file, d->line, e.parameter != NULL ? e.parameter : "fault",
                          e.message);
        }
    }
    return GS_HIL_OK;
}

static void open_expectations(gs_hil_bridge *b, const gs_hil_scenario *s)
{
    for (unsigned i = 0; i < s->expect_count; ++i) {
        const gs_hil_expect_def *d = &s->expects[i];
        gs_hil_expect_state *e = &b->expects[i];
        memset(e, 0, sizeof *e);
        e->start_period = gs_hil_period_at(b, d->at_s);
        uint64_t end = d->mode == GS_HIL_EXPECT_WITHIN  ? gs_hil_period_at(b, d->at_s + d->window_s)
                       : d->mode == GS_HIL_EXPECT_UNTIL ? gs_hil_period_at(b, d->window_s)
                                                        : 0u;
        e->end_period = at_least(end, e->start_period + 1u);
        e->observed = nan("");
    }
}

/* The parameter changes, tried in time order from the rig's parameters. */
static gs_hil_status check_changes(gs_hil_bridge *b, const gs_hil_scenario *s, gs_hil_error *err)
{
    int any = 0;
    for (unsigned i = 0; i < s->step_count; ++i) {
        if (s->steps[i].kind == GS_HIL_STEP_PARAM) {
            if (!b->tunable) {
                return refuse(err, "%s:%u: param: the rig's parameters were not given to the bridge", s->file,
                              s->steps[i].line);
            }
            any = 1;
        }
    }
    if (!any) {
        return GS_HIL_OK;
    }
    gs_error e;
    unsigned bad = gs_hil_check_changes_(b, s, &e);
    if (bad == 0u) {
        return GS_HIL_OK;
    }
    const gs_hil_step *st = &s->steps[bad - 1u];
    if (e.message == NULL) {
        return refuse(err, "%s:%u: param: %s has no element %u in use", s->file, st->line,
                      gs_hil_param_key(b->block, st->param), st->element);
    }
    return refuse(err, "%s:%u: value: %s = %g refused by the rig: %s%s%s", s->file, st->line,
                  gs_hil_param_key(b->block, st->param), st->value, e.message, e.parameter != NULL ? " " : "",
                  e.parameter != NULL ? e.parameter : "");
}

gs_hil_status gs_hil_attach_scenario(gs_hil_bridge *b, const gs_hil_scenario *s, gs_hil_error *err)
{
    if (b->scenario != NULL || b->counters.count[GS_HIL_COUNT_PERIODS] != 0u || b->fault_count != 0u) {
        return refuse(err, "a scenario is attached to a bridge that has not run and has no faults yet");
    }
    if (s->dbc == NULL || s->dbc->frames != b->config.dbc->frames || s->block != b->block) {
        return refuse(err, "%s: read for another DBC or rig than the bridge's", s->file);
    }
    if (add_faults(b, s, err) != GS_HIL_OK || check_changes(b, s, err) != GS_HIL_OK) {
        b->fault_count = 0;
        return GS_HIL_E_CONFIG;
    }
    open_expectations(b, s);
    b->next_step = 0;
    b->next_param_step = 0;
    b->has_load = 0;
    b->load_from = b->load_to = 0.0;
    b->load_start = b->load_end = 0;
    for (unsigned i = 0; i < s->step_count; ++i) {
        const gs_hil_step *st = &s->steps[i];
        b->step_period[i] = gs_hil_period_at(b, st->at_s);
        b->has_load |= st->kind == GS_HIL_STEP_LOAD;
        if (st->kind == GS_HIL_STEP_PARAM && b->step_period[i] == 0u) {
            /* in effect from the first period: derived and swapped now */
            (void)gs_hil_request_param(b, st->param, st->element, st->value);
            b->requests_due = 0;
            gs_hil_swap_params_(b);
        }
    }
    b->scenario = s;
    return GS_HIL_OK;
}

uint64_t gs_hil_scenario_end(const gs_hil_bridge *b)
{
    return b->scenario != NULL ? gs_hil_period_at(b, b->scenario->duration_s) : 0u;
}

double gs_hil_scenario_load_(const gs_hil_bridge *b, uint64_t n)
{
    if (n >= b->load_end) {
        return b->load_to;
    }
    /* a ramp: its value at the end of period n */
    double f = (double)(n - b->load_start + 1u) / (double)(b->load_end - b->load_start);
    return b->load_from + (b->load_to - b->load_from) * f;
}

void gs_hil_scenario_start_(gs_hil_bridge *b, uint64_t n)
{
    const gs_hil_scenario *s = b->scenario;
    /* parameter changes one period ahead: prepared between the periods, in effect at their step */
    for (unsigned i = b->next_param_step; i < s->step_count && b->step_period[i] <= n + 1u; ++i) {
        const gs_hil_step *st = &s->steps[i];
        if (st->kind == GS_HIL_STEP_PARAM && b->step_period[i] == n + 1u) {
            (void)gs_hil_request_param(b, st->param, st->element, st->value); /* refused: counted, acknowledged */
        }
        b->next_param_step = i + 1u;
    }
    for (; b->next_step < s->step_count && b->step_period[b->next_step] <= n; ++b->next_step) {
        const gs_hil_step *st = &s->steps[b->next_step];
        if (st->kind != GS_HIL_STEP_LOAD) {
            continue; /* faults and expectations act by their windows */
        }
        b->load_from = gs_hil_scenario_load_(b, n > 0u ? n - 1u : 0u);
        if (n == 0u) {
            b->load_from = b->load_to;
        }
        b->load_to = st->value;
        b->load_start = n;
        b->load_end = n + gs_hil_periods_in(b, st->over_s);
    }
}

void gs_hil_scenario_end_(gs_hil_bridge *b, uint64_t n)
{
    const gs_hil_scenario *s = b->scenario;
    for (unsigned i = 0; i < s->expect_count; ++i) {
        const gs_hil_expect_def *d = &s->expects[i];
        gs_hil_expect_state *e = &b->expects[i];
        if (e->verdict != GS_HIL_VERDICT_PENDING || n < e->start_period || n >= e->end_period) {
            continue;
        }
        double x = gs_hil_source_value_(b, &d->target);
        int ok = x >= d->minimum && x <= d->maximum; /* NaN: no command yet, never ok */
        int last = n + 1u >= e->end_period;
        if (d->mode == GS_HIL_EXPECT_WITHIN ? (ok || last) : (!ok || last)) {
            e->verdict = ok ? GS_HIL_VERDICT_PASS : GS_HIL_VERDICT_FAIL;
            e->decided_period = n;
            e->observed = x;
        }
    }
}

void gs_hil_finish_scenario(gs_hil_bridge *b)
{
    const gs_hil_scenario *s = b->scenario;
    if (s == NULL) {
        return;
    }
    for (unsigned i = 0; i < s->expect_count; ++i) {
        gs_hil_expect_state *e = &b->expects[i];
        if (e->verdict == GS_HIL_VERDICT_PENDING) {
            e->verdict = GS_HIL_VERDICT_FAIL;
            e->incomplete = 1;
            e->decided_period = b->counters.count[GS_HIL_COUNT_PERIODS];
        }
    }
}

void gs_hil_verdict_counts(const gs_hil_bridge *b, unsigned *passed, unsigned *failed, unsigned *pending)
{
    unsigned n[3] = {0, 0, 0};
    for (unsigned i = 0; b->scenario != NULL && i < b->scenario->expect_count; ++i) {
        n[b->expects[i].verdict] += 1u;
    }
    *pending = n[GS_HIL_VERDICT_PENDING];
    *passed = n[GS_HIL_VERDICT_PASS];
    *failed = n[GS_HIL_VERDICT_FAIL];
}

/* ---- JUnit XML -------------------------------------------------------------------- */

typedef struct {
    char *out;
    size_t size, length;
} text;

static void put(text *t, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void put(text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    size_t room = t->length < t->size ? t->size - t->length : 0u;
    int n = vsnprintf(room > 0u ? t->out + t->length : NULL, room, fmt, ap);
    va_end(ap);
    t->length += n > 0 ? (size_t)n : 0u;
}

/* s with the five XML characters escaped (attribute values and text). */
static void put_escaped(text *t, const char *s)
{
    for (; *s != '\0'; ++s) {
        switch (*s) {
        case '&':
            put(t, "&amp;");
            break;
        case '<':
            put(t, "&lt;");
            break;
        case '>':
            put(t, "&gt;");
            break;
        case '"':
            put(t, "&quot;");
            break;
        case '\'':
            put(t, "&apos;");
            break;
        case '\n':
            put(t, "&#10;");
            break;
        case '\t':
            put(t, "&#9;");
            break;
        default:
            if ((unsigned char)*s >= 0x20u) {
                put(t, "%c", *s);
            }
            break;
        }
    }
}

static void failure_text(const gs_hil_bridge *b, unsigned i, char *out, size_t size)
{
    const gs_hil_expect_def *d = &b->scenario->expects[i];
    const gs_hil_expect_state *e = &b->expects[i];
    double t = (double)e->decided_period * b->period_s;
    char seen[64];
    if (isnan(e->observed)) {
        snprintf(seen, sizeof seen, "no command received yet");
    } else {
        snprintf(seen, sizeof seen, "%.9g", e->observed);
    }
    if (e->incomplete) {
        snprintf(out, size, "the run ended at %.6g s, before the window closed at %.6g s", t,
                 (double)e->end_period * b->period_s);
    } else if (d->mode == GS_HIL_EXPECT_WITHIN) {
        snprintf(out, size, "never %s from %.6g s to %.6g s (last: %s)", d->what, (double)e->start_period * b->period_s,
                 (double)e->end_period * b->period_s, seen);
    } else {
        snprintf(out, size, "%s at %.6g s: expected %s", seen, t, d->what);
    }
}

static void put_case(text *t, const gs_hil_bridge *b, unsigned i)
{
    const gs_hil_scenario *s = b->scenario;
    const gs_hil_expect_def *d = &s->expects[i];
    const gs_hil_expect_state *e = &b->expects[i];
    uint64_t end = e->verdict == GS_HIL_VERDICT_PENDING ? e->start_period : e->decided_period + 1u;
    double span = end > e->start_period ? (double)(end - e->start_period) * b->period_s : 0.0;
    put(t, "    <testcase name=\"");
    put_escaped(t, d->name);
    put(t, "\" classname=\"");
    put_escaped(t, s->name);
    put(t, "\" file=\"");
    put_escaped(t, s->file);
    put(t, "\" line=\"%u\" time=\"%.6f\"", d->line, span);
    if (e->verdict == GS_HIL_VERDICT_PASS) {
        put(t, "/>\n");
        return;
    }
    char why[300];
    if (e->verdict == GS_HIL_VERDICT_PENDING) {
        snprintf(why, sizeof why, "not decided: the run has not reached %.6g s", (double)e->start_period * b->period_s);
    } else {
        failure_text(b, i, why, sizeof why);
    }
    put(t, ">\n      <failure type=\"%s\" message=\"", e->incomplete ? "incomplete" : "expectation");
    put_escaped(t, why);
    put(t, "\">");
    put_escaped(t, d->what);
    put(t, "</failure>\n    </testcase>\n");
}

size_t gs_hil_junit(const gs_hil_bridge *b, char *out, size_t size)
{
    text t = {out, size, 0};
    if (size > 0u) {
        out[0] = '\0';
    }
    const gs_hil_scenario *s = b->scenario;
    unsigned passed = 0, failed = 0, pending = 0;
    gs_hil_verdict_counts(b, &passed, &failed, &pending);
    unsigned tests = passed + failed + pending;
    double time = (double)b->counters.count[GS_HIL_COUNT_PERIODS] * b->period_s;
    const char *name = s != NULL ? s->name : "no scenario";
    put(&t, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    put(&t, "<testsuites name=\"gearsim-hil\" tests=\"%u\" failures=\"%u\" errors=\"0\" time=\"%.6f\">\n", tests,
        failed + pending, time);
    put(&t, "  <testsuite name=\"");
    put_escaped(&t, name);
    put(&t, "\" tests=\"%u\" failures=\"%u\" errors=\"0\" skipped=\"0\" time=\"%.6f\">\n", tests, failed + pending,
        time);
    put(&t, "    <properties>\n");
    put(&t, "      <property name=\"scenario\" value=\"");
    put_escaped(&t, s != NULL ? s->file : "");
    put(&t, "\"/>\n      <property name=\"dbc\" value=\"");
    put_escaped(&t, b->config.dbc->name);
    put(&t, "\"/>\n");
    put(&t, "      <property name=\"period\" value=\"%.9g\"/>\n", b->period_s);
    static const gs_hil_count shown[] = {
        GS_HIL_COUNT_PERIODS, GS_HIL_COUNT_RX_USED,       GS_HIL_COUNT_RX_REJECTED,   GS_HIL_COUNT_TIMEOUTS,
        GS_HIL_COUNT_FAULTS,  GS_HIL_COUNT_PARAM_CHANGES, GS_HIL_COUNT_PARAM_REFUSED, GS_HIL_COUNT_SATURATIONS};
    for (size_t k = 0; k < sizeof shown / sizeof shown[0]; ++k) {
        put(&t, "      <property name=\"%s\" value=\"%llu\"/>\n", gs_hil_count_name(shown[k]),
            (unsigned long long)b->counters.count[shown[k]]);
    }
    put(&t, "    </properties>\n");
    for (unsigned i = 0; s != NULL && i < s->expect_count; ++i) {
        put_case(&t, b, i);
    }
    put(&t, "  </testsuite>\n</testsuites>\n");
    return t.length;
}
