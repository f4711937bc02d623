#ifndef SHADEBENCH_TREND_H
#define SHADEBENCH_TREND_H

/* A trend chart of one figure over time, as SVG written by hand: the client
 * stays on libcurl and jansson alone (a CI runner needs no cairo or fonts
 * for it), and SVG opens in every browser and CI artifact viewer. One line
 * per series (a workload: jobs that measure the same thing), a point per
 * job with its 95% interval (clamped so that it never crosses zero), noisy
 * runs drawn hollow with what disturbed them, a log y axis when the values
 * span more than a decade, and x ticks on round times labelled exactly
 * (a tick labelled 03:26 is at 03:26:00). The legend, under the plot,
 * names every series; past MAX_SERIES the chart says how many it left out.
 * GL-free, no I/O; pure; unit-tested. */

#include <stdbool.h>
#include <stddef.h>

enum { TREND_MAX_SERIES = 8 };

struct trend_point {
    double t;        /* seconds since 1970 */
    double y, lo, hi; /* lo/hi NAN when there is no interval */
    char series[48];  /* the series' key: points with the same key form a line */
    char name[240];   /* the series' name in the legend ("" : the key) */
    char label[64];  /* the job id, as a tooltip */
    bool noisy;       /* the run was disturbed: drawn hollow */
    double other_share; /* other processes' CPU share during it, NAN if unknown */
};

/* Ticks of a time axis from tmin to tmax (seconds since 1970, UTC): the
 * smallest round step (1, 2, 5, 10, 15, 30 s; 1, 2, 5, 10, 15, 30 min; 1,
 * 2, 3, 6, 12 h; 1, 2, 7, 14, 28 days, ...) that gives at most 8 ticks,
 * at multiples of the step, each labelled exactly in the coarsest format
 * that shows it: "%H:%M:%S" below a minute, "%H:%M" below a day (with the
 * date, "%m-%d %H:%M", when the axis spans more than a day), else
 * "%Y-%m-%d". Returns the count (at most cap); *step gets the step. */
int trend_time_ticks(double tmin, double tmax, double *ticks, char (*labels)[24], int cap,
                     double *step);

/* Returns a malloc'ed SVG document (NUL-terminated), or NULL when out of
 * memory. title and ylabel are plain text (escaped here). */
char *trend_svg(const struct trend_point *pts, size_t n, const char *title, const char *ylabel);

/* True when values spanning lo..hi are drawn on a log axis. */
bool trend_log_axis(double lo, double hi);

#endif
