#define _DEFAULT_SOURCE /* M_PI */
#define _POSIX_C_SOURCE 200809L
#include "daemon/reports/charts.h"
#include "common/result_keys.h"
#include "common/axis.h"
#include "common/timing_series.h"
#include "daemon/reports/sweep_verdict.h"

#include <cairo-svg.h>
#include <cairo.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { WIDTH = 900, HEIGHT = 560, MAX_SERIES = 8, MAX_WORKLOADS = 32, MAX_LEVELS = 16 };
static const double LEFT = 90, RIGHT = 200, TOP = 62, BOTTOM = 70, FOOTER_LINE = 15;

/* Colour-blind-safe (Okabe-Ito). */
static const double PALETTE[MAX_SERIES][3] = {
    {0.00, 0.45, 0.70}, {0.90, 0.62, 0.00}, {0.00, 0.62, 0.45}, {0.80, 0.47, 0.65},
    {0.34, 0.71, 0.91}, {0.84, 0.37, 0.00}, {0.94, 0.89, 0.26}, {0.35, 0.35, 0.35},
};

struct point {
    double x, y, x_lo, x_hi, y_lo, y_hi;
    bool lo_clamped;   /* the interval reached below zero and was cut at the axis */
    char label[64];
    int series;
    int workload;      /* index into chart.workloads; fronts never cross them */
    bool pareto, reference;
    double box[6];     /* distribution charts: min, p5, median, p95, p99, max */
    bool runs_median;  /* box[2] is the median of run medians, the box the first run's */
    bool placed;       /* label drawn at lx, ly (top-left) with size lw, lh */
    double lx, ly, lw, lh;
    bool tied;         /* on the front, but its time overlaps another front point's */
    bool judged, pdiff_pass; /* speed_accuracy: PerceptualDiff ran, and passed */
    bool noisy;        /* the point's run was disturbed (sweep rows with interference) */
    double other_share;
    int tag;           /* label left out: its number in the key under the chart (0: none) */
    char tagtext[32];  /* the numbers drawn next to this point ("3" or "3,4": near points) */
    double tx, ty;     /* where tagtext is drawn (baseline start) */
};

/* A horizontal level: the reference where it has no x of its own. */
struct level {
    double y, lo, hi;
    char label[64];
};

struct axis {
    double lo, hi; /* in log10 units when log, in -log10(1 - v) when loss */
    bool log;
    /* SSIM's axis: -log10(1 - v), so that 0.999, 0.9999 and 0.99999 are a
     * decade apart instead of a hair; 1 - v below floor (exact, or closer
     * than a tenth of the best inexact score) sits at floor, the top. */
    bool loss;
    double floor;
};

struct chart {
    const char *name;
    char title[160], subtitle[200], xlabel[128], ylabel[128];
    char series[MAX_SERIES][64];
    int nseries;
    struct point *pts;
    int n;
    bool lines, boxes, categorical_x, no_markers, x_log_ok;
    /* A swept parameter: log x only when every value is above zero (light
     * counts 16 to 16,384), never for a 0 that log would misplace. */
    bool x_log_param;
    char categories[64][112];
    int ncategories;
    char workloads[MAX_WORKLOADS][128];
    int nworkloads;
    struct level levels[MAX_LEVELS];
    int nlevels;
    int labels_left_out;
    struct axis ax, ay;
    bool quality_y, flip;  /* speed_accuracy: y is worst SSIM (or FLIP) */
    bool has_jnd;          /* PerceptualDiff's verdicts separate at jnd_y */
    double jnd_y;
    bool any_noisy, any_pdiff_fail, any_tied;
    char pdiff_note[160];  /* how PerceptualDiff relates to the y axis */
    /* Lines under the plot: the key of left-out labels, points not drawn,
     * a partial sweep. */
    char footer[96][160];
    int nfooter, footer_left_out;
    char partial[160];     /* "" or why the sweep is partial */
};

const char *charts_default_series(const json_t *device)
{
    return timing_series_for_renderer(json_string_value(json_object_get(device, "gl_renderer")));
}

static bool software_device(const json_t *device)
{
    return device && json_string_value(json_object_get(device, "gl_renderer")) &&
           strcmp(charts_default_series(device), RK_FRAME_MS) == 0;
}

/* What the series measures here, for the chart's subtitle. */
static void series_note(const char *series, const json_t *device, bool chosen, char *out,
                        size_t cap)
{
    bool sw = software_device(device);
    if (!strcmp(series, RK_FRAME_MS))
        snprintf(out, cap, "frame_ms: present-to-present time%s", chosen && sw
                 ? ", the default on llvmpipe, whose gpu_ms covers rasterization only" : "");
    else if (!strcmp(series, RK_GPU_MS))
        snprintf(out, cap, "gpu_ms: GPU time from timer queries%s",
                 sw ? "; on llvmpipe it covers rasterization only, frame_ms compares techniques"
                    : chosen ? ", the default on GPUs" : "");
    else
        snprintf(out, cap, "cpu_ms: CPU time to submit a frame");
}

/* ---- axes ---- */

/* On a log axis, zero and below sit at the axis' lower end. */
static double to_axis(const struct axis *a, double v)
{
    if (a->loss)
        return -log10(fmax(1.0 - v, a->floor));
    return a->log ? (v > 0 ? fmax(log10(v), a->lo) : a->lo) : v;
}

/* A value of the axis' own units back in data units. */
static double from_axis(const struct axis *a, double t)
{
    if (a->loss)
        return 1.0 - pow(10.0, -t);
    return a->log ? pow(10.0, t) : t;
}

static double map(const struct axis *a, double v, double p0, double p1)
{
    return p0 + (to_axis(a, v) - a->lo) / (a->hi - a->lo) * (p1 - p0);
}

/* A padded range over [lo, hi] (data units). Log when asked and the values
 * span more than a decade; a linear range over positive values never pads
 * below zero. */
static struct axis make_axis(double lo, double hi, bool log_ok, bool nonneg)
{
    struct axis a = {lo, hi, false, false, 0};
    if (log_ok && lo > 0 && hi / lo > 10.0) {
        a.log = true;
        a.lo = log10(lo) - 0.06 * (log10(hi) - log10(lo));
        a.hi = log10(hi) + 0.06 * (log10(hi) - log10(lo));
        return a;
    }
    if (!(hi > lo)) {
        double pad = fabs(lo) > 0 ? fabs(lo) * 0.1 : 1.0;
        lo -= pad;
        hi += pad;
    }
    double pad = (hi - lo) * 0.08;
    a.lo = nonneg && lo - pad < 0 && lo >= 0 ? 0 : lo - pad;
    a.hi = hi + pad;
    return a;
}

/* Calls fn for each tick value of the axis: 1, 2, 5 per decade on log
 * axes, round steps on linear ones. */
static int ticks(const struct axis *a, double *out, int cap)
{
    int n = 0;
    if (a->loss) {
        /* 0.9, 0.99, 0.999, ... (with 1 - 2 and 1 - 5 times the decade where
         * the axis spans few decades), and exact at the floor. */
        bool fine = a->hi - a->lo < 3.0;
        for (int e = (int)floor(a->lo); e <= (int)ceil(a->hi) && n < cap; e++)
            for (int m = 5; m >= 1 && n < cap; m -= m == 5 ? 3 : (m == 2 ? 1 : 1)) {
                if (m != 1 && !fine)
                    continue;
                double t = -log10(m * pow(10.0, -e));
                if (t >= a->lo && t <= a->hi && t < -log10(a->floor) - 0.3)
                    out[n++] = 1.0 - m * pow(10.0, -e);
            }
        if (n < cap && -log10(a->floor) <= a->hi)
            out[n++] = 1.0;
        return n;
    }
    if (a->log) {
        for (int e = (int)floor(a->lo); e <= (int)ceil(a->hi) && n < cap; e++)
            for (int m = 1; m <= 5 && n < cap; m += m == 1 ? 1 : 3) {
                double v = m * pow(10.0, e);
                if (log10(v) >= a->lo && log10(v) <= a->hi)
                    out[n++] = v;
            }
        return n;
    }
    double step = axis_tick_step(a->hi - a->lo);
    for (double v = ceil(a->lo / step) * step; v <= a->hi + step * 1e-9 && n < cap; v += step)
        out[n++] = fabs(v) < step * 1e-6 ? 0.0 : v;
    return n;
}

