/*
 * Per-period timing of the paced loop, recorded without I/O or allocation
 * into fixed histograms: 0.1 us bins up to 10 ms, then 100 us bins up to
 * 10 s (beyond: the last bin; the exact maximum is kept apart).
 */
#ifndef GEARSIM_HIL_RUNNER_LOOP_STATS_H
#define GEARSIM_HIL_RUNNER_LOOP_STATS_H

#include <stdint.h>
#include <stdio.h>

#define LOOP_FINE_BINS   100000u /* 100 ns each: [0, 10 ms) */
#define LOOP_COARSE_BINS 100000u /* 100 us each: [10 ms, 10 s) */

typedef struct {
    uint32_t fine[LOOP_FINE_BINS];
    uint32_t coarse[LOOP_COARSE_BINS];
    uint64_t count;
    int64_t max_ns;
    double sum_ns;
} loop_histogram;

typedef struct {
    loop_histogram lateness;     /* period start minus its deadline */
    loop_histogram period_error; /* |start[k+1] - start[k] - period| */
    loop_histogram work;         /* start to end of the period's work (poll, steps, send) */
} loop_stats;

void loop_histogram_add(loop_histogram *h, int64_t ns);

/* q-quantile in microseconds (upper edge of its bin; at most 0.1 us above below 10 ms). */
double loop_histogram_quantile_us(const loop_histogram *h, double q);

/* Writes `"name": {...}` members (median, p99, p999, max, mean in us). */
void loop_histogram_json(FILE *out, const char *name, const loop_histogram *h);

#endif
