/*
 * Rig parameters changed at run time (gearsim/hil.h, docs/hil.md "Parameters
 * at run time"): which parameters may change (the TUNABLE entries of the
 * library's parameter tables), requests queued per period, their constants
 * derived between periods into the spare of two buffers and swapped at the
 * next period boundary, acknowledgements queued for the ack frame.
 *
 * Derivation is one gs_rig_init_* per request (bounded, no allocation),
 * into a scratch state that is thrown away: the rig's own state carries on
 * with the new constants (gearsim/rig.h allows it).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gearsim/hil.h"

static int is_changeable(const gs_param_info *e)
{
    return e->flags == GS_PARAM_TUNABLE && (e->kind == GS_PARAM_REAL || e->kind == GS_PARAM_ARRAY ||
                                            e->kind == GS_PARAM_TABLE || e->kind == GS_PARAM_MATRIX);
}

static void block_table(gs_rig_block block, const gs_param_info **table, unsigned *count)
{
    if (block == GS_RIG_SIMPLE_GEAR) {
        *table = gs_simple_gear_param_info;
        *count = (unsigned)GS_SIMPLE_GEAR_PARAM_FIELDS;
    } else {
        *table = gs_rack_pinion_param_info;
        *count = (unsigned)GS_RACK_PINION_PARAM_FIELDS;
    }
}

/* The index-th changeable entry of table[0..count), counting from *seen. */
static const gs_param_info *nth(const gs_param_info *table, unsigned count, unsigned index, unsigned *seen)
{
    for (unsigned i = 0; i < count; ++i) {
        if (!is_changeable(&table[i])) {
            continue;
        }
        if (*seen == index) {
            return &table[i];
        }
        ++*seen;
    }
    return NULL;
}

const gs_param_info *gs_hil_param_info(gs_rig_block block, unsigned index, int *is_rig)
{
    const gs_param_info *table;
    unsigned count, seen = 0;
    block_table(block, &table, &count);
    const gs_param_info *e = nth(table, count, index, &seen);
    if (is_rig != NULL) {
        *is_rig = e == NULL;
    }
    return e != NULL ? e : nth(gs_rig_param_info, (unsigned)GS_RIG_PARAM_FIELDS, index, &seen);
}

unsigned gs_hil_param_count(gs_rig_block block)
{
    unsigned n = 0;
    while (gs_hil_param_info(block, n, NULL) != NULL) {
        ++n;
    }
    return n;
}

const char *gs_hil_param_key(gs_rig_block block, unsigned index)
{
    int is_rig = 0;
    const gs_param_info *e = gs_hil_param_info(block, index, &is_rig);
    if (e == NULL) {
        return "";
    }
    return is_rig && block == GS_RIG_RACK_PINION ? e->rack_key : e->key;
}

/* The int a COUNT member of table holds in the struct at base (0 if none). */
static int count_member(const gs_param_info *table, unsigned count, const unsigned char *base, const char *member)
{
    for (unsigned i = 0; i < count; ++i) {
        if (table[i].kind == GS_PARAM_COUNT && strcmp(table[i].member, member) == 0) {
            int n;
            memcpy(&n, base + table[i].offset, sizeof n);
            return n;
        }
    }
    return 0;
}

/* Elements an entry may be given: its length (a scalar: 1), a matrix as
 * GS_TABLE_MAX columns per row. */
static unsigned capacity(const gs_param_info *e)
{
    return e->kind == GS_PARAM_MATRIX ? (unsigned)(GS_TABLE_MAX * GS_TABLE_MAX) : (unsigned)e->length;
}

/* The element is one the parameter has; for tables and matrices within the
 * used rows and columns (the count members in params). */
static int element_in_use(gs_rig_block block, const gs_hil_rig_params *params, const gs_param_info *e, int is_rig,
                          unsigned element)
{
    if (element >= capacity(e)) {
        return 0;
    }
    if (is_rig || (e->kind != GS_PARAM_TABLE && e->kind != GS_PARAM_MATRIX)) {
        return 1;
    }
    const gs_param_info *table;
    unsigned count;
    block_table(block, &table, &count);
    const unsigned char *base = (const unsigned char *)&params->block;
    int rows = count_member(table, count, base, e->count);
    if (e->kind == GS_PARAM_TABLE) {
        return (int)element < rows;
    }
    int columns = count_member(table, count, base, e->count2);
    return (int)(element / GS_TABLE_MAX) < rows && (int)(element % GS_TABLE_MAX) < columns;
}