static void text(cairo_t *cr, double x, double y, const char *s, double size, double align)
{
    cairo_text_extents_t e;
    cairo_set_font_size(cr, size);
    cairo_text_extents(cr, s, &e);
    cairo_move_to(cr, x - e.width * align - e.x_bearing * (align == 0), y);
    cairo_show_text(cr, s);
}

struct frame {
    double x0, x1, y0, y1;
};

static double px(const struct chart *c, const struct frame *f, double x)
{
    return map(&c->ax, x, f->x0, f->x1);
}

static double py(const struct chart *c, const struct frame *f, double y)
{
    return map(&c->ay, y, f->y0, f->y1);
}

/* Joins the points of one series (series >= 0) or of one workload's Pareto
 * front (series < 0, workload w) in order of x. */
static void polyline_by_x(cairo_t *cr, const struct chart *c, int series, int w,
                          const struct frame *f)
{
    bool first = true;
    double last_x = -INFINITY;
    for (;;) {
        int best = -1;
        for (int i = 0; i < c->n; i++) {
            const struct point *p = &c->pts[i];
            bool member = series < 0 ? p->pareto && p->workload == w : p->series == series;
            if (member && p->x > last_x && (best < 0 || p->x < c->pts[best].x))
                best = i;
        }
        if (best < 0)
            break;
        double x = px(c, f, c->pts[best].x), y = py(c, f, c->pts[best].y);
        if (first)
            cairo_move_to(cr, x, y);
        else
            cairo_line_to(cr, x, y);
        first = false;
        last_x = c->pts[best].x;
    }
    cairo_stroke(cr);
}

/* ---- label placement: greedy, first free spot among eight around the
 * point; a label that fits nowhere gets a number instead, drawn next to the
 * point (one tag for points that sit on top of each other), and its full
 * label in the key under the chart: every point is named somewhere. ---- */

struct rect {
    double x, y, w, h;
};

