#ifndef SHADEBENCH_STATS_H
#define SHADEBENCH_STATS_H

#include <stdbool.h>
#include <stddef.h>

struct stats {
    size_t n;
    double mean, median, stddev, min, max, p5, p95, p99, cv;
    /* Distribution-free 95% confidence interval of the median: the order
     * statistics at ranks floor((n - 1.96 sqrt(n)) / 2) and
     * ceil(1 + (n + 1.96 sqrt(n)) / 2) (binomial, normal approximation);
     * min and max below 6 samples. */
    double median_lo, median_hi;
};

/* Summarises n samples. Percentiles interpolate linearly between closest
 * ranks (NumPy's default); stddev is the sample standard deviation (n - 1);
 * cv = stddev / mean. Returns false for n == 0 (all fields zeroed). */
bool stats_compute(const double *samples, size_t n, struct stats *out);

/* 95% confidence interval of the mean (Student's t, n - 1 degrees of
 * freedom). False below 2 samples. */
bool stats_mean_ci95(const double *samples, size_t n, double *lo, double *hi);

/* The repeat rule rigorous harnesses use (Intel's ezbench): a measurement is
 * stable once the 95% interval of the mean of per-run medians is within
 * tolerance (0.025 = 2.5%) of that mean, from 3 runs on. */
bool stats_is_stable(const double *run_medians, size_t n, double tolerance);

/* Percentile q in [0, 100] of an ascending array. */
double stats_percentile_sorted(const double *sorted, size_t n, double q);

#endif
