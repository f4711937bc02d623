#ifndef SHADEBENCH_STATS_TEST_H
#define SHADEBENCH_STATS_TEST_H

/* Is a new run slower than its baseline? The median frame time must be
 * slower by more than the allowed fraction, and the difference significant:
 * a one-sided Mann-Whitney U test (rank sums, ties averaged, normal
 * approximation with tie and continuity corrections) at 95% confidence, so
 * CI does not flap on noise. GL-free, unit-tested. */

#include <stdbool.h>
#include <stddef.h>

struct regression_verdict {
    double baseline_median, new_median;
    double slowdown;  /* new / baseline - 1 */
    double p_value;   /* one-sided: the new samples are larger */
    bool significant; /* p < 0.05 */
    bool regression;  /* slowdown > allowed and significant */
};

/* Returns false when either sample set is empty. */
bool regression_test(const double *baseline, size_t nb, const double *current, size_t nc,
                     double max_slowdown, struct regression_verdict *out);

/* One-sided p-value that the second sample tends to be larger. */
double mann_whitney_p_greater(const double *a, size_t na, const double *b, size_t nb);

#endif
