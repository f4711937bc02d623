#include "client/stats_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/stats.h"

struct ranked {
    double v;
    int group; /* 0: a, 1: b */
};

static int by_value(const void *x, const void *y)
{
    double a = ((const struct ranked *)x)->v, b = ((const struct ranked *)y)->v;
    return (a > b) - (a < b);
}

double mann_whitney_p_greater(const double *a, size_t na, const double *b, size_t nb)
{
    size_t n = na + nb;
    struct ranked *all = malloc(n * sizeof(*all));
    if (!all || !na || !nb) {
        free(all);
        return 1.0;
    }
    for (size_t i = 0; i < na; i++)
        all[i] = (struct ranked){a[i], 0};
    for (size_t i = 0; i < nb; i++)
        all[na + i] = (struct ranked){b[i], 1};
    qsort(all, n, sizeof(*all), by_value);
    double rank_sum_b = 0, ties = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && all[j].v == all[i].v)
            j++;
        double t = (double)(j - i), avg_rank = (double)(i + j + 1) / 2.0; /* 1-based */
        for (size_t k = i; k < j; k++)
            if (all[k].group == 1)
                rank_sum_b += avg_rank;
        ties += t * t * t - t;
        i = j;
    }
    free(all);
    double n1 = (double)na, n2 = (double)nb, nn = (double)n;
    double u_b = rank_sum_b - n2 * (n2 + 1) / 2.0;
    double mean = n1 * n2 / 2.0;
    double var = n1 * n2 / 12.0 * ((nn + 1) - ties / (nn * (nn - 1)));
    if (var <= 0)
        return u_b > mean ? 0.0 : 1.0;
    double z = (u_b - mean - 0.5) / sqrt(var);
    return 0.5 * erfc(z / sqrt(2.0));
}

bool regression_test(const double *baseline, size_t nb, const double *current, size_t nc,
                     double max_slowdown, struct regression_verdict *out)
{
    memset(out, 0, sizeof(*out));
    struct stats sb, sc;
    if (!stats_compute(baseline, nb, &sb) || !stats_compute(current, nc, &sc))
        return false;
    out->baseline_median = sb.median;
    out->new_median = sc.median;
    out->slowdown = sb.median > 0 ? sc.median / sb.median - 1.0 : 0.0;
    out->p_value = mann_whitney_p_greater(baseline, nb, current, nc);
    out->significant = out->p_value < 0.05;
    out->regression = out->slowdown > max_slowdown && out->significant;
    return true;
}
