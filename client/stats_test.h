#ifndef SHADEBENCH_STATS_TEST_H
#define SHADEBENCH_STATS_TEST_H

/* The statistics behind the client's verdicts, for few samples: Student's t
 * (exact, through the regularised incomplete beta function, so that Welch's
 * fractional degrees of freedom need no table), and confidence intervals of
 * a ratio of run medians, computed on their logarithms because run-to-run
 * noise is multiplicative (a busy machine slows a run by a share, not by
 * milliseconds) and so that the interval of a ratio never reaches zero.
 * Pure functions: GL-free, no I/O, any thread; unit-tested. */

#include <stdbool.h>
#include <stddef.h>

/* P(T <= t) for Student's t with df > 0 degrees of freedom. */
double student_t_cdf(double t, double df);

/* The p quantile (0 < p < 1) of Student's t with df > 0 degrees of freedom. */
double student_t_quantile(double p, double df);

/* A ratio of typical values (b over a) with its two-sided confidence
 * interval at the confidence asked for. */
struct ratio_interval {
    size_t na, nb;      /* samples used */
    double ratio;       /* exp(mean log b - mean log a) */
    double lo, hi;      /* interval of the ratio */
    double df;          /* degrees of freedom of the t used */
    double cv_a, cv_b;  /* run-to-run spread of each side (stddev of logs ~ CV) */
    double p_greater;   /* one-sided p-value that b is larger than a */
    double confidence;
};

/* Two independent samples (Welch's t on logs, unequal variances). With one
 * sample on a side, that side's spread is taken to equal the other's (a
 * pooled t with the other side's degrees of freedom). False when a value is
 * not positive, or there are fewer than 3 values in all, or one side is
 * empty. */
bool welch_log_ratio(const double *a, size_t na, const double *b, size_t nb, double confidence,
                     struct ratio_interval *out);

/* Paired samples (a[i] and b[i] measured side by side): a one-sample t on
 * log(b[i] / a[i]). False below 2 pairs or for values that are not
 * positive. na = nb = pairs. */
bool paired_log_ratio(const double *a, const double *b, size_t n, double confidence,
                      struct ratio_interval *out);

#endif
