#include <math.h>

#include "client/stats_test.h"
#include "tests/unit/check.h"

int main(void)
{
    /* a = 1..5, b = 6..10: U_b = 25, mean 12.5, variance 25 * 11 / 12, so
     * z = (25 - 12.5 - 0.5) / sqrt(22.9167) = 2.5067 and p = 0.006092
     * (scipy.stats.mannwhitneyu(b, a, alternative="greater",
     * method="asymptotic") gives the same). */
    double a[5] = {1, 2, 3, 4, 5}, b[5] = {6, 7, 8, 9, 10};
    CHECK_NEAR(mann_whitney_p_greater(a, 5, b, 5), 0.006092, 1e-5);
    /* The other direction is not significant. */
    CHECK(mann_whitney_p_greater(b, 5, a, 5) > 0.99);

    /* Ties are averaged: identical samples are never significant. */
    double same[6] = {3, 3, 3, 3, 3, 3};
    CHECK(mann_whitney_p_greater(same, 6, same, 6) >= 0.5);

    /* A 10% slowdown over 60 noisy frames is a regression at 5%... */
    double base[60], slow[60], same_job[60];
    for (int i = 0; i < 60; i++) {
        double noise = sin(i * 12.9898) * 0.5; /* deterministic, +-0.5 ms */
        base[i] = 10.0 + noise;
        slow[i] = 11.0 + sin(i * 78.233) * 0.5;
        same_job[i] = 10.0 + sin(i * 78.233) * 0.5;
    }
    struct regression_verdict v;
    CHECK(regression_test(base, 60, slow, 60, 0.05, &v));
    CHECK(v.regression && v.significant && v.slowdown > 0.05 && v.p_value < 0.05);
    /* ...but not when 20% is allowed, and the same job passes. */
    CHECK(regression_test(base, 60, slow, 60, 0.20, &v) && !v.regression);
    CHECK(regression_test(base, 60, same_job, 60, 0.05, &v) && !v.regression);
    CHECK(fabs(v.slowdown) < 0.05);

    /* Slower by more than allowed but too noisy to tell: no regression. */
    double wild_base[4] = {5, 20, 8, 14}, wild_new[4] = {6, 21, 9, 15};
    CHECK(regression_test(wild_base, 4, wild_new, 4, 0.05, &v));
    CHECK(v.slowdown > 0.05 && !v.significant && !v.regression);

    CHECK(!regression_test(base, 0, slow, 60, 0.05, &v));
    return check_finish("test_baseline");
}
