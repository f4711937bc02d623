#define _POSIX_C_SOURCE 200809L
#include "client/trend.h"
#include "common/axis.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { W = 900, PLOT_H = 520, MAX_SERIES = TREND_MAX_SERIES };
static const double L = 80, R = 40, T = 50, B = 70, LEGEND_LINE = 18;
static const char *const COLOURS[MAX_SERIES] = {"#0072b2", "#e69f00", "#009e73", "#cc79a7",
                                                "#56b4e9", "#d55e00", "#f0e442", "#595959"};

struct out {
    char *data;
    size_t len, cap;
    bool failed;
};

static void add(struct out *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add(struct out *o, const char *fmt, ...)
{
    if (o->failed)
        return;
    va_list ap;
    va_start(ap, fmt);
    char buf[1024];
    int n = vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    size_t len = (size_t)n < sizeof(buf) ? (size_t)n : sizeof(buf) - 1;
    if (o->len + len + 1 > o->cap) {
        size_t cap = (o->len + len + 1) * 2;
        char *grown = realloc(o->data, cap);
        if (!grown) {
            o->failed = true;
            return;
        }
        o->data = grown;
        o->cap = cap;
    }
    memcpy(o->data + o->len, buf, len);
    o->len += len;
    o->data[o->len] = '\0';
}

static void escaped(struct out *o, const char *s)
{
    for (; s && *s; s++)
        switch (*s) {
        case '<': add(o, "&lt;"); break;
        case '>': add(o, "&gt;"); break;
        case '&': add(o, "&amp;"); break;
        case '"': add(o, "&quot;"); break;
        default:
            if ((unsigned char)*s >= 0x20)
                add(o, "%c", *s);
        }
}

bool trend_log_axis(double lo, double hi) { return lo > 0 && hi / lo > 10.0; }

int trend_time_ticks(double tmin, double tmax, double *ticks, char (*labels)[24], int cap,
                     double *step)
{
    static const double steps[] = {1,     2,     5,     10,     15,     30,     60,      120,
                                   300,   600,   900,   1800,   3600,   7200,   10800,   21600,
                                   43200, 86400, 172800, 604800, 1209600, 2419200};
    double span = tmax - tmin, st = 0;
    for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]) && !st; i++)
        if (span / steps[i] <= 7.0)
            st = steps[i];
    if (!st) /* beyond 28-day steps: whole multiples of 28 days */
        st = 2419200.0 * ceil(span / 7.0 / 2419200.0);
    *step = st;
    const char *fmt = st < 60 ? "%H:%M:%S" : st < 86400 ? (span > 86400 ? "%m-%d %H:%M" : "%H:%M")
                                                       : "%Y-%m-%d";
    int n = 0;
    for (double t = ceil(tmin / st) * st; t <= tmax + 1e-6 && n < cap; t += st) {
        time_t tt = (time_t)llround(t);
        struct tm tm;
        gmtime_r(&tt, &tm);
        ticks[n] = (double)tt;
        strftime(labels[n], sizeof(labels[0]), fmt, &tm);
        n++;
    }
    return n;
}

/* The series of the points, in order of first appearance; past MAX_SERIES
 * they are counted, not drawn. */
struct series_list {
    const char *key[MAX_SERIES];
    const char *name[MAX_SERIES];
    int n, left_out;
};

static int series_index(const struct series_list *sl, const char *key)
{
    for (int s = 0; s < sl->n; s++)
        if (!strcmp(sl->key[s], key))
            return s;
    return -1;
}