gs_hil_param_result gs_hil_param_set(gs_rig_block block, gs_hil_rig_params *params, unsigned index, unsigned element,
                                     double value)
{
    int is_rig = 0;
    const gs_param_info *e = gs_hil_param_info(block, index, &is_rig);
    if (e == NULL) {
        return GS_HIL_PARAM_UNKNOWN_PARAM;
    }
    if (!element_in_use(block, params, e, is_rig, element)) {
        return GS_HIL_PARAM_BAD_ELEMENT;
    }
    if (!isfinite(value)) {
        return GS_HIL_PARAM_INVALID_VALUE;
    }
    unsigned char *base = is_rig ? (unsigned char *)&params->rig : (unsigned char *)&params->block;
    const gs_real x = (gs_real)value;
    memcpy(base + e->offset + (size_t)element * sizeof x, &x, sizeof x);
    return GS_HIL_PARAM_APPLIED;
}

/* "[n]" at *p -> n; advances *p. -1 when not such a suffix. */
static int bracket(const char **p, unsigned *n)
{
    const char *s = *p;
    if (*s != '[') {
        return -1;
    }
    char *end = NULL;
    unsigned long v = strtoul(s + 1, &end, 10);
    if (end == s + 1 || *end != ']' || v > 1000u) {
        return -1;
    }
    *n = (unsigned)v;
    *p = end + 1;
    return 0;
}

int gs_hil_param_parse(gs_rig_block block, const char *text, unsigned *index, unsigned *element)
{
    size_t key_len = strcspn(text, "[");
    unsigned n = gs_hil_param_count(block);
    for (unsigned i = 0; i < n; ++i) {
        const char *key = gs_hil_param_key(block, i);
        if (strlen(key) != key_len || strncmp(key, text, key_len) != 0) {
            continue;
        }
        const gs_param_info *e = gs_hil_param_info(block, i, NULL);
        const char *p = text + key_len;
        unsigned row = 0, column = 0;
        int indices = 0;
        while (*p == '[' && indices < 2) {
            if (bracket(&p, indices == 0 ? &row : &column) != 0) {
                return -1;
            }
            ++indices;
        }
        int wanted = e->kind == GS_PARAM_REAL ? 0 : e->kind == GS_PARAM_MATRIX ? 2 : 1;
        if (*p != '\0' || indices != wanted) {
            return -1;
        }
        if (wanted == 2 && (row >= GS_TABLE_MAX || column >= GS_TABLE_MAX)) {
            return -1;
        }
        *index = i;
        *element = wanted == 2 ? row * GS_TABLE_MAX + column : row;
        return element[0] < capacity(e) ? 0 : -1;
    }
    return -1;
}

/* ---- the bridge's requests ---------------------------------------------------- */

static gs_hil_status init_rig(const gs_hil_bridge *b, const gs_hil_rig_params *p, gs_rig_consts *consts,
                              gs_rig_state *scratch, gs_error *err)
{
    gs_status status = b->block == GS_RIG_SIMPLE_GEAR ? gs_rig_init_gear(consts, scratch, &p->block.gear, &p->rig, err)
                                                      : gs_rig_init_rack(consts, scratch, &p->block.rack, &p->rig, err);
    return status == GS_OK ? GS_HIL_OK : GS_HIL_E_CONFIG;
}

static void queue_ack(gs_hil_bridge *b, const gs_hil_param_request *r)
{
    if (b->ack_count < sizeof b->acks / sizeof b->acks[0]) {
        b->acks[b->ack_count++] = *r;
    }
}

/* Counted at the boundary where the request is settled: applied or refused. */
static void settle(gs_hil_bridge *b, const gs_hil_param_request *r)
{
    uint64_t *count = b->counters.count;
    if (r->result == GS_HIL_PARAM_APPLIED) {
        count[GS_HIL_COUNT_PARAM_CHANGES] += 1u;
        count[GS_HIL_COUNT_RX_USED] += 1u;
    } else {
        count[GS_HIL_COUNT_PARAM_REFUSED] += 1u;
        gs_hil_reason reason = r->result == GS_HIL_PARAM_BUSY ? GS_HIL_REJECTED_PARAM_BUSY : GS_HIL_REJECTED_BAD_PARAM;
        count[GS_HIL_COUNT_RX_REJECTED] += 1u;
        b->counters.reasons[reason] += 1u;
    }
    queue_ack(b, r);
}

