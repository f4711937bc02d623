#include "daemon/stats.h"

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
    free(sorted);
    return true;
}