char *trend_svg(const struct trend_point *pts, size_t n, const char *title, const char *ylabel)
{
    struct out o = {0};
    struct series_list sl = {.n = 0};
    const char *seen_extra[64];
    int nextra = 0;
    for (size_t i = 0; i < n; i++) {
        if (series_index(&sl, pts[i].series) >= 0)
            continue;
        if (sl.n < MAX_SERIES) {
            sl.key[sl.n] = pts[i].series;
            sl.name[sl.n++] = pts[i].name[0] ? pts[i].name : pts[i].series;
            continue;
        }
        bool seen = false;
        for (int k = 0; k < nextra && !seen; k++)
            seen = !strcmp(seen_extra[k], pts[i].series);
        if (!seen) {
            if (nextra < 64)
                seen_extra[nextra++] = pts[i].series;
            sl.left_out++;
        }
    }
    int legend_lines = sl.n + (sl.left_out > 0) + 1;
    int H = PLOT_H + (int)(legend_lines * LEGEND_LINE);
    double x0 = L, x1 = W - R, y0 = PLOT_H - B, y1 = T;
    double tmin = INFINITY, tmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (series_index(&sl, pts[i].series) < 0)
            continue;
        tmin = fmin(tmin, pts[i].t);
        tmax = fmax(tmax, pts[i].t);
        /* Intervals never cross zero: figures here are times and scores. */
        double lo = isnan(pts[i].lo) ? pts[i].y : fmax(pts[i].lo, 0.0);
        double hi = isnan(pts[i].hi) ? pts[i].y : pts[i].hi;
        ymin = fmin(ymin, fmin(pts[i].y, lo));
        ymax = fmax(ymax, fmax(pts[i].y, hi));
    }
    if (!(tmax >= tmin)) {
        tmin = 0;
        tmax = 1;
        ymin = 0;
        ymax = 1;
    }
    bool logy = trend_log_axis(ymin, ymax);
    if (tmax - tmin < 60) {
        /* Jobs within a minute: a minute's axis, so that it has ticks. */
        double mid = (tmin + tmax) / 2;
        tmin = mid - 30;
        tmax = mid + 30;
    }
    double pad = (tmax - tmin) * 0.05;
    tmin -= pad;
    tmax += pad;
    double ylo, yhi;
    if (logy) {
        ylo = log10(ymin) - 0.05;
        yhi = log10(ymax) + 0.05;
    } else {
        if (!(ymax > ymin)) {
            ymin = ymin > 0 ? ymin * 0.9 : ymin - 1;
            ymax = ymax > 0 ? ymax * 1.1 : ymax + 1;
        }
        double p = (ymax - ymin) * 0.08;
        ylo = ymin - p < 0 && ymin >= 0 ? 0 : ymin - p;
        yhi = ymax + p;
    }