static bool overlaps(struct rect a, struct rect b)
{
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

/* The first of eight spots around (x, y) for a w x h box inside the frame
 * that overlaps nothing taken; false when none is free. */
static bool free_spot(double x, double y, double w, double h, const struct frame *f,
                      const struct rect *taken, int nt, struct rect *out)
{
    const double cand[8][2] = {
        {x + 9, y - 7 - h},      {x + 9, y + 7},      {x - 9 - w, y - 7 - h}, {x - 9 - w, y + 7},
        {x - w / 2, y - 9 - h},  {x - w / 2, y + 9},  {x + 9, y - h / 2},     {x - 9 - w, y - h / 2},
    };
    for (int k = 0; k < 8; k++) {
        struct rect r = {cand[k][0], cand[k][1], w, h};
        bool ok = r.x >= f->x0 + 1 && r.x + r.w <= f->x1 - 1 && r.y >= f->y1 + 1 &&
                  r.y + r.h <= f->y0 - 1;
        for (int t = 0; ok && t < nt; t++)
            ok = !overlaps(r, taken[t]);
        if (ok) {
            *out = r;
            return true;
        }
    }
    return false;
}

static void add_footer(struct chart *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add_footer(struct chart *c, const char *fmt, ...)
{
    if (c->nfooter == (int)(sizeof(c->footer) / sizeof(c->footer[0]))) {
        c->footer_left_out++;
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->footer[c->nfooter++], sizeof(c->footer[0]), fmt, ap);
    va_end(ap);
}

static void place_labels(cairo_t *cr, struct chart *c, const struct frame *f)
{
    cairo_set_font_size(cr, 11);
    struct rect *taken = calloc((size_t)c->n * 5 + 1, sizeof(*taken));
    if (!taken)
        return;
    int nt = 0;
    for (int i = 0; i < c->n; i++) {
        /* Every marker and interval bar is an obstacle. */
        const struct point *p = &c->pts[i];
        double x = px(c, f, p->x), y = py(c, f, p->y);
        taken[nt++] = (struct rect){x - 6, y - 6, 12, 12};
        if (p->x_hi > p->x_lo) {
            double a = px(c, f, p->x_lo), b = px(c, f, p->x_hi);
            taken[nt++] = (struct rect){a, y - 4, b - a, 8};
        }
        if (p->y_hi > p->y_lo) {
            double a = py(c, f, p->y_hi), b = py(c, f, p->y_lo);
            taken[nt++] = (struct rect){x - 4, a, 8, b - a};
        }
    }
    for (int i = 0; i < c->n; i++) {
        struct point *p = &c->pts[i];
        if (!p->label[0])
            continue;
        cairo_text_extents_t e;
        cairo_text_extents(cr, p->label, &e);
        struct rect r;
        if (free_spot(px(c, f, p->x), py(c, f, p->y), e.x_advance + 2, 13, f, taken, nt, &r)) {
            p->placed = true;
            p->lx = r.x, p->ly = r.y, p->lw = r.w, p->lh = r.h;
            taken[nt++] = r;
        }
        c->labels_left_out += !p->placed;
    }
    /* Numbers for the rest; points within a marker of each other share one
     * tag ("3,4"), drawn by the first of them. */
    int next = 0;
    for (int i = 0; i < c->n; i++) {
        struct point *p = &c->pts[i];
        if (!p->label[0] || p->placed)
            continue;
        p->tag = ++next;
        double x = px(c, f, p->x), y = py(c, f, p->y);
        struct point *lead = p;
        for (int j = 0; j < i; j++) {
            struct point *q = &c->pts[j];
            if (q->tag && q->tagtext[0] && fabs(px(c, f, q->x) - x) < 10 &&
                fabs(py(c, f, q->y) - y) < 10) {
                lead = q;
                break;
            }
        }
        size_t used = strlen(lead->tagtext);
        snprintf(lead->tagtext + used, sizeof(lead->tagtext) - used, "%s%d", used ? "," : "",
                 p->tag);
    }
    cairo_set_font_size(cr, 10);
    for (int i = 0; i < c->n; i++) {
        struct point *p = &c->pts[i];
        if (!p->tagtext[0])
            continue;
        cairo_text_extents_t e;
        cairo_text_extents(cr, p->tagtext, &e);
        double x = px(c, f, p->x), y = py(c, f, p->y);
        struct rect r = {x + 7, y - 16, e.x_advance + 2, 11};
        /* Where no spot is free the tag still goes next to its point: a
         * number over something beats a point without a name. */
        if (free_spot(x, y, e.x_advance + 2, 11, f, taken, nt, &r))
            taken[nt++] = r;
        p->tx = r.x + 1, p->ty = r.y + r.h - 2;
    }
    free(taken);
}

static void diamond(cairo_t *cr, double x, double y, double r)
{
    cairo_move_to(cr, x, y - r);
    cairo_line_to(cr, x + r, y);
    cairo_line_to(cr, x, y + r);
    cairo_line_to(cr, x - r, y);
    cairo_close_path(cr);
}

/* The plot's frame: with many categories, labels slanted, with room made
 * for them below and to the left, so that they overlap neither each other
 * nor the axis title nor the edge. */
static struct frame frame_of(cairo_t *cr, const struct chart *c, double *angle_out)
{
    double left = LEFT, bottom = BOTTOM, angle = 0;
    if (c->categorical_x && c->ncategories > 4) {
        angle = 0.6;
        cairo_set_font_size(cr, 10);
        double span = WIDTH - RIGHT - LEFT;
        for (int i = 0; i < c->ncategories; i++) {
            cairo_text_extents_t e;
            cairo_text_extents(cr, c->categories[i], &e);
            left = fmax(left, 5 + e.x_advance * cos(angle) - (i + 0.5) * span / c->ncategories);
            bottom = fmax(bottom, e.x_advance * sin(angle) + 48);
        }
        left = fmin(left, WIDTH / 3.0);
        bottom = fmin(bottom, HEIGHT / 2.0);
    }
    *angle_out = angle;
    return (struct frame){left, WIDTH - RIGHT, HEIGHT - bottom, TOP};
}

static void draw(cairo_t *cr, struct chart *c)
{
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    double angle;
    const struct frame f = frame_of(cr, c, &angle);

    char buf[64];
    double tv[64];
    int nt = ticks(&c->ay, tv, 64);
    cairo_set_line_width(cr, 1);
    for (int i = 0; i < nt; i++) {
        double y = py(c, &f, tv[i]);
        cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
        cairo_move_to(cr, f.x0, y);
        cairo_line_to(cr, f.x1, y);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
        if (c->ay.loss && tv[i] >= 1.0)
            snprintf(buf, sizeof(buf), "1 (exact)");
        else if (c->ay.loss) /* as many decimals as the nines need: 0.99995 */
            snprintf(buf, sizeof(buf), "%.*f", (int)ceil(-log10(1.0 - tv[i]) - 1e-9), tv[i]);
        else
            snprintf(buf, sizeof(buf), "%.6g", tv[i]);
        text(cr, f.x0 - 8, y + 4, buf, 12, 1.0);
    }
    if (c->categorical_x) {
        for (int i = 0; i < c->ncategories; i++) {
            cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
            if (angle == 0) {
                text(cr, px(c, &f, i), f.y0 + 18, c->categories[i], 11, 0.5);
                continue;
            }
            cairo_save(cr);
            cairo_translate(cr, px(c, &f, i) + 3, f.y0 + 10);
            cairo_rotate(cr, -angle);
            text(cr, 0, 0, c->categories[i], 10, 1.0);
            cairo_restore(cr);
        }
    } else {
        nt = ticks(&c->ax, tv, 64);
        for (int i = 0; i < nt; i++) {
            double x = px(c, &f, tv[i]);
            cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
            cairo_move_to(cr, x, f.y0);
            cairo_line_to(cr, x, f.y1);
            cairo_stroke(cr);
            cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
            snprintf(buf, sizeof(buf), "%.6g", tv[i]);
            text(cr, x, f.y0 + 18, buf, 12, 0.5);
        }
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    cairo_rectangle(cr, f.x0, f.y1, f.x1 - f.x0, f.y0 - f.y1);
    cairo_stroke(cr);
    char axis_label[160];
    snprintf(axis_label, sizeof(axis_label), "%s%s", c->xlabel, c->ax.log ? " (log scale)" : "");
    text(cr, (f.x0 + f.x1) / 2, angle > 0 ? HEIGHT - 10 : HEIGHT - 22, axis_label, 14, 0.5);
    cairo_save(cr);
    cairo_translate(cr, f.x0 - 66, (f.y0 + f.y1) / 2);
    cairo_rotate(cr, -M_PI / 2);
    snprintf(axis_label, sizeof(axis_label), "%s%s", c->ylabel,
             c->ay.loss ? " (log scale of 1 - SSIM)" : c->ay.log ? " (log scale)" : "");
    text(cr, 0, 0, axis_label, 14, 0.5);
    cairo_restore(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    text(cr, f.x0, 26, c->title, 16, 0.0);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    text(cr, f.x0, 46, c->subtitle, 11, 0.0);

    if (c->n == 0 && c->nlevels == 0) {
        text(cr, (f.x0 + f.x1) / 2, (f.y0 + f.y1) / 2, "no finished points yet", 14, 0.5);
        return;
    }

    /* Reference levels: a dashed line with its interval as a band. */
    for (int i = 0; i < c->nlevels; i++) {
        const struct level *l = &c->levels[i];
        double y = py(c, &f, l->y);
        cairo_set_source_rgba(cr, 0.1, 0.1, 0.1, 0.05);
        if (l->hi > l->lo) {
            double a = py(c, &f, l->lo), b = py(c, &f, l->hi);
            cairo_rectangle(cr, f.x0, b, f.x1 - f.x0, a - b);
            cairo_fill(cr);
        }
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        double dash[] = {8, 4};
        cairo_set_dash(cr, dash, 2, 0);
        cairo_set_line_width(cr, 1.5);
        cairo_move_to(cr, f.x0, y);
        cairo_line_to(cr, f.x1, y);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        text(cr, f.x1 - 4, y - 4, l->label, 11, 1.0);
    }

    /* PerceptualDiff's just-noticeable difference, where its verdicts
     * separate along y: every point on the passing side passed. */
    if (c->has_jnd) {
        double y = py(c, &f, c->jnd_y);
        double dash[] = {3, 3};
        cairo_set_source_rgb(cr, 0.0, 0.5, 0.2);
        cairo_set_dash(cr, dash, 2, 0);
        cairo_set_line_width(cr, 1.2);
        cairo_move_to(cr, f.x0, y);
        cairo_line_to(cr, f.x1, y);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        text(cr, f.x0 + 4, y + (c->flip ? -4 : 12),
             c->flip ? "PerceptualDiff passes at and below this line (just-noticeable difference)"
                     : "PerceptualDiff passes at and above this line (just-noticeable difference)",
             10, 0.0);
    }

    /* Pareto fronts first, under the points: one per workload, each with
     * a dash pattern of its own (named in the legend). */
    static const double DASHES[4][2] = {{6, 4}, {2, 3}, {10, 3}, {4, 2}};
    bool any_front = false;
    for (int w = 0; w < c->nworkloads; w++) {
        int members = 0;
        for (int i = 0; i < c->n; i++)
            members += c->pts[i].pareto && c->pts[i].workload == w;
        if (members < 1)
            continue;
        any_front = true;
        if (members < 2)
            continue;
        cairo_set_source_rgba(cr, 0.2, 0.2, 0.2, 0.7);
        cairo_set_line_width(cr, 1.5);
        cairo_set_dash(cr, DASHES[w % 4], 2, 0);
        polyline_by_x(cr, c, -1, w, &f);
        cairo_set_dash(cr, NULL, 0, 0);
    }

    for (int s = 0; s < c->nseries; s++) {
        const double *col = PALETTE[s % MAX_SERIES];
        if (c->lines) {
            cairo_set_source_rgb(cr, col[0], col[1], col[2]);
            cairo_set_line_width(cr, c->no_markers ? 1.2 : 2);
            polyline_by_x(cr, c, s, 0, &f);
        }
        if (c->no_markers)
            continue;
        for (int i = 0; i < c->n; i++) {
            struct point *p = &c->pts[i];
            if (p->series != s)
                continue;
            double x = px(c, &f, p->x), y = py(c, &f, p->y);
            cairo_set_source_rgb(cr, col[0], col[1], col[2]);
            cairo_set_line_width(cr, 1.5);
            if (c->boxes) {
                /* Whiskers min-max, box p5-p95, median line, p99 tick. */
                double w = fmin(40.0, (f.x1 - f.x0) / (c->ncategories * 2.5));
                double b[6];
                for (int k = 0; k < 6; k++)
                    b[k] = py(c, &f, p->box[k]);
                cairo_move_to(cr, x, b[0]);
                cairo_line_to(cr, x, b[5]);
                cairo_stroke(cr);
                cairo_rectangle(cr, x - w / 2, b[3], w, b[1] - b[3]);
                cairo_set_source_rgba(cr, col[0], col[1], col[2], 0.3);
                cairo_fill_preserve(cr);
                cairo_set_source_rgb(cr, col[0], col[1], col[2]);
                cairo_stroke(cr);
                cairo_set_line_width(cr, 3);
                if (p->runs_median) {
                    /* Not this run's median: a mark of its own. */
                    cairo_set_line_width(cr, 2);
                    diamond(cr, x, b[2], 6);
                    cairo_stroke(cr);
                } else {
                    cairo_move_to(cr, x - w / 2, b[2]);
                    cairo_line_to(cr, x + w / 2, b[2]);
                    cairo_stroke(cr);
                }
                cairo_set_line_width(cr, 1.5);
                cairo_move_to(cr, x - w / 4, b[4]);
                cairo_line_to(cr, x + w / 4, b[4]);
                cairo_stroke(cr);
                continue;
            }
            /* Error bars from the intervals; a bar cut at zero ends in an
             * arrow head instead of a cap. */
            if (p->x_hi > p->x_lo) {
                double a = px(c, &f, p->x_lo), b = px(c, &f, p->x_hi);
                cairo_move_to(cr, a, y);
                cairo_line_to(cr, b, y);
                cairo_move_to(cr, b, y - 4);
                cairo_line_to(cr, b, y + 4);
                if (p->lo_clamped) {
                    cairo_move_to(cr, a + 5, y - 4);
                    cairo_line_to(cr, a, y);
                    cairo_line_to(cr, a + 5, y + 4);
                } else {
                    cairo_move_to(cr, a, y - 4);
                    cairo_line_to(cr, a, y + 4);
                }
                cairo_stroke(cr);
            }
            if (p->y_hi > p->y_lo) {
                double a = py(c, &f, p->y_lo), b = py(c, &f, p->y_hi);
                cairo_move_to(cr, x - 4, a);
                cairo_line_to(cr, x + 4, a);
                cairo_move_to(cr, x, a);
                cairo_line_to(cr, x, b);
                cairo_move_to(cr, x - 4, b);
                cairo_line_to(cr, x + 4, b);
                cairo_stroke(cr);
            }
            if (p->reference) {
                diamond(cr, x, y, 6.5);
            } else {
                cairo_new_sub_path(cr);
                cairo_arc(cr, x, y, 4.5, 0, 2 * M_PI);
            }
            if (p->judged && !p->pdiff_pass) {
                /* Hollow: PerceptualDiff sees a difference. */
                cairo_set_source_rgb(cr, 1, 1, 1);
                cairo_fill_preserve(cr);
                cairo_set_source_rgb(cr, col[0], col[1], col[2]);
                cairo_set_line_width(cr, 2);
                cairo_stroke(cr);
            } else {
                cairo_fill(cr);
            }
            if (p->pareto) {
                /* On the front; dashed when tied with another front point. */
                double dash[] = {3, 2};
                cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
                cairo_set_line_width(cr, 1.5);
                cairo_set_dash(cr, dash, p->tied ? 2 : 0, 0);
                cairo_new_sub_path(cr);
                cairo_arc(cr, x, y, 9, 0, 2 * M_PI);
                cairo_stroke(cr);
                cairo_set_dash(cr, NULL, 0, 0);
            }
            if (p->noisy) {
                double dot[] = {1.5, 2.5};
                cairo_set_source_rgb(cr, 0.85, 0.35, 0.0);
                cairo_set_line_width(cr, 1.5);
                cairo_set_dash(cr, dot, 2, 0);
                cairo_new_sub_path(cr);
                cairo_arc(cr, x, y, 13, 0, 2 * M_PI);
                cairo_stroke(cr);
                cairo_set_dash(cr, NULL, 0, 0);
            }
            if (p->placed) {
                cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
                cairo_set_font_size(cr, 11);
                cairo_move_to(cr, p->lx + 1, p->ly + p->lh - 3);
                cairo_show_text(cr, p->label);
            }
            if (p->tagtext[0]) {
                cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
                cairo_set_font_size(cr, 10);
                cairo_move_to(cr, p->tx, p->ty);
                cairo_show_text(cr, p->tagtext);
            }
        }
    }

    /* Legend. */
    double ly = TOP + 10;
    for (int s = 0; s < c->nseries; s++, ly += 22) {
        const double *col = PALETTE[s % MAX_SERIES];
        cairo_set_source_rgb(cr, col[0], col[1], col[2]);
        bool ref = false;
        for (int i = 0; i < c->n && !ref; i++)
            ref = c->pts[i].series == s && c->pts[i].reference;
        if (ref) {
            diamond(cr, f.x1 + 20, ly, 6);
        } else {
            cairo_new_sub_path(cr);
            cairo_arc(cr, f.x1 + 20, ly, 5, 0, 2 * M_PI);
        }
        cairo_fill(cr);
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        text(cr, f.x1 + 32, ly + 4, c->series[s], 12, 0.0);
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    if (any_front) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, f.x1 + 20, ly, 8, 0, 2 * M_PI);
        cairo_stroke(cr);
        text(cr, f.x1 + 32, ly + 4, c->nworkloads > 1 ? "Pareto front, per workload"
                                                      : "Pareto front (on", 12, 0.0);
        if (c->nworkloads <= 1) {
            ly += 14;
            text(cr, f.x1 + 32, ly + 4, "intervals, see below)", 12, 0.0);
        }
        ly += 20;
        for (int w = 0; c->nworkloads > 1 && w < c->nworkloads && w < 8; w++, ly += 18) {
            cairo_set_line_width(cr, 1.5);
            cairo_set_dash(cr, DASHES[w % 4], 2, 0);
            cairo_move_to(cr, f.x1 + 12, ly);
            cairo_line_to(cr, f.x1 + 30, ly);
            cairo_stroke(cr);
            cairo_set_dash(cr, NULL, 0, 0);
            char wl[40];
            const char *dot = strrchr(c->workloads[w], '.');
            snprintf(wl, sizeof(wl), "%.38s", dot ? dot + 1 : c->workloads[w]);
            text(cr, f.x1 + 34, ly + 4, wl, 11, 0.0);
        }
        ly += 4;
    }
    /* What the marks mean, for the marks this chart uses. */
    if (c->any_tied) {
        double dash[] = {3, 2};
        cairo_set_dash(cr, dash, 2, 0);
        cairo_new_sub_path(cr);
        cairo_arc(cr, f.x1 + 20, ly, 8, 0, 2 * M_PI);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        text(cr, f.x1 + 32, ly + 4, "tied on the front:", 11, 0.0);
        text(cr, f.x1 + 32, ly + 17, "times not distinguishable", 11, 0.0);
        ly += 34;
    }
    if (c->any_pdiff_fail) {
        cairo_set_line_width(cr, 2);
        cairo_new_sub_path(cr);
        cairo_arc(cr, f.x1 + 20, ly, 4.5, 0, 2 * M_PI);
        cairo_stroke(cr);
        text(cr, f.x1 + 32, ly + 4, "hollow: fails PerceptualDiff", 11, 0.0);
        ly += 20;
    }
    if (c->any_noisy) {
        double dot[] = {1.5, 2.5};
        cairo_set_source_rgb(cr, 0.85, 0.35, 0.0);
        cairo_set_line_width(cr, 1.5);
        cairo_set_dash(cr, dot, 2, 0);
        cairo_new_sub_path(cr);
        cairo_arc(cr, f.x1 + 20, ly, 9, 0, 2 * M_PI);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        text(cr, f.x1 + 32, ly + 4, "dotted: a noisy run", 11, 0.0);
        text(cr, f.x1 + 32, ly + 17, "(others took CPU)", 11, 0.0);
        ly += 34;
    }
    if (c->labels_left_out) {
        snprintf(buf, sizeof(buf), "%d label%s numbered:", c->labels_left_out,
                 c->labels_left_out > 1 ? "s" : "");
        text(cr, f.x1 + 12, ly + 4, buf, 11, 0.0);
        text(cr, f.x1 + 12, ly + 18, "the key is under the chart", 11, 0.0);
    }
}

/* Under the plot: the partial sweep, the key of numbered labels, the
 * points not drawn; the canvas is made tall enough for them. */
static void draw_footer(cairo_t *cr, const struct chart *c)
{
    double y = HEIGHT + 4;
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    for (int i = 0; i < c->nfooter; i++, y += FOOTER_LINE) {
        bool warn = !strncmp(c->footer[i], "Not drawn", 9) || !strncmp(c->footer[i], "PARTIAL", 7);
        if (warn)
            cairo_set_source_rgb(cr, 0.7, 0.0, 0.0);
        else
            cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
        text(cr, LEFT - 60, y, c->footer[i], 11, 0.0);
    }
    if (c->footer_left_out) {
        char buf[96];
        snprintf(buf, sizeof(buf), "... and %d more lines: see the report's table",
                 c->footer_left_out);
        text(cr, LEFT - 60, y, buf, 11, 0.0);
    }
}

static int footer_height(const struct chart *c)
{
    int lines = c->nfooter + (c->footer_left_out > 0);
    return lines ? (int)(lines * FOOTER_LINE + 10) : 0;
}

/* ---- output ---- */

struct sink {
    char *data;
    size_t len, cap;
};

static cairo_status_t collect(void *closure, const unsigned char *data, unsigned int length)
{
    struct sink *s = closure;
    if (s->len + length + 1 > s->cap) {
        size_t cap = (s->len + length + 1) * 2;
        char *grown = realloc(s->data, cap);
        if (!grown)
            return CAIRO_STATUS_NO_MEMORY;
        s->data = grown;
        s->cap = cap;
    }
    memcpy(s->data + s->len, data, length);
    s->len += length;
    return CAIRO_STATUS_SUCCESS;
}

static json_t *layout_json(const struct chart *c)
{
    json_t *pts = json_array(), *fronts = json_array(), *workloads = json_array();
    for (int i = 0; i < c->n; i++) {
        const struct point *p = &c->pts[i];
        json_t *o = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:b, s:s, s:s, s:i, s:b, s:b}", "x",
                              p->x, "y", p->y, "x_lo", p->x_lo, "x_hi", p->x_hi, "y_lo", p->y_lo,
                              "y_hi", p->y_hi, "lo_clamped", p->lo_clamped, "label", p->label,
                              "series", c->series[p->series], RK_WORKLOAD, p->workload, "pareto",
                              p->pareto, "reference", p->reference);
        json_object_set_new(o, "label_box", p->placed ? json_pack("[f, f, f, f]", p->lx, p->ly,
                                                                  p->lw, p->lh)
                                                      : json_null());
        json_object_set_new(o, "tag", p->tag ? json_integer(p->tag) : json_null());
        json_object_set_new(o, "tied", json_boolean(p->tied));
        json_object_set_new(o, "noisy", json_boolean(p->noisy));
        if (p->judged)
            json_object_set_new(o, "pdiff_pass", json_boolean(p->pdiff_pass));
        json_array_append_new(pts, o);
    }
    for (int w = 0; w < c->nworkloads; w++) {
        json_array_append_new(workloads, json_string(c->workloads[w]));
        json_t *members = json_array();
        for (int i = 0; i < c->n; i++)
            if (c->pts[i].pareto && c->pts[i].workload == w)
                json_array_append_new(members, json_integer(i));
        json_array_append_new(fronts, members);
    }
    json_t *levels = json_array();
    for (int i = 0; i < c->nlevels; i++)
        json_array_append_new(levels, json_pack("{s:s, s:f, s:f, s:f}", "label", c->levels[i].label,
                                                "y", c->levels[i].y, "lo", c->levels[i].lo, "hi",
                                                c->levels[i].hi));
    json_t *footer = json_array();
    for (int i = 0; i < c->nfooter; i++)
        json_array_append_new(footer, json_string(c->footer[i]));
    json_t *out = json_pack("{s:s, s:s, s:s, s:s, s:s, s:b, s:b, s:o, s:o, s:o, s:o, s:i, s:o, "
                            "s:s, s:[f, f]}", "chart", c->name, "title", c->title,
                            "subtitle", c->subtitle, "xlabel", c->xlabel, "ylabel", c->ylabel,
                            "x_log", c->ax.log, "y_log", c->ay.log, "points", pts, "workloads",
                            workloads, "fronts", fronts, "levels", levels, "labels_left_out",
                            c->labels_left_out, "footer", footer, "partial", c->partial,
                            "y_range", from_axis(&c->ay, c->ay.lo), from_axis(&c->ay, c->ay.hi));
    json_object_set_new(out, "y_scale", json_string(c->ay.loss ? "one_minus_log" : c->ay.log ? "log" : "linear"));
    json_object_set_new(out, "jnd", c->has_jnd ? json_real(c->jnd_y) : json_null());
    return out;
}

/* The layout as JSON inside <metadata>, before the closing </svg>. */
static bool add_metadata(struct sink *s, const struct chart *c)
{
    json_t *layout = layout_json(c);
    char *text = json_dumps(layout, JSON_COMPACT);
    json_decref(layout);
    if (!text)
        return false;
    size_t esc = 0;
    for (const char *p = text; *p; p++)
        esc += *p == '<' || *p == '>' ? 3 : *p == '&' ? 4 : 0;
    static const char open[] = "<metadata id=\"shadebench-chart\">", close[] = "</metadata>\n";
    size_t add = strlen(open) + strlen(text) + esc + strlen(close);
    char *end = NULL;
    for (size_t i = s->len; i >= 6 && !end; i--)
        if (!strncmp(s->data + i - 6, "</svg>", 6))
            end = s->data + i - 6;
    char *grown = end ? realloc(s->data, s->len + add + 1) : NULL;
    if (!grown) {
        free(text);
        return false;
    }
    end = grown + (end - s->data);
    s->data = grown;
    size_t tail = (size_t)(s->data + s->len - end);
    memmove(end + add, end, tail);
    char *w = end;
    memcpy(w, open, strlen(open));
    w += strlen(open);
    for (const char *p = text; *p; p++) {
        const char *rep = *p == '<' ? "&lt;" : *p == '>' ? "&gt;" : *p == '&' ? "&amp;" : NULL;
        if (rep) {
            memcpy(w, rep, strlen(rep));
            w += strlen(rep);
        } else {
            *w++ = *p;
        }
    }
    memcpy(w, close, strlen(close));
    s->len += add;
    s->data[s->len] = '\0';
    free(text);
    return true;
}

/* Axes from the points (and levels). The log decision looks at the
 * positive values only: an interval cut at zero runs to the axis' end on a
 * log axis (drawn with the arrow head that marks the cut). */
static void fit_axes(struct chart *c)
{
    double xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;
    double xpos = INFINITY, ypos = INFINITY;
    for (int i = 0; i < c->n; i++) {
        const struct point *p = &c->pts[i];
        double ylo = c->boxes ? p->box[0] : fmin(p->y, p->y_lo);
        double yhi = c->boxes ? p->box[5] : fmax(p->y, p->y_hi);
        xl = fmin(xl, fmin(p->x, p->x_lo));
        xh = fmax(xh, fmax(p->x, p->x_hi));
        yl = fmin(yl, ylo);
        yh = fmax(yh, yhi);
        xpos = fmin(xpos, p->x > 0 ? p->x : INFINITY);
        xpos = fmin(xpos, p->x_lo > 0 ? p->x_lo : INFINITY);
        ypos = fmin(ypos, p->y > 0 ? p->y : INFINITY);
        ypos = fmin(ypos, ylo > 0 ? ylo : INFINITY);
    }
    for (int i = 0; i < c->nlevels; i++) {
        yl = fmin(yl, fmin(c->levels[i].y, c->levels[i].lo));
        yh = fmax(yh, fmax(c->levels[i].y, c->levels[i].hi));
        ypos = fmin(ypos, c->levels[i].y > 0 ? c->levels[i].y : INFINITY);
    }
    if (c->n == 0 && c->nlevels == 0)
        xl = yl = xpos = ypos = 0, xh = yh = 1;
    if (c->n == 0)
        xl = xpos = 0, xh = 1;
    bool x_log_ok = (c->x_log_ok && xpos > 0 && xh / xpos > 10.0) ||
                    (c->x_log_param && xl > 0 && xh / xl > 10.0);
    bool y_log_ok = !c->x_log_ok && strcmp(c->name, "speed_accuracy") != 0 && ypos > 0 &&
                    yh / ypos > 10.0;
    /* Times never go below zero; a swept parameter or SSIM may. */
    bool sa = strcmp(c->name, "speed_accuracy") == 0;
    c->ax = c->categorical_x ? (struct axis){-0.5, c->ncategories - 0.5, false, false, 0}
                             : make_axis(x_log_ok ? xpos : xl, xh, x_log_ok, sa);
    c->ay = make_axis(y_log_ok ? ypos : yl, yh, y_log_ok, !sa);
    if (c->quality_y && c->flip) {
        /* FLIP from 0 to the worst, or to 0.01 when every score is better. */
        double lo = 0.0, hi = fmax(c->n ? yh : 0.0, 0.01);
        double pad = (hi - lo) * 0.06;
        c->ay = (struct axis){lo - pad, hi + pad, false, false, 0};
    } else if (c->quality_y) {
        /* SSIM on -log10(1 - SSIM): from the worst score (0.99 at least) to
         * exact, a decade above the best inexact score, so that 0.99998
         * and 0.99997 are apart and neither is drawn as exact. */
        double worst = 1.0, best = 1.0;
        for (int i = 0; i < c->n; i++) {
            double loss = 1.0 - c->pts[i].y;
            if (loss > 0) {
                worst = fmin(worst, c->pts[i].y);
                best = best >= 1.0 ? c->pts[i].y : fmax(best, c->pts[i].y);
            }
        }
        double floor_loss = best < 1.0 ? (1.0 - best) / 10.0 : 1e-6;
        double lo = -log10(fmax(1.0 - fmin(worst, 0.99), floor_loss * 10.0));
        double hi = -log10(floor_loss);
        double pad = (hi - lo) * 0.06;
        c->ay = (struct axis){lo - pad, hi + pad, false, true, floor_loss};
    }
}

/* Before drawing, on a scratch surface: where the labels go and which
 * get numbers, so that the key under the chart, and so its height, are
 * known when the real surface is made. */
static void layout(struct chart *c)
{
    if (c->boxes || c->no_markers)
        return;
    cairo_surface_t *scratch = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, 1, 1);
    cairo_t *cr = cairo_create(scratch);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    double angle;
    struct frame f = frame_of(cr, c, &angle);
    place_labels(cr, c, &f);
    cairo_destroy(cr);
    cairo_surface_destroy(scratch);
    bool first = true;
    for (int i = 0; i < c->n; i++) {
        const struct point *p = &c->pts[i];
        if (!p->tag)
            continue;
        char where[48];
        if (c->boxes || c->categorical_x)
            snprintf(where, sizeof(where), "%.4g ms", p->y);
        else if (c->quality_y)
            snprintf(where, sizeof(where), "%.4g ms, %s %.6g", p->x, c->flip ? "FLIP" : "SSIM", p->y);
        else
            snprintf(where, sizeof(where), "x %.4g, %.4g ms", p->x, p->y);
        add_footer(c, "%s%d: %.20s%s%.80s (%s)", first ? "Key: " : "     ", p->tag,
                   c->series[p->series], p->label[0] ? ", " : "", p->label, where);
        first = false;
    }
}

