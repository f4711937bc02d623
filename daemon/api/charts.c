#define _DEFAULT_SOURCE /* M_PI */
#define _POSIX_C_SOURCE 200809L
#include "daemon/api/charts.h"

#include <cairo-svg.h>
#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { WIDTH = 900, HEIGHT = 560, MAX_SERIES = 8 };
static const double LEFT = 90, RIGHT = 200, TOP = 50, BOTTOM = 70;

/* Colour-blind-safe (Okabe-Ito). */
static const double PALETTE[MAX_SERIES][3] = {
    {0.00, 0.45, 0.70}, {0.90, 0.62, 0.00}, {0.00, 0.62, 0.45}, {0.80, 0.47, 0.65},
    {0.34, 0.71, 0.91}, {0.84, 0.37, 0.00}, {0.94, 0.89, 0.26}, {0.35, 0.35, 0.35},
};

struct point {
    double x, y, x_lo, x_hi, y_lo, y_hi;
    char label[64];
    int series;
    bool pareto;
    /* distribution charts */
    double box[6]; /* min, p5, median, p95, p99, max */
};

struct chart {
    char title[160], xlabel[96], ylabel[96];
    char series[MAX_SERIES][48];
    int nseries;
    struct point *pts;
    int n;
    bool lines, boxes, categorical_x;
    char categories[64][112];
    int ncategories;
};

struct range {
    double lo, hi;
};

static struct range nice_range(double lo, double hi)
{
    if (!(hi > lo)) {
        double pad = fabs(lo) > 0 ? fabs(lo) * 0.1 : 1.0;
        lo -= pad;
        hi += pad;
    }
    double pad = (hi - lo) * 0.08;
    return (struct range){lo - pad, hi + pad};
}

static double tick_step(struct range r)
{
    double raw = (r.hi - r.lo) / 6.0, mag = pow(10.0, floor(log10(raw))), f = raw / mag;
    return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}

static double map(double v, struct range r, double a, double b)
{
    return a + (v - r.lo) / (r.hi - r.lo) * (b - a);
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
    struct range rx, ry;
    double x0, x1, y0, y1;
};

/* Joins the points of one series (or, with series < 0, the Pareto points)
 * in order of x. */
static void polyline_by_x(cairo_t *cr, const struct chart *c, int series, const struct frame *f)
{
    bool first = true;
    double last_x = -INFINITY;
    for (;;) {
        int best = -1;
        for (int i = 0; i < c->n; i++) {
            const struct point *p = &c->pts[i];
            bool member = series < 0 ? p->pareto : p->series == series;
            if (member && p->x > last_x && (best < 0 || p->x < c->pts[best].x))
                best = i;
        }
        if (best < 0)
            break;
        double px = map(c->pts[best].x, f->rx, f->x0, f->x1), py = map(c->pts[best].y, f->ry, f->y0, f->y1);
        if (first)
            cairo_move_to(cr, px, py);
        else
            cairo_line_to(cr, px, py);
        first = false;
        last_x = c->pts[best].x;
    }
    cairo_stroke(cr);
}

