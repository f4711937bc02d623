#ifndef SHADEBENCH_STATS_H
#define SHADEBENCH_STATS_H

#include <stdbool.h>
#include <stddef.h>

struct stats {
    size_t n;
    double mean, median, stddev, min, max, p5, p95, p99, cv;
};

/* Summarises n samples. Percentiles interpolate linearly between closest
 * ranks (NumPy's default); stddev is the sample standard deviation (n - 1);
 * cv = stddev / mean. Returns false for n == 0 (all fields zeroed). */
bool stats_compute(const double *samples, size_t n, struct stats *out);

/* Percentile q in [0, 100] of an ascending array. */
double stats_percentile_sorted(const double *sorted, size_t n, double q);

#endif