static char *render(struct chart *c, enum chart_format format, size_t *len)
{
    fit_axes(c);
    layout(c);
    int height = HEIGHT + footer_height(c);
    struct sink sink = {0};
    cairo_surface_t *surface =
        format == CHART_SVG ? cairo_svg_surface_create_for_stream(collect, &sink, WIDTH, height)
                            : cairo_image_surface_create(CAIRO_FORMAT_ARGB32, WIDTH, height);
    cairo_t *cr = cairo_create(surface);
    draw(cr, c);
    draw_footer(cr, c);
    cairo_destroy(cr);
    if (format == CHART_PNG)
        cairo_surface_write_to_png_stream(surface, collect, &sink);
    cairo_surface_finish(surface);
    bool ok = cairo_surface_status(surface) == CAIRO_STATUS_SUCCESS && sink.data;
    cairo_surface_destroy(surface);
    if (ok && format == CHART_SVG)
        ok = add_metadata(&sink, c);
    if (!ok) {
        free(sink.data);
        return NULL;
    }
    *len = sink.len;
    return sink.data;
}

static int series_of(struct chart *c, const char *name)
{
    for (int i = 0; i < c->nseries; i++)
        if (strcmp(c->series[i], name) == 0)
            return i;
    if (c->nseries == MAX_SERIES)
        return MAX_SERIES - 1;
    snprintf(c->series[c->nseries], sizeof(c->series[0]), "%s", name);
    return c->nseries++;
}