#define MAPX(t) (x0 + ((t) - tmin) / (tmax - tmin) * (x1 - x0))
#define YV(v) (logy ? log10(v) : (v))
#define MAPY(v) (y0 + (YV(v) - ylo) / (yhi - ylo) * (y1 - y0))
    add(&o, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
            "width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" font-family=\"sans-serif\">\n",
        W, H, W, H);
    add(&o, "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n<text x=\"%g\" y=\"30\" "
            "font-size=\"16\" font-weight=\"bold\">", x0);
    escaped(&o, title);
    add(&o, "</text>\n");
    /* Y grid and ticks. */
    if (logy) {
        for (int e = (int)floor(ylo); e <= (int)ceil(yhi); e++)
            for (int m = 1; m < 10; m++) {
                double v = m * pow(10.0, e);
                if (YV(v) < ylo || YV(v) > yhi || (m != 1 && m != 2 && m != 5))
                    continue;
                add(&o, "<line x1=\"%g\" x2=\"%g\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#e0e0e0\"/>"
                        "<text x=\"%g\" y=\"%.1f\" font-size=\"12\" text-anchor=\"end\">%g</text>\n",
                    x0, x1, MAPY(v), MAPY(v), x0 - 8, MAPY(v) + 4, v);
            }
    } else {
        double step = axis_tick_step(yhi - ylo);
        for (double v = ceil(ylo / step) * step; v <= yhi; v += step)
            add(&o, "<line x1=\"%g\" x2=\"%g\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#e0e0e0\"/>"
                    "<text x=\"%g\" y=\"%.1f\" font-size=\"12\" text-anchor=\"end\">%g</text>\n",
                x0, x1, MAPY(v), MAPY(v), x0 - 8, MAPY(v) + 4, fabs(v) < step * 1e-6 ? 0.0 : v);
    }
    /* X ticks on round times, each labelled exactly. */
    double ticks[16], tstep;
    char labels[16][24];
    int nt = trend_time_ticks(tmin, tmax, ticks, labels, 16, &tstep);
    for (int k = 0; k < nt; k++)
        add(&o, "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%g\" y2=\"%g\" stroke=\"#e0e0e0\"/>"
                "<text class=\"tick\" data-t=\"%.0f\" x=\"%.1f\" y=\"%g\" font-size=\"12\" "
                "text-anchor=\"middle\">%s</text>\n",
            MAPX(ticks[k]), MAPX(ticks[k]), y0, y1, ticks[k], MAPX(ticks[k]), y0 + 18, labels[k]);
    add(&o, "<rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"#222\"/>\n",
        x0, y1, x1 - x0, y0 - y1);
    add(&o, "<text x=\"%g\" y=\"%g\" font-size=\"14\" text-anchor=\"middle\">job created (UTC)"
            "</text>\n", (x0 + x1) / 2, y0 + 44);
    add(&o, "<text transform=\"translate(24 %g) rotate(-90)\" font-size=\"14\" "
            "text-anchor=\"middle\">", (y0 + y1) / 2);
    escaped(&o, ylabel);
    add(&o, "%s</text>\n", logy ? " (log scale)" : "");
    /* One line per series, in time order, then the points. */
    for (int s = 0; s < sl.n; s++) {
        add(&o, "<g class=\"series\" data-series=\"");
        escaped(&o, sl.key[s]);
        add(&o, "\" stroke=\"%s\" fill=\"%s\">\n<polyline fill=\"none\" stroke-width=\"2\" points=\"",
            COLOURS[s], COLOURS[s]);
        double last = -INFINITY;
        for (;;) {
            size_t best = n;
            for (size_t i = 0; i < n; i++)
                if (!strcmp(pts[i].series, sl.key[s]) && pts[i].t > last &&
                    (best == n || pts[i].t < pts[best].t))
                    best = i;
            if (best == n)
                break;
            add(&o, "%.1f,%.1f ", MAPX(pts[best].t), MAPY(pts[best].y));
            last = pts[best].t;
        }
        add(&o, "\"/>\n");
        for (size_t i = 0; i < n; i++) {
            const struct trend_point *p = &pts[i];
            if (strcmp(p->series, sl.key[s]) != 0)
                continue;
            if (!isnan(p->lo) && !isnan(p->hi)) {
                double lo = fmax(p->lo, logy ? ymin : 0.0);
                add(&o, "<line class=\"interval\" x1=\"%.1f\" x2=\"%.1f\" y1=\"%.1f\" y2=\"%.1f\" "
                        "data-low=\"%g\" data-high=\"%g\"/>\n",
                    MAPX(p->t), MAPX(p->t), MAPY(lo), MAPY(p->hi), lo, p->hi);
            }
            /* A noisy run: hollow, and the tooltip says what disturbed it. */
            add(&o, "<circle class=\"point\" cx=\"%.1f\" cy=\"%.1f\" r=\"4\" data-value=\"%g\" "
                    "data-t=\"%.0f\"%s><title>", MAPX(p->t), MAPY(p->y), p->y, p->t,
                p->noisy ? " data-noisy=\"true\" fill=\"white\" stroke-width=\"2\"" : "");
            escaped(&o, p->label);
            add(&o, ": %g", p->y);
            if (p->noisy && !isnan(p->other_share))
                add(&o, " (noisy: other processes took %.0f%% of the CPU)", 100 * p->other_share);
            else if (p->noisy)
                add(&o, " (noisy)");
            add(&o, "</title></circle>\n");
        }
        add(&o, "</g>\n");
    }
    /* The legend under the plot: every series by its full name. */
    double ly = PLOT_H + 4;
    for (int s = 0; s < sl.n; s++, ly += LEGEND_LINE) {
        add(&o, "<circle cx=\"%g\" cy=\"%.1f\" r=\"5\" fill=\"%s\"/><text class=\"legend\" "
                "x=\"%g\" y=\"%.1f\" font-size=\"12\">", x0 + 6, ly - 4, COLOURS[s], x0 + 18, ly);
        escaped(&o, sl.name[s]);
        add(&o, "</text>\n");
    }
    add(&o, "<circle cx=\"%g\" cy=\"%.1f\" r=\"4\" fill=\"white\" stroke=\"#222\" "
            "stroke-width=\"2\"/><text x=\"%g\" y=\"%.1f\" font-size=\"12\">hollow: a run the "
            "daemon found noisy (result.interference); hover for the CPU others took</text>\n",
        x0 + 6, ly - 4, x0 + 18, ly);
    ly += LEGEND_LINE;
    if (sl.left_out)
        add(&o, "<text class=\"left-out\" x=\"%g\" y=\"%.1f\" font-size=\"12\">%d more "
                "workload%s not drawn (at most %d series): narrow the history with --filter</text>\n",
            x0, ly, sl.left_out, sl.left_out == 1 ? "" : "s", MAX_SERIES);
    if (n == 0)
        add(&o, "<text x=\"%g\" y=\"%g\" font-size=\"14\" text-anchor=\"middle\">no matching "
                "jobs</text>\n", (x0 + x1) / 2, (y0 + y1) / 2);
    add(&o, "</svg>\n");
#undef MAPX
#undef YV
#undef MAPY
    if (o.failed) {
        free(o.data);
        return NULL;
    }
    return o.data;
}
