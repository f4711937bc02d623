#include "client/stats_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Continued fraction of the incomplete beta function (modified Lentz). */
static double beta_cf(double a, double b, double x)
{
    const double tiny = 1e-300;
    double qab = a + b, qap = a + 1.0, qam = a - 1.0;
    double c = 1.0, d = 1.0 - qab * x / qap;
    if (fabs(d) < tiny)
        d = tiny;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 300; m++) {
        double m2 = 2.0 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = fabs(d) < tiny ? tiny : d;
        c = 1.0 + aa / c;
        c = fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = fabs(d) < tiny ? tiny : d;
        c = 1.0 + aa / c;
        c = fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15)
            break;
    }
    return h;
}

/* Regularised incomplete beta I_x(a, b). */
static double beta_inc(double a, double b, double x)
{
    if (x <= 0)
        return 0.0;
    if (x >= 1)
        return 1.0;
    double front = exp(lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log1p(-x));
    if (x < (a + 1.0) / (a + b + 2.0))
        return front * beta_cf(a, b, x) / a;
    return 1.0 - front * beta_cf(b, a, 1.0 - x) / b;
}

double student_t_cdf(double t, double df)
{
    if (isinf(t))
        return t > 0 ? 1.0 : 0.0;
    double tail = 0.5 * beta_inc(df / 2.0, 0.5, df / (df + t * t));
    return t > 0 ? 1.0 - tail : tail;
}

double student_t_quantile(double p, double df)
{
    if (p == 0.5)
        return 0.0;
    if (p < 0.5)
        return -student_t_quantile(1.0 - p, df);
    /* Bisection: the cdf is monotonic, and 200 halvings of [0, 1e8] reach
     * far below double precision. */
    double lo = 0.0, hi = 1e8;
    for (int i = 0; i < 200 && hi - lo > 1e-12 * (1.0 + lo); i++) {
        double mid = 0.5 * (lo + hi);
        if (student_t_cdf(mid, df) < p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* Mean and sample variance of the logs; false for a value that is not positive. */
static bool log_moments(const double *v, size_t n, double *mean, double *var)
{
    double m = 0.0, m2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        if (!(v[i] > 0) || !isfinite(v[i]))
            return false;
        double x = log(v[i]), delta = x - m;
        m += delta / (double)(i + 1);
        m2 += delta * (x - m);
    }
    *mean = m;
    *var = n > 1 ? m2 / (double)(n - 1) : 0.0;
    return true;
}

/* Fills the interval from the log difference d, its standard error and df. */
static void finish_interval(double d, double se, double df, double confidence,
                            struct ratio_interval *out)
{
    out->ratio = exp(d);
    out->df = df;
    out->confidence = confidence;
    if (!(se > 0) || !(df > 0)) {
        /* No spread at all: the ratio is exact. */
        out->lo = out->hi = out->ratio;
        out->p_greater = d > 0 ? 0.0 : (d < 0 ? 1.0 : 0.5);
        return;
    }
    double t = student_t_quantile(0.5 + confidence / 2.0, df);
    out->lo = exp(d - t * se);
    out->hi = exp(d + t * se);
    out->p_greater = 1.0 - student_t_cdf(d / se, df);
}

bool welch_log_ratio(const double *a, size_t na, const double *b, size_t nb, double confidence,
                     struct ratio_interval *out)
{
    memset(out, 0, sizeof(*out));
    double ma, va, mb, vb;
    if (na == 0 || nb == 0 || na + nb < 3 || !log_moments(a, na, &ma, &va) ||
        !log_moments(b, nb, &mb, &vb))
        return false;
    out->na = na;
    out->nb = nb;
    out->cv_a = sqrt(va);
    out->cv_b = sqrt(vb);
    double se, df;
    if (na == 1 || nb == 1) {
        /* One run on a side tells nothing of its spread: assume the other's. */
        double v = na == 1 ? vb : va;
        size_t n_other = na == 1 ? nb : na;
        se = sqrt(v * (1.0 / (double)na + 1.0 / (double)nb));
        df = (double)(n_other - 1);
        if (na == 1)
            out->cv_a = out->cv_b;
        else
            out->cv_b = out->cv_a;
    } else {
        double sa = va / (double)na, sb = vb / (double)nb;
        se = sqrt(sa + sb);
        double denom = sa * sa / (double)(na - 1) + sb * sb / (double)(nb - 1);
        df = denom > 0 ? (sa + sb) * (sa + sb) / denom : (double)(na + nb - 2);
    }
    finish_interval(mb - ma, se, df, confidence, out);
    return true;
}

bool paired_log_ratio(const double *a, const double *b, size_t n, double confidence,
                      struct ratio_interval *out)
{
    memset(out, 0, sizeof(*out));
    if (n < 2)
        return false;
    double *d = malloc(n * sizeof(double));
    if (!d)
        return false;
    double ma, va, mb, vb;
    bool ok = log_moments(a, n, &ma, &va) && log_moments(b, n, &mb, &vb);
    for (size_t i = 0; ok && i < n; i++)
        d[i] = b[i] / a[i];
    double md = 0, vd = 0;
    ok = ok && log_moments(d, n, &md, &vd);
    free(d);
    if (!ok)
        return false;
    out->na = out->nb = n;
    out->cv_a = sqrt(va);
    out->cv_b = sqrt(vb);
    finish_interval(md, sqrt(vd / (double)n), (double)(n - 1), confidence, out);
    return true;
}