gs_hil_param_result gs_hil_request_param(gs_hil_bridge *b, unsigned index, unsigned element, double value)
{
    gs_hil_param_request r;
    memset(&r, 0, sizeof r);
    r.index = index;
    r.element = element;
    r.value = value;
    r.result = GS_HIL_PARAM_APPLIED;
    if (!b->tunable) {
        r.result = GS_HIL_PARAM_UNAVAILABLE;
    } else if (b->request_count == GS_HIL_PARAM_QUEUE) {
        r.result = GS_HIL_PARAM_BUSY;
    } else {
        int is_rig = 0;
        const gs_param_info *e = gs_hil_param_info(b->block, index, &is_rig);
        if (e == NULL) {
            r.result = GS_HIL_PARAM_UNKNOWN_PARAM;
        } else if (!element_in_use(b->block, &b->params, e, is_rig, element)) {
            r.result = GS_HIL_PARAM_BAD_ELEMENT;
        } else if (!isfinite(value)) {
            r.result = GS_HIL_PARAM_INVALID_VALUE;
        }
    }
    if (r.result != GS_HIL_PARAM_APPLIED) {
        settle(b, &r); /* refused now: counted, acknowledged with the next period's feedback */
        return r.result;
    }
    b->requests_due = b->counters.count[GS_HIL_COUNT_PERIODS] + 1u;
    b->requests[b->request_count++] = r;
    return GS_HIL_PARAM_APPLIED; /* pending: prepared between periods, effective at requests_due */
}

void gs_hil_prepare(gs_hil_bridge *b)
{
    for (unsigned i = 0; i < b->request_count; ++i) {
        gs_hil_param_request *r = &b->requests[i];
        if (r->prepared) {
            continue;
        }
        r->prepared = 1;
        b->params_try = b->params_next;
        r->result = gs_hil_param_set(b->block, &b->params_try, r->index, r->element, r->value);
        gs_error err;
        if (r->result == GS_HIL_PARAM_APPLIED &&
            init_rig(b, &b->params_try, &b->consts_buf[b->consts_next], &b->scratch, &err) != GS_HIL_OK) {
            r->result = GS_HIL_PARAM_INVALID_VALUE; /* init left the spare constants as they were */
        }
        if (r->result == GS_HIL_PARAM_APPLIED) {
            b->params_next = b->params_try;
            b->next_ready = 1;
        }
    }
}

/* At the start of a period: the requests due take effect (or are refused). */
void gs_hil_swap_params_(gs_hil_bridge *b);
void gs_hil_swap_params_(gs_hil_bridge *b)
{
    if (b->request_count == 0u || b->counters.count[GS_HIL_COUNT_PERIODS] < b->requests_due) {
        return;
    }
    gs_hil_prepare(b); /* nothing left to do when the caller prepared them */
    if (b->next_ready) {
        b->consts = &b->consts_buf[b->consts_next];
        b->consts_next ^= 1u;
        b->params = b->params_next;
        b->next_ready = 0;
    }
    for (unsigned i = 0; i < b->request_count; ++i) {
        settle(b, &b->requests[i]);
    }
    b->request_count = 0;
}

const gs_hil_rig_params *gs_hil_params(const gs_hil_bridge *b)
{
    return &b->params;
}

/* Set up parameter changes from the config (gs_hil_bridge_init). */
void gs_hil_init_tuning_(gs_hil_bridge *b, gs_rig_block block);
void gs_hil_init_tuning_(gs_hil_bridge *b, gs_rig_block block)
{
    const gs_hil_config *c = &b->config;
    b->block = block;
    b->tunable =
        c->rig_params != NULL && (block == GS_RIG_SIMPLE_GEAR ? c->gear_params != NULL : c->rack_params != NULL);
    if (!b->tunable) {
        return;
    }
    if (block == GS_RIG_SIMPLE_GEAR) {
        b->params.block.gear = *c->gear_params;
    } else {
        b->params.block.rack = *c->rack_params;
    }
    b->params.rig = *c->rig_params;
    b->params_next = b->params;
}

/* A dry run of the parameter changes of a scenario, in time order from the
 * rig's parameters (before the bridge runs: the spare constants and the
 * scratch state are free): 0, or the index of the first change refused + 1;
 * *err says why (parameter and message NULL: an element not in use). */
unsigned gs_hil_check_changes_(gs_hil_bridge *b, const gs_hil_scenario *s, gs_error *err);
unsigned gs_hil_check_changes_(gs_hil_bridge *b, const gs_hil_scenario *s, gs_error *err)
{
    b->params_try = b->params;
    for (unsigned i = 0; i < s->step_count; ++i) {
        const gs_hil_step *st = &s->steps[i];
        if (st->kind != GS_HIL_STEP_PARAM) {
            continue;
        }
        memset(err, 0, sizeof *err);
        if (gs_hil_param_set(b->block, &b->params_try, st->param, st->element, st->value) != GS_HIL_PARAM_APPLIED ||
            init_rig(b, &b->params_try, &b->consts_buf[b->consts_next], &b->scratch, err) != GS_HIL_OK) {
            return i + 1u;
        }
    }
    return 0;
}