/* "async_distance=5, lights=8" without the technique (it is the series). */
static void values_label(const json_t *values, char *out, size_t cap)
{
    out[0] = '\0';
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)values, key, v) {
        if (strcmp(key, "technique") == 0)
            continue;
        char *t = json_dumps(v, JSON_ENCODE_ANY | SV_DUMP_REALS);
        size_t used = strlen(out);
        const char *short_key = strrchr(key, '.') ? strrchr(key, '.') + 1 : key;
        snprintf(out + used, cap - used, "%s%s=%s", used ? ", " : "", short_key, t ? t : "?");
        free(t);
    }
}

static double num(const json_t *v, double fallback)
{
    return json_is_number(v) ? json_number_value(v) : fallback;
}

/* The quality axis and PerceptualDiff's line on it: y from the worst score
 * (or 0.99 when every score is better, so that differences of 1e-5 are not
 * drawn as a cliff) to exact; the line where PerceptualDiff's verdicts
 * separate, when they do. */
static void quality_axis(struct chart *c)
{
    double worst_pass = c->flip ? -INFINITY : INFINITY, best_fail = c->flip ? INFINITY : -INFINITY;
    int pass = 0, fail = 0;
    for (int i = 0; i < c->n; i++) {
        const struct point *p = &c->pts[i];
        if (!p->judged)
            continue;
        if (p->pdiff_pass) {
            pass++;
            worst_pass = c->flip ? fmax(worst_pass, p->y) : fmin(worst_pass, p->y);
        } else {
            fail++;
            best_fail = c->flip ? fmin(best_fail, p->y) : fmax(best_fail, p->y);
        }
    }
    c->any_pdiff_fail = fail > 0;
    bool separate = pass && fail && (c->flip ? worst_pass < best_fail : worst_pass > best_fail);
    if (separate) {
        c->has_jnd = true;
        c->jnd_y = worst_pass;
        snprintf(c->pdiff_note, sizeof(c->pdiff_note), "PerceptualDiff passes from %s %.6g on",
                 c->flip ? "FLIP" : "SSIM", worst_pass);
    } else if (pass && fail) {
        snprintf(c->pdiff_note, sizeof(c->pdiff_note), "PerceptualDiff's verdicts do not follow "
                 "%s here: hollow points fail it", c->flip ? "FLIP" : "SSIM");
    } else if (pass || fail) {
        snprintf(c->pdiff_note, sizeof(c->pdiff_note), "every judged point %s PerceptualDiff",
                 pass ? "passes" : "fails");
    }
}