static void draw(cairo_t *cr, const struct chart *c)
{
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    double x0 = LEFT, x1 = WIDTH - RIGHT, y0 = HEIGHT - BOTTOM, y1 = TOP;

    struct range rx = {0, 1}, ry = {0, 1};
    if (c->n > 0) {
        double xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;
        for (int i = 0; i < c->n; i++) {
            const struct point *p = &c->pts[i];
            xl = fmin(xl, fmin(p->x, p->x_lo));
            xh = fmax(xh, fmax(p->x, p->x_hi));
            double lo = c->boxes ? p->box[0] : fmin(p->y, p->y_lo);
            double hi = c->boxes ? p->box[5] : fmax(p->y, p->y_hi);
            yl = fmin(yl, lo);
            yh = fmax(yh, hi);
        }
        rx = c->categorical_x ? (struct range){-0.5, c->ncategories - 0.5} : nice_range(xl, xh);
        ry = nice_range(yl, yh);
    }

    /* Grid, ticks and axis labels. */
    cairo_set_line_width(cr, 1);
    cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
    char buf[64];
    double sy = tick_step(ry);
    for (double v = ceil(ry.lo / sy) * sy; v <= ry.hi; v += sy) {
        double py = map(v, ry, y0, y1);
        cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
        cairo_move_to(cr, x0, py);
        cairo_line_to(cr, x1, py);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
        snprintf(buf, sizeof(buf), "%.6g", fabs(v) < sy * 1e-6 ? 0.0 : v);
        text(cr, x0 - 8, py + 4, buf, 12, 1.0);
    }
    if (c->categorical_x) {
        /* Many categories: slanted labels, so that they never overlap. */
        bool slant = c->ncategories > 4;
        for (int i = 0; i < c->ncategories; i++) {
            cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
            if (!slant) {
                text(cr, map(i, rx, x0, x1), y0 + 18, c->categories[i], 11, 0.5);
                continue;
            }
            cairo_save(cr);
            cairo_translate(cr, map(i, rx, x0, x1), y0 + 12);
            cairo_rotate(cr, -0.35);
            text(cr, 0, 0, c->categories[i], 10, 1.0);
            cairo_restore(cr);
        }
    } else {
        double sx = tick_step(rx);
        for (double v = ceil(rx.lo / sx) * sx; v <= rx.hi; v += sx) {
            double px = map(v, rx, x0, x1);
            cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
            cairo_move_to(cr, px, y0);
            cairo_line_to(cr, px, y1);
            cairo_stroke(cr);
            cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
            snprintf(buf, sizeof(buf), "%.6g", fabs(v) < sx * 1e-6 ? 0.0 : v);
            text(cr, px, y0 + 18, buf, 12, 0.5);
        }
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    cairo_rectangle(cr, x0, y1, x1 - x0, y0 - y1);
    cairo_stroke(cr);
    text(cr, (x0 + x1) / 2, HEIGHT - 22, c->xlabel, 14, 0.5);
    cairo_save(cr);
    cairo_translate(cr, 24, (y0 + y1) / 2);
    cairo_rotate(cr, -M_PI / 2);
    text(cr, 0, 0, c->ylabel, 14, 0.5);
    cairo_restore(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    text(cr, x0, 30, c->title, 16, 0.0);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

    if (c->n == 0) {
        text(cr, (x0 + x1) / 2, (y0 + y1) / 2, "no finished points yet", 14, 0.5);
        return;
    }

    const struct frame frame = {rx, ry, x0, x1, y0, y1};
    /* The Pareto front first, under the points. */
    int npareto = 0;
    for (int i = 0; i < c->n; i++)
        npareto += c->pts[i].pareto;
    if (npareto > 1) {
        cairo_set_source_rgba(cr, 0.2, 0.2, 0.2, 0.6);
        cairo_set_line_width(cr, 1.5);
        double dash[] = {6, 4};
        cairo_set_dash(cr, dash, 2, 0);
        polyline_by_x(cr, c, -1, &frame);
        cairo_set_dash(cr, NULL, 0, 0);
    }

    for (int s = 0; s < c->nseries; s++) {
        const double *col = PALETTE[s % MAX_SERIES];
        if (c->lines) {
            cairo_set_source_rgb(cr, col[0], col[1], col[2]);
            cairo_set_line_width(cr, 2);
            polyline_by_x(cr, c, s, &frame);
        }
        for (int i = 0; i < c->n; i++) {
            const struct point *p = &c->pts[i];
            if (p->series != s)
                continue;
            double px = map(p->x, rx, x0, x1), py = map(p->y, ry, y0, y1);
            cairo_set_source_rgb(cr, col[0], col[1], col[2]);
            cairo_set_line_width(cr, 1.5);
            if (c->boxes) {
                /* Whiskers min-max, box p5-p95, median line, p99 tick. */
                double w = fmin(40.0, (x1 - x0) / (c->ncategories * 2.5));
                double b[6];
                for (int k = 0; k < 6; k++)
                    b[k] = map(p->box[k], ry, y0, y1);
                cairo_move_to(cr, px, b[0]);
                cairo_line_to(cr, px, b[5]);
                cairo_stroke(cr);
                cairo_rectangle(cr, px - w / 2, b[3], w, b[1] - b[3]);
                cairo_set_source_rgba(cr, col[0], col[1], col[2], 0.3);
                cairo_fill_preserve(cr);
                cairo_set_source_rgb(cr, col[0], col[1], col[2]);
                cairo_stroke(cr);
                cairo_set_line_width(cr, 3);
                cairo_move_to(cr, px - w / 2, b[2]);
                cairo_line_to(cr, px + w / 2, b[2]);
                cairo_stroke(cr);
                cairo_set_line_width(cr, 1.5);
                cairo_move_to(cr, px - w / 4, b[4]);
                cairo_line_to(cr, px + w / 4, b[4]);
                cairo_stroke(cr);
                continue;
            }
            /* Error bars from the intervals. */
            if (p->x_hi > p->x_lo) {
                double a = map(p->x_lo, rx, x0, x1), bx = map(p->x_hi, rx, x0, x1);
                cairo_move_to(cr, a, py);
                cairo_line_to(cr, bx, py);
                cairo_move_to(cr, a, py - 4);
                cairo_line_to(cr, a, py + 4);
                cairo_move_to(cr, bx, py - 4);
                cairo_line_to(cr, bx, py + 4);
                cairo_stroke(cr);
            }
            if (p->y_hi > p->y_lo) {
                double a = map(p->y_lo, ry, y0, y1), by = map(p->y_hi, ry, y0, y1);
                cairo_move_to(cr, px, a);
                cairo_line_to(cr, px, by);
                cairo_stroke(cr);
            }
            cairo_new_sub_path(cr);
            cairo_arc(cr, px, py, 4.5, 0, 2 * M_PI);
            cairo_fill(cr);
            if (p->pareto) {
                cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
                cairo_new_sub_path(cr);
            cairo_arc(cr, px, py, 8, 0, 2 * M_PI);
                cairo_stroke(cr);
            }
            if (p->label[0]) {
                cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
                text(cr, px + 9, py - 7, p->label, 11, 0.0);
            }
        }
    }

    /* Legend. */
    double ly = TOP + 10;
    for (int s = 0; s < c->nseries; s++, ly += 22) {
        const double *col = PALETTE[s % MAX_SERIES];
        cairo_set_source_rgb(cr, col[0], col[1], col[2]);
        cairo_new_sub_path(cr);
            cairo_arc(cr, x1 + 20, ly, 5, 0, 2 * M_PI);
        cairo_fill(cr);
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        text(cr, x1 + 32, ly + 4, c->series[s], 12, 0.0);
    }
    if (npareto > 0) {
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        cairo_new_sub_path(cr);
            cairo_arc(cr, x1 + 20, ly, 8, 0, 2 * M_PI);
        cairo_stroke(cr);
        text(cr, x1 + 32, ly + 4, "Pareto front", 12, 0.0);
    }
}

struct sink {
    char *data;
    size_t len, cap;
};

static cairo_status_t collect(void *closure, const unsigned char *data, unsigned int length)
{
    struct sink *s = closure;
    if (s->len + length > s->cap) {
        size_t cap = (s->len + length) * 2;
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

static char *render(const struct chart *c, enum chart_format format, size_t *len)
{
    struct sink sink = {0};
    cairo_surface_t *surface =
        format == CHART_SVG ? cairo_svg_surface_create_for_stream(collect, &sink, WIDTH, HEIGHT)
                            : cairo_image_surface_create(CAIRO_FORMAT_ARGB32, WIDTH, HEIGHT);
    cairo_t *cr = cairo_create(surface);
    draw(cr, c);
    cairo_destroy(cr);
    if (format == CHART_PNG)
        cairo_surface_write_to_png_stream(surface, collect, &sink);
    cairo_surface_finish(surface);
    bool ok = cairo_surface_status(surface) == CAIRO_STATUS_SUCCESS;
    cairo_surface_destroy(surface);
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

/* "async_distance=5, scene.lights=8" without the technique (it is the series). */
static void values_label(const json_t *values, char *out, size_t cap)
{
    out[0] = '\0';
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)values, key, v) {
        if (strcmp(key, "technique") == 0)
            continue;
        char *text = json_dumps(v, JSON_ENCODE_ANY);
        size_t used = strlen(out);
        const char *short_key = strrchr(key, '.') ? strrchr(key, '.') + 1 : key;
        snprintf(out + used, cap - used, "%s%s=%s", used ? ", " : "", short_key, text ? text : "?");
        free(text);
    }
}

static double num(const json_t *v, double fallback)
{
    return json_is_number(v) ? json_number_value(v) : fallback;
}

char *charts_sweep(const json_t *sweep, const char *name, enum chart_format format,
                   const struct chart_options *o, size_t *len, char *err, size_t errlen)
{
    const char *series = o->series ? o->series : "frame_ms";
    json_t *points = json_object_get(sweep, "points");
    struct chart c;
    memset(&c, 0, sizeof(c));
    c.pts = calloc(json_array_size(points) + 1, sizeof(*c.pts));
    if (!c.pts) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    const char *param = NULL;
    json_t *first_values = json_object_get(json_array_get(points, 0), "values");
    const char *key;
    json_t *v;
    json_object_foreach(first_values, key, v) if (!param) param = key;
    size_t i;
    json_t *row;
    json_array_foreach(points, i, row) {
        json_t *t = json_object_get(row, series);
        if (!t || !json_is_number(json_object_get(t, "median")))
            continue; /* a failed or cancelled point */
        struct point *p = &c.pts[c.n];
        const char *tech = json_string_value(json_object_get(row, "technique"));
        p->series = series_of(&c, tech ? tech : "?");
        values_label(json_object_get(row, "values"), p->label, sizeof(p->label));
        double median = json_number_value(json_object_get(t, "median"));
        json_t *ci = json_object_get(t, "ci95");
        double lo = num(json_array_get(ci, 0), median), hi = num(json_array_get(ci, 1), median);
        if (strcmp(name, "speed_accuracy") == 0) {
            json_t *q = json_object_get(row, o->flip ? "worst_flip" : "worst_ssim");
            if (!json_is_number(q))
                continue;
            p->x = median, p->x_lo = lo, p->x_hi = hi;
            p->y = p->y_lo = p->y_hi = json_number_value(q);
        } else if (strcmp(name, "time_vs_param") == 0) {
            json_t *pv = json_object_get(json_object_get(row, "values"), param);
            if (json_is_number(pv)) {
                p->x = p->x_lo = p->x_hi = json_number_value(pv);
            } else {
                c.categorical_x = true;
                char *text = json_dumps(pv, JSON_ENCODE_ANY);
                int k = 0;
                while (k < c.ncategories && strcmp(c.categories[k], text ? text : "?") != 0)
                    k++;
                if (k == c.ncategories && c.ncategories < 64)
                    snprintf(c.categories[c.ncategories++], sizeof(c.categories[0]), "%s", text ? text : "?");
                free(text);
                p->x = p->x_lo = p->x_hi = k;
            }
            p->y = median, p->y_lo = lo, p->y_hi = hi;
            p->label[0] = '\0';
        } else if (strcmp(name, "distribution") == 0) {
            c.boxes = c.categorical_x = true;
            static const char *const keys[6] = {"min", "p5", "median", "p95", "p99", "max"};
            for (int k = 0; k < 6; k++)
                p->box[k] = num(json_object_get(t, keys[k]), median);
            if (c.ncategories < 64) {
                char label[64];
                values_label(json_object_get(row, "values"), label, sizeof(label));
                snprintf(c.categories[c.ncategories], sizeof(c.categories[0]), "%s %s",
                         tech ? tech : "", label);
                p->x = c.ncategories++;
            }
            p->y = median;
            p->label[0] = '\0';
        } else {
            free(c.pts);
            snprintf(err, errlen, "no chart named %s (speed_accuracy, time_vs_param, distribution)", name);
            return NULL;
        }
        c.n++;
    }
    if (strcmp(name, "speed_accuracy") == 0) {
        snprintf(c.title, sizeof(c.title), "Speed against accuracy");
        snprintf(c.xlabel, sizeof(c.xlabel), "median %s (95%% interval)", series);
        snprintf(c.ylabel, sizeof(c.ylabel), o->flip ? "worst mean FLIP (lower is better)"
                                                     : "worst SSIM (higher is better)");
        /* Pareto: nothing both faster and at least as accurate. */
        for (int a = 0; a < c.n; a++) {
            c.pts[a].pareto = true;
            for (int b = 0; b < c.n && c.pts[a].pareto; b++) {
                if (a == b)
                    continue;
                bool better_q = o->flip ? c.pts[b].y <= c.pts[a].y : c.pts[b].y >= c.pts[a].y;
                bool strictly = c.pts[b].x < c.pts[a].x ||
                                (o->flip ? c.pts[b].y < c.pts[a].y : c.pts[b].y > c.pts[a].y);
                if (c.pts[b].x <= c.pts[a].x && better_q && strictly)
                    c.pts[a].pareto = false;
            }
        }
    } else if (strcmp(name, "time_vs_param") == 0) {
        c.lines = !c.categorical_x;
        snprintf(c.title, sizeof(c.title), "Frame time against %s", param ? param : "the parameter");
        snprintf(c.xlabel, sizeof(c.xlabel), "%s", param ? param : "");
        snprintf(c.ylabel, sizeof(c.ylabel), "median %s (95%% interval)", series);
    } else {
        snprintf(c.title, sizeof(c.title), "Frame-time distribution per point");
        snprintf(c.xlabel, sizeof(c.xlabel), "box p5-p95, line median, tick p99, whiskers min-max");
        snprintf(c.ylabel, sizeof(c.ylabel), "%s", series);
    }
    char *out = render(&c, format, len);
    free(c.pts);
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
    json_t *result = json_object_get(job, "result");
    /* One box per series. */
    struct chart c;
    memset(&c, 0, sizeof(c));
    struct point pts[3];
    memset(pts, 0, sizeof(pts));
    c.pts = pts;
    c.boxes = c.categorical_x = true;
    static const char *const all[3] = {"frame_ms", "gpu_ms", "cpu_ms"};
    static const char *const keys[6] = {"min", "p5", "median", "p95", "p99", "max"};
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
    snprintf(c.title, sizeof(c.title), "Frame times of job %s (%s)",
             json_string_value(json_object_get(job, "id")) ? json_string_value(json_object_get(job, "id")) : "",
             json_string_value(json_object_get(job, "technique")) ? json_string_value(json_object_get(job, "technique")) : "");
    snprintf(c.xlabel, sizeof(c.xlabel), "box p5-p95, line median, tick p99, whiskers min-max");
    snprintf(c.ylabel, sizeof(c.ylabel), "milliseconds");
    char *out = render(&c, format, len);
    if (!out)
        snprintf(err, errlen, "cairo could not draw the chart");
    return out;
}
