#include "loop_stats.h"

#include <math.h>

#define FINE_NS      100
#define COARSE_NS    100000
#define FINE_SPAN_NS ((int64_t)LOOP_FINE_BINS * FINE_NS)

void loop_histogram_add(loop_histogram *h, int64_t ns)
{
    int64_t x = ns < 0 ? 0 : ns; /* early starts cannot happen (the loop waits for the deadline) */
    if (x < FINE_SPAN_NS) {
        h->fine[x / FINE_NS]++;
    } else {
        int64_t bin = (x - FINE_SPAN_NS) / COARSE_NS;
        h->coarse[bin < (int64_t)LOOP_COARSE_BINS ? bin : (int64_t)LOOP_COARSE_BINS - 1]++;
    }
    h->count++;
    h->sum_ns += (double)x;
    if (x > h->max_ns) {
        h->max_ns = x;
    }
}

double loop_histogram_quantile_us(const loop_histogram *h, double q)
{
    if (h->count == 0u) {
        return 0.0;
    }
    uint64_t rank = (uint64_t)ceil(q * (double)h->count);
    rank = rank < 1u ? 1u : rank;
    uint64_t seen = 0;
    for (uint32_t i = 0; i < LOOP_FINE_BINS; ++i) {
        seen += h->fine[i];
        if (seen >= rank) {
            double edge = (double)(i + 1u) * FINE_NS;
            return (edge < (double)h->max_ns ? edge : (double)h->max_ns) / 1e3;
        }
    }
    for (uint32_t i = 0; i < LOOP_COARSE_BINS; ++i) {
        seen += h->coarse[i];
        if (seen >= rank) {
            double edge = (double)FINE_SPAN_NS + (double)(i + 1u) * COARSE_NS;
            return (edge < (double)h->max_ns ? edge : (double)h->max_ns) / 1e3;
        }
    }
    return (double)h->max_ns / 1e3;
}

void loop_histogram_json(FILE *out, const char *name, const loop_histogram *h)
{
    fprintf(out,
            "\"%s\": {\"count\": %llu, \"median_us\": %.3f, \"p99_us\": %.3f, \"p999_us\": %.3f, "
            "\"max_us\": %.3f, \"mean_us\": %.3f}",
            name, (unsigned long long)h->count, loop_histogram_quantile_us(h, 0.5), loop_histogram_quantile_us(h, 0.99),
            loop_histogram_quantile_us(h, 0.999), (double)h->max_ns / 1e3,
            h->count ? h->sum_ns / (double)h->count / 1e3 : 0.0);
}
