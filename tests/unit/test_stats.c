#include <math.h>

#include "common/stats.h"
#include "tests/unit/check.h"

int main(void)
{
    double v[100];
    for (int i = 0; i < 100; i++)
        v[99 - i] = i + 1; /* descending input: stats must sort */
    struct stats s;
    CHECK(stats_compute(v, 100, &s));
    CHECK(s.n == 100);
    CHECK_NEAR(s.mean, 50.5, 1e-12);
    CHECK_NEAR(s.median, 50.5, 1e-12);
    CHECK_NEAR(s.min, 1.0, 0);
    CHECK_NEAR(s.max, 100.0, 0);
    /* NumPy: np.percentile(range(1,101), [5, 95, 99]) = 5.95, 95.05, 99.01 */
    CHECK_NEAR(s.p5, 5.95, 1e-9);
    CHECK_NEAR(s.p95, 95.05, 1e-9);
    CHECK_NEAR(s.p99, 99.01, 1e-9);
    /* Sample standard deviation of 1..100: sqrt(841.666...) */
    CHECK_NEAR(s.stddev, sqrt(100.0 * 101.0 / 12.0), 1e-9);
    CHECK_NEAR(s.cv, s.stddev / 50.5, 1e-12);

    double one = 4.25;
    CHECK(stats_compute(&one, 1, &s));
    CHECK(s.mean == 4.25 && s.median == 4.25 && s.p99 == 4.25 && s.stddev == 0.0);

    double flat[5] = {2, 2, 2, 2, 2};
    CHECK(stats_compute(flat, 5, &s));
    CHECK(s.stddev == 0.0 && s.cv == 0.0);

    double even[4] = {4, 1, 3, 2};
    CHECK(stats_compute(even, 4, &s));
    CHECK_NEAR(s.median, 2.5, 1e-12);

    /* Median interval of 1..100: ranks floor(40.2) = 40 and ceil(60.8) = 61. */
    CHECK(stats_compute(v, 100, &s));
    CHECK(s.median_lo == 40.0 && s.median_hi == 61.0);
    CHECK(stats_compute(even, 4, &s) && s.median_lo == 1.0 && s.median_hi == 4.0);

    /* Mean interval: 10, 12, 14 has mean 12, sd 2: 12 -+ 4.303 * 2 / sqrt(3). */
    double three[3] = {10, 12, 14}, lo, hi;
    CHECK(stats_mean_ci95(three, 3, &lo, &hi));
    CHECK_NEAR(lo, 12.0 - 4.303 * 2.0 / sqrt(3.0), 1e-9);
    CHECK_NEAR(hi, 12.0 + 4.303 * 2.0 / sqrt(3.0), 1e-9);
    CHECK(!stats_mean_ci95(three, 1, &lo, &hi));

    /* The repeat rule: tight runs are stable, noisy ones and too few are not. */
    double tight[5] = {10.0, 10.1, 9.9, 10.05, 9.95}, noisy[5] = {10, 13, 8, 12, 9};
    CHECK(stats_is_stable(tight, 5, 0.025));
    CHECK(!stats_is_stable(noisy, 5, 0.025));
    CHECK(!stats_is_stable(tight, 2, 0.025));

    CHECK(!stats_compute(v, 0, &s));
    CHECK(s.n == 0);
    return check_finish("test_stats");
}
