#include "common/stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double stats_percentile_sorted(const double *sorted, size_t n, double q)
{
    if (n == 0)
        return 0.0;
    double pos = q / 100.0 * (double)(n - 1);
    size_t lo = (size_t)floor(pos);
    if (lo >= n - 1)
        return sorted[n - 1];
    double frac = pos - (double)lo;
    return sorted[lo] + (sorted[lo + 1] - sorted[lo]) * frac;
}

bool stats_compute(const double *samples, size_t n, struct stats *out)
{
    memset(out, 0, sizeof(*out));
    if (n == 0)
        return false;
    double *sorted = malloc(n * sizeof(*sorted));
    if (!sorted)
        return false;
    memcpy(sorted, samples, n * sizeof(*sorted));
    qsort(sorted, n, sizeof(*sorted), cmp_double);

    /* Welford's update keeps the variance exact for long, nearly constant series. */
    double mean = 0.0, m2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double delta = samples[i] - mean;
        mean += delta / (double)(i + 1);
        m2 += delta * (samples[i] - mean);
    }
    out->n = n;
    out->mean = mean;
    out->stddev = n > 1 ? sqrt(m2 / (double)(n - 1)) : 0.0;
    out->min = sorted[0];
    out->max = sorted[n - 1];
    out->median = stats_percentile_sorted(sorted, n, 50.0);
    out->p5 = stats_percentile_sorted(sorted, n, 5.0);
    out->p95 = stats_percentile_sorted(sorted, n, 95.0);
    out->p99 = stats_percentile_sorted(sorted, n, 99.0);
    out->cv = mean != 0.0 ? out->stddev / mean : 0.0;
    if (n < 6) {
        out->median_lo = out->min;
        out->median_hi = out->max;
    } else {
        double spread = 1.96 * sqrt((double)n);
        long lo = (long)floor(((double)n - spread) / 2.0);
        long hi = (long)ceil(1.0 + ((double)n + spread) / 2.0);
        lo = lo < 1 ? 1 : lo;
        hi = hi > (long)n ? (long)n : hi;
        out->median_lo = sorted[lo - 1];
        out->median_hi = sorted[hi - 1];
    }
    free(sorted);
    return true;
}

/* Two-sided 97.5% quantiles of Student's t for 1 to 30 degrees of freedom. */
static const double T975[31] = {
    0,     12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
    2.201, 2.179,  2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080,
    2.074, 2.069,  2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
};

bool stats_mean_ci95(const double *samples, size_t n, double *lo, double *hi)
{
    struct stats s;
    if (n < 2 || !stats_compute(samples, n, &s))
        return false;
    double t = n - 1 <= 30 ? T975[n - 1] : 1.96;
    double half = t * s.stddev / sqrt((double)n);
    *lo = s.mean - half;
    *hi = s.mean + half;
    return true;
}

bool stats_is_stable(const double *run_medians, size_t n, double tolerance)
{
    double lo, hi;
    if (n < 3 || !stats_mean_ci95(run_medians, n, &lo, &hi))
        return false;
    double mean = (lo + hi) / 2.0;
    return mean > 0 && (hi - lo) / 2.0 <= tolerance * mean;
}