/* What could not be drawn, and a partial sweep, under the chart. */
static void missing_footer(struct chart *c, const struct sweep_view *v, bool sa, bool flip)
{
    if (v->partial) {
        snprintf(c->partial, sizeof(c->partial), "partial sweep: %s, %lld of %lld points ran",
                 v->status, (long long)(v->n - v->not_done), (long long)v->points_total);
        add_footer(c, "PARTIAL sweep (%s): %d of %lld planned points finished; the chart shows "
                   "only those", v->status, v->n - v->not_done, (long long)v->points_total);
    }
    for (int i = 0; i < v->n; i++) {
        const struct sv_point *p = &v->pts[i];
        bool no_quality = sa && p->timed && !(flip ? p->has_flip : p->has_ssim);
        if (p->timed && !no_quality)
            continue;
        add_footer(c, "Not drawn: %.20s%s%.80s (%s)", p->technique, p->label[0] ? ", " : "",
                   p->label, strcmp(p->status, "done") != 0 ? p->status
                             : no_quality ? "not judged: no reference" : "no time");
    }
    if (v->not_run)
        add_footer(c, "Not drawn: %d planned point%s not run", v->not_run,
                   v->not_run == 1 ? "" : "s");
}

char *charts_sweep(const json_t *sweep, const char *name, enum chart_format format,
                   const struct chart_options *o, size_t *len, char *err, size_t errlen)
{
    bool sa = !strcmp(name, "speed_accuracy"), tvp = !strcmp(name, "time_vs_param"),
         dist = !strcmp(name, "distribution");
    if (!sa && !tvp && !dist) {
        snprintf(err, errlen, "no chart named %s (speed_accuracy, time_vs_param, distribution)", name);
        return NULL;
    }
    const char *series = o->series ? o->series : charts_default_series(o->device);
    /* The same reading of the table as the verdict's (sweep_verdict.h):
     * workloads, intervals, the front. */
    struct sweep_view v;
    struct chart c;
    memset(&c, 0, sizeof(c));
    c.name = name;
    if (!sweep_view_init(&v, sweep, series) ||
        !(c.pts = calloc((size_t)v.n + 1, sizeof(*c.pts)))) {
        sweep_view_finish(&v);
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    if (sa)
        sweep_view_front(&v, o->flip);
    c.nworkloads = v.nworkloads;
    for (int w = 0; w < v.nworkloads; w++)
        snprintf(c.workloads[w], sizeof(c.workloads[0]), "%s", v.workloads[w]);
    /* The x axis: the first numeric swept parameter, as the verdict's
     * crossovers use (a sweep over technique and light count charts time
     * against the light count, a line per technique); with none, the first
     * swept parameter other than a timed reference point's technique. */
    const char *param = v.param;
    for (int i = 0; i < v.n && !param; i++) {
        const json_t *values = json_object_get(v.pts[i].row, "values");
        const char *key;
        json_t *val;
        json_object_foreach((json_t *)values, key, val) {
            if (!param && !(strcmp(key, "technique") == 0 && json_object_size(values) == 1))
                param = key;
        }
    }
    c.x_log_ok = sa;
    c.x_log_param = tvp;
    c.quality_y = sa;
    c.flip = o->flip;
    missing_footer(&c, &v, sa, o->flip);
    bool any_runs = false;
    for (int k = 0; k < v.n; k++) {
        const struct sv_point *sp = &v.pts[k];
        if (!sp->timed)
            continue; /* a failed or cancelled point: named under the chart */
        const json_t *t = json_object_get(sp->row, series);
        const char *tech = sp->technique;
        const json_t *values = json_object_get(sp->row, "values");
        struct point *p = &c.pts[c.n];
        p->reference = sp->reference;
        p->noisy = sp->noisy;
        p->other_share = sp->other_share;
        c.any_noisy = c.any_noisy || sp->noisy;
        char sname[96], others[64] = "";
        if (tvp) {
            /* A line per technique and per value of the other swept
             * parameters: lines never join points of two workloads. */
            json_t *rest = json_deep_copy(values);
            if (param)
                json_object_del(rest, param);
            values_label(rest, others, sizeof(others));
            json_decref(rest);
        }
        snprintf(sname, sizeof(sname), "%.20s%s%s%.24s", tech, p->reference ? " (reference)" : "",
                 others[0] ? " " : "", others);
        p->workload = sp->workload;
        double median = sp->ms, lo = sp->lo, hi = sp->hi;
        p->lo_clamped = sp->lo_clamped;
        if (!(tvp && p->reference && !(param && json_object_get(values, param))))
            p->series = series_of(&c, sname);
        if (sa) {
            if (!(o->flip ? sp->has_flip : sp->has_ssim))
                continue; /* not judged: named under the chart */
            p->x = median, p->x_lo = lo, p->x_hi = hi;
            p->y = p->y_lo = p->y_hi = o->flip ? sp->flip : sp->ssim;
            p->pareto = sp->pareto;
            p->tied = sp->tied;
            c.any_tied = c.any_tied || sp->tied;
            p->judged = sp->judged;
            p->pdiff_pass = sp->pdiff_pass;
            snprintf(p->label, sizeof(p->label), "%.63s", sp->label);
            if (p->reference) {
                char wl[64];
                snprintf(wl, sizeof(wl), "%s", p->label);
                snprintf(p->label, sizeof(p->label), "%.20s%s%.40s", tech, wl[0] ? ", " : "", wl);
            }
        } else if (tvp) {
            json_t *pv = param ? json_object_get(values, param) : NULL;
            if (!pv && p->reference) {
                /* Timed on the same workload but not swept: a level. */
                if (c.nlevels < MAX_LEVELS) {
                    struct level *l = &c.levels[c.nlevels++];
                    l->y = median, l->lo = lo, l->hi = hi;
                    snprintf(l->label, sizeof(l->label), "%.20s (reference)%s%.30s", tech,
                             sp->label[0] ? " " : "", sp->label);
                }
                continue;
            }
            if (json_is_number(pv)) {
                p->x = p->x_lo = p->x_hi = json_number_value(pv);
            } else {
                c.categorical_x = true;
                char *text = json_dumps(pv, JSON_ENCODE_ANY | SV_DUMP_REALS);
                int q = 0;
                while (q < c.ncategories && strcmp(c.categories[q], text ? text : "?") != 0)
                    q++;
                if (q == c.ncategories && c.ncategories < 64)
                    snprintf(c.categories[c.ncategories++], sizeof(c.categories[0]), "%s", text ? text : "?");
                free(text);
                p->x = p->x_lo = p->x_hi = q;
            }
            p->y = median, p->y_lo = lo, p->y_hi = hi;
        } else {
            c.boxes = c.categorical_x = true;
            static const char *const keys[6] = {RK_MIN, RK_P5, RK_MEDIAN, RK_P95, RK_P99, RK_MAX};
            for (int q = 0; q < 6; q++)
                p->box[q] = num(json_object_get(t, keys[q]), median);
            const char *over = json_string_value(json_object_get(t, "over"));
            p->runs_median = over && !strcmp(over, "runs");
            any_runs = any_runs || p->runs_median;
            if (c.ncategories < 64) {
                snprintf(c.categories[c.ncategories], sizeof(c.categories[0]), "%.48s %.60s",
                         sname, sp->label);
                p->x = c.ncategories++;
            }
            p->y = median;
        }
        c.n++;
    }
    char note[200];
    series_note(series, o->device, !o->series, note, sizeof(note));
    snprintf(c.subtitle, sizeof(c.subtitle), "%s", note);
    if (sa) {
        quality_axis(&c);
        snprintf(c.title, sizeof(c.title), "Speed against accuracy");
        snprintf(c.xlabel, sizeof(c.xlabel), "median %s, ms (95%% interval)", series);
        snprintf(c.ylabel, sizeof(c.ylabel), o->flip ? "worst mean FLIP (lower is better)"
                                                     : "worst SSIM (higher is better)");
        if (c.nworkloads > 1) {
            size_t used = strlen(c.subtitle);
            snprintf(c.subtitle + used, sizeof(c.subtitle) - used, "; a front per workload (%d)",
                     c.nworkloads);
        }
        if (c.pdiff_note[0])
            add_footer(&c, "%s.", c.pdiff_note);
        add_footer(&c, "Pareto front: nothing of the same workload is measurably faster (its "
                   "95%% interval separate) and at least as accurate, or as fast and more "
                   "accurate.");
    } else if (tvp) {
        c.lines = !c.categorical_x;
        snprintf(c.title, sizeof(c.title), "Frame time against %s", param ? param : "the parameter");
        snprintf(c.xlabel, sizeof(c.xlabel), "%s", param ? param : "");
        snprintf(c.ylabel, sizeof(c.ylabel), "median %s, ms (95%% interval)", series);
    } else {
        snprintf(c.title, sizeof(c.title), "Frame-time distribution per point");
        snprintf(c.xlabel, sizeof(c.xlabel), any_runs
                 ? "box p5-p95 of the first run, line median, diamond median over runs, tick p99"
                 : "box p5-p95, line median, tick p99, whiskers min-max");
        snprintf(c.ylabel, sizeof(c.ylabel), "%s, ms", series);
    }
    if (c.partial[0]) {
        size_t used = strlen(c.title);
        snprintf(c.title + used, sizeof(c.title) - used, " (%s)", c.partial);
    }
    char *out = render(&c, format, len);
    free(c.pts);
    sweep_view_finish(&v);
    if (!out)
        snprintf(err, errlen, "cairo could not draw the chart");
    return out;
}

char *charts_job(const json_t *job, const char *name, enum chart_format format,
                 const struct chart_options *o, size_t *len, char *err, size_t errlen)
{
    if (strcmp(name, "distribution") != 0) {
        snprintf(err, errlen, "no chart named %s for a job (distribution)", name);
        return NULL;
    }
    json_t *result = json_object_get(job, RK_RESULT);
    /* One box per series. */
    struct chart c;
    memset(&c, 0, sizeof(c));
    c.name = name;
    struct point pts[3];
    memset(pts, 0, sizeof(pts));
    c.pts = pts;
    c.boxes = c.categorical_x = true;
    static const char *const all[3] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    static const char *const keys[6] = {RK_MIN, RK_P5, RK_MEDIAN, RK_P95, RK_P99, RK_MAX};
    for (int s = 0; s < 3; s++) {
        if (o->series && strcmp(o->series, all[s]) != 0)
            continue;
        json_t *st = json_object_get(result, all[s]);
        if (!st)
            continue;
        struct point *p = &pts[c.n++];
        for (int k = 0; k < 6; k++)
            p->box[k] = num(json_object_get(st, keys[k]), 0);
        p->y = p->box[2];
        p->x = c.ncategories;
        p->series = series_of(&c, all[s]);
        snprintf(c.categories[c.ncategories++], sizeof(c.categories[0]), "%s", all[s]);
    }
    const json_t *device = json_object_get(result, "device");
    snprintf(c.title, sizeof(c.title), "Frame times of job %s (%s)",
             json_string_value(json_object_get(job, "id")) ? json_string_value(json_object_get(job, "id")) : "",
             json_string_value(json_object_get(job, "technique")) ? json_string_value(json_object_get(job, "technique")) : "");
    if (software_device(device))
        snprintf(c.subtitle, sizeof(c.subtitle), "on llvmpipe gpu_ms covers rasterization only: "
                 "frame_ms compares techniques");
    snprintf(c.xlabel, sizeof(c.xlabel), "box p5-p95, line median, tick p99, whiskers min-max");
    snprintf(c.ylabel, sizeof(c.ylabel), "milliseconds");
    char *out = render(&c, format, len);
    if (!out)
        snprintf(err, errlen, "cairo could not draw the chart");
    return out;
}

char *charts_job_timeline(const json_t *job, const json_t *samples, enum chart_format format,
                          const struct chart_options *o, size_t *len, char *err, size_t errlen)
{
    const json_t *device = json_object_get(json_object_get(job, RK_RESULT), "device");
    const char *series = o->series ? o->series : charts_default_series(device);
    json_t *main = json_object_get(samples, series);
    size_t n = json_array_size(main);
    if (!n) {
        snprintf(err, errlen, "no per-frame %s samples", series);
        return NULL;
    }
    struct chart c;
    memset(&c, 0, sizeof(c));
    c.name = "timeline";
    c.pts = calloc(n, sizeof(*c.pts));
    if (!c.pts) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    c.lines = c.no_markers = true;
    int s = series_of(&c, series);
    for (size_t i = 0; i < n; i++) {
        struct point *p = &c.pts[c.n++];
        p->x = p->x_lo = p->x_hi = (double)(i + 1);
        p->y = p->y_lo = p->y_hi = num(json_array_get(main, i), 0);
        p->series = s;
    }
    /* The median as a level, so that drift over the run stands out. */
    json_t *st = json_object_get(json_object_get(job, RK_RESULT), series);
    if (json_is_number(json_object_get(st, RK_MEDIAN))) {
        struct level *l = &c.levels[c.nlevels++];
        l->y = l->lo = l->hi = json_number_value(json_object_get(st, RK_MEDIAN));
        snprintf(l->label, sizeof(l->label), "median %.3f ms", l->y);
    }
    snprintf(c.title, sizeof(c.title), "%s over the run of job %s", series,
             json_string_value(json_object_get(job, "id")) ? json_string_value(json_object_get(job, "id")) : "");
    series_note(series, device, !o->series, c.subtitle, sizeof(c.subtitle));
    snprintf(c.xlabel, sizeof(c.xlabel), "timed frame");
    snprintf(c.ylabel, sizeof(c.ylabel), "%s, ms", series);
    char *out = render(&c, format, len);
    free(c.pts);
    if (!out)
        snprintf(err, errlen, "cairo could not draw the chart");
    return out;
}
