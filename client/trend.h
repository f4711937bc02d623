#ifndef SHADEBENCH_TREND_H
#define SHADEBENCH_TREND_H

/* A trend chart of one figure over time, as SVG written by hand: the client
 * stays on libcurl and jansson alone (a CI runner needs no cairo or fonts
 * for it), and SVG opens in every browser and CI artifact viewer. One line
 * per series (technique), a point per job with its 95% interval (clamped so
 * that it never crosses zero), a log y axis when the values span more than
 * a decade, and dated x ticks. GL-free, no I/O; pure; unit-tested. */

#include <stdbool.h>
#include <stddef.h>

struct trend_point {
    double t;        /* seconds since 1970 */
    double y, lo, hi; /* lo/hi NAN when there is no interval */
    char series[48];
    char label[64];  /* the job id, as a tooltip */
};

/* Returns a malloc'ed SVG document (NUL-terminated), or NULL when out of
 * memory. title and ylabel are plain text (escaped here). */
char *trend_svg(const struct trend_point *pts, size_t n, const char *title, const char *ylabel);

/* True when values spanning lo..hi are drawn on a log axis. */
bool trend_log_axis(double lo, double hi);

#endif
