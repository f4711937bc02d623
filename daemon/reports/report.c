#define _POSIX_C_SOURCE 200809L
#include "daemon/reports/report.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "daemon/reports/charts.h"
#include "daemon/reports/sweep_verdict.h"
#include "daemon/status/interference.h" /* INTERFERENCE_RULE */
#include "common/job_files.h"
#include "common/png_io.h"
#include "common/result_keys.h"
#include "daemon/reports/diff_views.h"
#include "daemon/spec/sweep_spec.h" /* sweep_thesis_size */

/* Points of a sweep that get thumbnails: enough to see how the image
 * changes, few enough that the page stays a reasonable size. */
enum { THUMB_POINTS = 64, THUMB_WIDTH = 240 };
/* A job report's captures and difference views: at their size up to this
 * width; the views' contrast (each error times this, cut at the top). */
enum { VIEW_WIDTH = 960 };
static const float GAIN_ABS = 8, GAIN_SSIM = 8, GAIN_FLIP = 4;

static const char *str(const json_t *o, const char *key);

struct html {
    char *data;
    size_t len, cap;
    bool failed;
};

static void put(struct html *h, const char *s, size_t n)
{
    if (h->failed)
        return;
    if (h->len + n + 1 > h->cap) {
        size_t cap = (h->len + n + 1) * 2;
        char *grown = realloc(h->data, cap);
        if (!grown) {
            h->failed = true;
            return;
        }
        h->data = grown;
        h->cap = cap;
    }
    memcpy(h->data + h->len, s, n);
    h->len += n;
    h->data[h->len] = '\0';
}

static void add(struct html *h, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add(struct html *h, const char *fmt, ...)
{
    char buf[2048];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    if (n > 0)
        put(h, buf, (size_t)n < sizeof(buf) ? (size_t)n : sizeof(buf) - 1);
}

static void escaped(struct html *h, const char *s)
{
    for (; s && *s; s++) {
        switch (*s) {
        case '<': put(h, "&lt;", 4); break;
        case '>': put(h, "&gt;", 4); break;
        case '&': put(h, "&amp;", 5); break;
        case '"': put(h, "&quot;", 6); break;
        default: put(h, s, 1);
        }
    }
}

static void base64(struct html *h, const unsigned char *data, size_t len)
{
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char out[4];
    for (size_t i = 0; i < len; i += 3) {
        unsigned v = (unsigned)data[i] << 16 | (i + 1 < len ? (unsigned)data[i + 1] << 8 : 0) |
                     (i + 2 < len ? data[i + 2] : 0);
        out[0] = t[v >> 18 & 63];
        out[1] = t[v >> 12 & 63];
        out[2] = i + 1 < len ? t[v >> 6 & 63] : '=';
        out[3] = i + 2 < len ? t[v & 63] : '=';
        put(h, out, 4);
    }
}

static void png_img(struct html *h, const unsigned char *png, size_t len, const char *alt,
                    const char *cls)
{
    add(h, "<img class=\"%s\" alt=\"", cls);
    escaped(h, alt);
    put(h, "\" src=\"data:image/png;base64,", 29);
    base64(h, png, len);
    put(h, "\">", 2);
}

/* A thumbnail of a PNG file in the job's directory, or a note if missing;
 * an SSIM or FLIP map with its contrast stretched by gain (0: as it is). */
static void stretched_thumbnail(struct html *h, const char *dir, enum job_image image, int frame,
                                float gain, const char *caption)
{
    char path[PATH_MAX + JOB_IMAGE_NAME_MAX], err[256];
    job_image_path(dir, image, frame, path, sizeof(path));
    struct image img;
    add(h, "<figure>");
    if (png_read_rgb(path, &img, err, sizeof(err))) {
        if (gain > 0 && image == JOB_IMAGE_FLIP)
            metrics_stretch_flip_map(&img, gain);
        else if (gain > 0 && image == JOB_IMAGE_SSIM)
            metrics_stretch_ssim_map(&img, gain);
        size_t len = 0;
        unsigned char *png = png_encode_thumbnail(&img, THUMB_WIDTH, &len);
        if (png)
            png_img(h, png, len, caption, "thumb");
        free(png);
        image_finish(&img);
    } else {
        add(h, "<div class=\"missing\">no image</div>");
    }
    add(h, "<figcaption>");
    escaped(h, caption);
    add(h, "</figcaption></figure>");
}

static void thumbnail(struct html *h, const char *dir, enum job_image image, int frame,
                      const char *caption)
{
    stretched_thumbnail(h, dir, image, frame, 0, caption);
}

/* An image of the report's own making, at its size up to VIEW_WIDTH. */
static void view_figure(struct html *h, const struct image *img, const char *caption)
{
    size_t len = 0;
    unsigned char *png = img && img->rgb ? png_encode_thumbnail(img, VIEW_WIDTH, &len) : NULL;
    add(h, "<figure class=\"view\">");
    if (png)
        png_img(h, png, len, caption, "view");
    else
        add(h, "<div class=\"missing\">no image</div>");
    free(png);
    add(h, "<figcaption>");
    escaped(h, caption);
    add(h, "</figcaption></figure>");
}

static bool read_image(const char *dir, enum job_image image, int frame, struct image *img)
{
    char path[PATH_MAX + JOB_IMAGE_NAME_MAX], err[256];
    memset(img, 0, sizeof(*img));
    return job_image_path(dir, image, frame, path, sizeof(path)) &&
           png_read_rgb(path, img, err, sizeof(err));
}

/* A job's capture: the frame and its reference at their size, then the
 * difference views with their contrast stretched, as the dashboard shows
 * them: |frame - reference|, the SSIM map's shortfall, the FLIP map, and
 * PerceptualDiff's failing pixels with their count. */
static void capture_views(struct html *h, const json_t *job, const char *dir, const json_t *cap)
{
    int frame = (int)json_integer_value(json_object_get(cap, "frame"));
    json_t *m = json_object_get(cap, "metrics");
    struct image test, ref, view;
    bool has_test = read_image(dir, JOB_IMAGE_FRAME, frame, &test);
    char caption[256];
    snprintf(caption, sizeof(caption), "frame %d (%s)", frame, str(job, "technique"));
    view_figure(h, has_test ? &test : NULL, caption);
    if (!m) {
        image_finish(&test);
        return;
    }
    bool has_ref = read_image(dir, JOB_IMAGE_REFERENCE, frame, &ref);
    const json_t *q = json_object_get(json_object_get(job, RK_RESULT), RK_QUALITY);
    snprintf(caption, sizeof(caption), "reference (%s)", str(q, "reference"));
    view_figure(h, has_ref ? &ref : NULL, caption);
    add(h, "<br>");
    long differing = 0;
    if (has_test && has_ref && metrics_abs_difference(&test, &ref, GAIN_ABS, &view, &differing)) {
        snprintf(caption, sizeof(caption), "|frame - reference| per channel x %g: %ld pixels differ",
                 GAIN_ABS, differing);
        view_figure(h, &view, caption);
        image_finish(&view);
    }
    json_t *worst = json_object_get(m, "ssim_min");
    if (read_image(dir, JOB_IMAGE_SSIM, frame, &view)) {
        metrics_stretch_ssim_map(&view, GAIN_SSIM);
        snprintf(caption, sizeof(caption), "SSIM map (white = 1), its shortfall x %g; the worst "
                 "11x11 window, %.4f, is centred at %lld, %lld", GAIN_SSIM,
                 json_number_value(json_object_get(worst, "value")),
                 (long long)json_integer_value(json_object_get(worst, "x")),
                 (long long)json_integer_value(json_object_get(worst, "y")));
        view_figure(h, &view, caption);
        image_finish(&view);
    }
    if (read_image(dir, JOB_IMAGE_FLIP, frame, &view)) {
        metrics_stretch_flip_map(&view, GAIN_FLIP);
        snprintf(caption, sizeof(caption), "FLIP map x %g (black 0, pale yellow 1); mean %.5f",
                 GAIN_FLIP, json_number_value(json_object_get(json_object_get(m, "flip"), "mean")));
        view_figure(h, &view, caption);
        image_finish(&view);
    }
    long failing = 0;
    char err[256];
    json_t *pd = json_object_get(m, "pdiff");
    if (pd && has_ref && diff_views_pdiff_mask(job, dir, frame, &view, &failing, err, sizeof(err))) {
        snprintf(caption, sizeof(caption), "PerceptualDiff: %ld failing pixels (white), %s at a "
                 "threshold of %lld", failing, json_is_true(json_object_get(pd, "pass")) ? "passes"
                 : "fails", (long long)json_integer_value(json_object_get(pd, "threshold_pixels")));
        view_figure(h, &view, caption);
        image_finish(&view);
    }
    image_finish(&test);
    image_finish(&ref);
}

/* A JSON value people read: objects as tables of name and value (nested
 * ones nested), lists of numbers on one line, lists of objects as a table
 * with a column a key, reals to 9 significant digits (as dump). */
static void value_html(struct html *h, const json_t *v)
{
    if (json_is_object(v)) {
        add(h, "<table class=\"kv\">");
        const char *k;
        json_t *x;
        json_object_foreach((json_t *)v, k, x) {
            add(h, "<tr><th>");
            escaped(h, k);
            add(h, "</th><td>");
            value_html(h, x);
            add(h, "</td></tr>");
        }
        add(h, "</table>");
    } else if (json_is_array(v)) {
        size_t i;
        json_t *x;
        bool objects = json_array_size(v) > 0;
        json_array_foreach((json_t *)v, i, x) objects = objects && json_is_object(x);
        if (objects) {
            json_t *keys = json_object();
            json_array_foreach((json_t *)v, i, x) {
                const char *k;
                json_t *y;
                json_object_foreach(x, k, y) json_object_set_new(keys, k, json_true());
            }
            add(h, "<table class=\"kv\"><tr>");
            const char *k;
            json_t *y;
            json_object_foreach(keys, k, y) {
                add(h, "<th>");
                escaped(h, k);
                add(h, "</th>");
            }
            add(h, "</tr>");
            json_array_foreach((json_t *)v, i, x) {
                add(h, "<tr>");
                json_object_foreach(keys, k, y) {
                    add(h, "<td>");
                    value_html(h, json_object_get(x, k));
                    add(h, "</td>");
                }
                add(h, "</tr>");
            }
            add(h, "</table>");
            json_decref(keys);
        } else {
            json_array_foreach((json_t *)v, i, x) {
                if (i)
                    add(h, ", ");
                value_html(h, x);
            }
        }
    } else if (json_is_integer(v)) {
        add(h, "%lld", (long long)json_integer_value(v));
    } else if (json_is_real(v)) {
        add(h, "%.9g", json_real_value(v));
    } else if (json_is_string(v)) {
        escaped(h, json_string_value(v));
    } else {
        add(h, "%s", json_is_true(v) ? "true" : json_is_false(v) ? "false" : "-");
    }
}

static void chart(struct html *h, const json_t *subject, const char *name, bool sweep,
                  const struct chart_options *o, const char *alt)
{
    char err[256];
    size_t len = 0;
    char *png = sweep ? charts_sweep(subject, name, CHART_PNG, o, &len, err, sizeof(err))
                      : charts_job(subject, name, CHART_PNG, o, &len, err, sizeof(err));
    if (png)
        png_img(h, (unsigned char *)png, len, alt, "chart");
    else
        escaped(h, err);
    free(png);
}

static void json_block(struct html *h, const json_t *v)
{
    char *text = json_dumps(v, JSON_INDENT(2) | JSON_PRESERVE_ORDER | SV_DUMP_REALS);
    add(h, "<pre>");
    escaped(h, text);
    add(h, "</pre>");
    free(text);
}

static const char *str(const json_t *o, const char *key)
{
    const char *s = json_string_value(json_object_get(o, key));
    return s ? s : "";
}

static void head(struct html *h, const char *title, const json_t *device)
{
    add(h, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
           "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>");
    escaped(h, title);
    add(h, "</title><style>"
           "body{font-family:sans-serif;margin:2em;color:#222;max-width:1400px}"
           "table{border-collapse:collapse;margin:1em 0;font-size:14px}"
           "th,td{border:1px solid #ccc;padding:4px 8px;text-align:right}"
           "th{background:#f0f0f0}td.l,th.l{text-align:left}"
           ".fail{color:#b00;font-weight:bold}.pass{color:#070}"
           ".noisy{color:#a50;font-weight:bold}.partial{background:#fff3cd;padding:0.5em}"
           "img.chart{max-width:100%%;border:1px solid #ddd;margin:0.5em 0}"
           "figure{display:inline-block;margin:4px;text-align:center;font-size:12px}"
           "img.thumb{display:block;border:1px solid #ccc}"
           "img.view{display:block;border:1px solid #ccc;max-width:100%%;"
           "min-width:min(320px,100%%);image-rendering:pixelated}"
           "figure.view{display:inline-table;vertical-align:top;max-width:%dpx}"
           "figure.view figcaption{display:table-caption;caption-side:bottom}"
           "table.kv{margin:0}table.kv td,table.kv th{text-align:left;border:none;"
           "border-top:1px solid #eee;padding:2px 8px;vertical-align:top}"
           "table.kv th{background:none;font-weight:600}"
           ".missing{width:240px;height:60px;background:#eee}"
           "pre{background:#f7f7f7;padding:1em;overflow:auto;font-size:12px}"
           "</style></head><body><h1>", VIEW_WIDTH);
    escaped(h, title);
    add(h, "</h1><p>shadebenchd %s on <b>", PACKAGE_VERSION);
    escaped(h, str(device, "gl_renderer"));
    add(h, "</b> (");
    escaped(h, str(device, "gl_version"));
    add(h, "; EGL ");
    escaped(h, str(device, "egl_platform"));
    add(h, " platform, ");
    escaped(h, str(device, "egl_device"));
    add(h, ")</p>");
}

static void ms_cell(struct html *h, const json_t *cell)
{
    json_t *ci = json_object_get(cell, RK_CI95);
    if (!json_is_number(json_object_get(cell, RK_MEDIAN))) {
        add(h, "<td>-</td>");
        return;
    }
    if (json_array_size(ci) == 2)
        add(h, "<td>%.3f [%.3f, %.3f]</td>", json_number_value(json_object_get(cell, RK_MEDIAN)),
            fmax(0.0, json_number_value(json_array_get(ci, 0))),
            json_number_value(json_array_get(ci, 1)));
    else
        add(h, "<td>%.3f</td>", json_number_value(json_object_get(cell, RK_MEDIAN)));
}

static void num_cell(struct html *h, const json_t *v, const char *fmt)
{
    if (json_is_number(v))
        add(h, fmt, json_number_value(v));
    else
        add(h, "<td>-</td>");
}

/* ---- the verdict of a sweep ---- */

/* A swept value or a spec for people: reals to 9 significant digits (0.1,
 * not 0.10000000000000001). */
static char *dump(const json_t *v, size_t flags)
{
    return json_dumps(v, flags | JSON_ENCODE_ANY | SV_DUMP_REALS);
}

/* The first max names of a list, "a, b and 3 more", after lead. */
static void name_list(struct html *h, const json_t *names, size_t max, const char *lead)
{
    size_t i;
    json_t *name;
    json_array_foreach(names, i, name) {
        if (i == max) {
            add(h, " and %zu more", json_array_size(names) - max);
            break;
        }
        add(h, "%s", i ? ", " : lead);
        escaped(h, json_string_value(name));
    }
}

/* "x at 12.3 ms: 0.90x the reference (0.85x to 0.95x)", or not
 * distinguishable when the intervals overlap. */
static void against_html(struct html *h, const json_t *pt, const char *what)
{
    char *vals = dump(json_object_get(pt, "values"), JSON_COMPACT);
    add(h, "; %s is ", what);
    escaped(h, str(pt, "technique"));
    add(h, " ");
    escaped(h, vals);
    free(vals);
    add(h, " at %.3f ms", json_number_value(json_object_get(pt, "ms")));
    json_t *ci = json_object_get(pt, "ratio_ci");
    if (json_object_get(pt, "ratio")) {
        double r = json_number_value(json_object_get(pt, "ratio"));
        double lo = json_number_value(json_array_get(ci, 0)), hi = json_number_value(json_array_get(ci, 1));
        char hi_text[32];
        if (hi > 1e6)
            snprintf(hi_text, sizeof(hi_text), "any ratio");
        else
            snprintf(hi_text, sizeof(hi_text), "%.2f&times;", hi);
        if (json_is_true(json_object_get(pt, "distinguishable")))
            add(h, " (<b>%.2f&times;</b> the reference; the intervals allow %.2f&times; to %s)", r,
                lo, hi_text);
        else
            add(h, " (<b>not distinguishable from the reference at this noise</b>: %.2f&times; "
                   "by the medians, but the intervals allow %.2f&times; to %s)", r, lo, hi_text);
    }
    json_t *tied = json_object_get(pt, "tied_with");
    if (json_array_size(tied)) {
        add(h, ", as fast as far as the intervals tell as ");
        name_list(h, tied, 4, "");
    }
}

/* One point of the summary: technique and values, time, and its ratio
 * to the reference with the interval (or that the two are not told apart). */
static void summary_point(struct html *h, const json_t *pt)
{
    if (!pt || !json_object_get(pt, "technique")) {
        add(h, "<td class=\"l\">-</td><td>-</td><td>-</td>");
        return;
    }
    char *vals = dump(json_object_get(pt, "values"), JSON_COMPACT);
    add(h, "<td class=\"l\"><b>");
    escaped(h, str(pt, "technique"));
    add(h, "</b> ");
    escaped(h, vals);
    free(vals);
    add(h, "</td><td>%.3f</td>", json_number_value(json_object_get(pt, "ms")));
    json_t *ci = json_object_get(pt, "ratio_ci");
    if (!json_object_get(pt, "ratio")) {
        add(h, "<td>-</td>");
        return;
    }
    bool told = json_is_true(json_object_get(pt, "distinguishable"));
    double r = json_number_value(json_object_get(pt, "ratio"));
    double hi = json_number_value(json_array_get(ci, 1));
    char hi_text[32];
    if (hi > 1e6)
        snprintf(hi_text, sizeof(hi_text), "any");
    else
        snprintf(hi_text, sizeof(hi_text), "%.2f", hi);
    add(h, "<td class=\"%s\">%.2f&times; [%.2f, %s]%s</td>", told ? (r < 1 ? "pass" : "fail") : "", r,
        json_number_value(json_array_get(ci, 0)), hi_text, told ? "" : "<br>not told apart");
}

/* The summary first: per workload, the fastest technique and its ratio to
 * the reference with intervals, and the fastest passing PerceptualDiff. */
static void summary_html(struct html *h, const json_t *verdict)
{
    json_t *rows = json_object_get(verdict, "against_reference");
    if (!json_array_size(rows))
        return;
    add(h, "<h2>Which technique wins where</h2><table><tr><th class=\"l\">workload</th>"
           "<th>reference, ms [95%%]</th><th class=\"l\">wins</th>"
           "<th class=\"l\">fastest swept point</th><th>ms</th>"
           "<th>ratio to the reference [95%%]</th><th class=\"l\">fastest passing "
           "PerceptualDiff</th><th>ms</th><th>ratio [95%%]</th></tr>");
    size_t i;
    json_t *w;
    json_array_foreach(rows, i, w) {
        json_t *ci = json_object_get(w, "reference_ci");
        add(h, "<tr><td class=\"l\">");
        escaped(h, str(w, "workload")[0] ? str(w, "workload") : "all points");
        add(h, "</td><td>");
        escaped(h, str(w, "reference"));
        add(h, " %.3f [%.3f, %.3f]</td>", json_number_value(json_object_get(w, "reference_ms")),
            json_number_value(json_array_get(ci, 0)), json_number_value(json_array_get(ci, 1)));
        json_t *win = json_object_get(w, "winner");
        add(h, "<td class=\"l\"><b>");
        escaped(h, str(win, "technique"));
        add(h, "</b>%s</td>", json_is_true(json_object_get(win, "reference"))
                                  ? " (the reference)"
                              : json_is_true(json_object_get(win, "tied_with_reference"))
                                  ? "<br>not told apart from the reference"
                                  : "");
        summary_point(h, json_object_get(w, "fastest"));
        summary_point(h, json_object_get(w, "fastest_passing"));
        add(h, "</tr>");
    }
    add(h, "</table>");
}

static void verdict_html(struct html *h, const json_t *v)
{
    add(h, "<h2>Verdict</h2>");
    if (json_is_true(json_object_get(v, "partial"))) {
        add(h, "<p class=\"partial\"><b>A partial sweep</b> (%s): %lld of %lld planned points "
               "have rows",
            str(v, "status"),
            (long long)(json_integer_value(json_object_get(v, "points_total")) -
                        json_integer_value(json_object_get(v, "not_run"))),
            (long long)json_integer_value(json_object_get(v, "points_total")));
        if (json_array_size(json_object_get(v, "missing")))
            add(h, ", %zu of them did not finish", json_array_size(json_object_get(v, "missing")));
        add(h, ". The verdict below covers only the points that ran.</p>");
    }
    add(h, "<ul class=\"verdict\">");
    size_t i;
    json_t *m;
    json_array_foreach(json_object_get(v, "missing"), i, m) {
        char *vals = dump(json_object_get(m, "values"), JSON_COMPACT);
        add(h, "<li class=\"fail\">Not measured: ");
        escaped(h, str(m, "technique"));
        add(h, " ");
        escaped(h, vals);
        add(h, " (%s", str(m, "status"));
        if (json_is_string(json_object_get(m, "error"))) {
            add(h, ": ");
            escaped(h, str(m, "error"));
        }
        add(h, ").</li>");
        free(vals);
    }
    json_t *noisy = json_object_get(v, "noisy");
    if (json_array_size(noisy)) {
        double worst = 0;
        json_array_foreach(noisy, i, m) worst = fmax(worst, json_number_value(json_object_get(m, "other_cpu_share")));
        add(h, "<li class=\"noisy\"><b>Noise:</b> %zu point%s ran while other processes took CPU "
               "time", json_array_size(noisy), json_array_size(noisy) == 1 ? "" : "s");
        if (worst > 0)
            add(h, " (up to %.0f%% of the machine)", 100 * worst);
        add(h, "; their times may be inflated, and a comparison involving them is only as good "
               "as their intervals: ");
        json_array_foreach(noisy, i, m) {
            char *vals = dump(json_object_get(m, "values"), JSON_COMPACT);
            add(h, "%s", i ? ", " : "");
            escaped(h, str(m, "technique"));
            add(h, " ");
            escaped(h, vals);
            double share = json_number_value(json_object_get(m, "other_cpu_share"));
            if (share >= 0)
                add(h, " (%.0f%%)", 100 * share);
            free(vals);
        }
        add(h, ".</li>");
    }
    long long judged = json_integer_value(json_object_get(v, "pdiff_judged"));
    json_t *passing = json_object_get(v, "pdiff_passing");
    json_t *lp = json_object_get(v, "largest_pdiff_pass");
    if (lp) {
        char *val = dump(json_object_get(lp, "value"), 0);
        add(h, "<li>Largest <b>");
        escaped(h, str(lp, "param"));
        if (json_is_null(json_object_get(lp, "value")))
            add(h, "</b> whose captures all pass PerceptualDiff: <b>none</b> of the %lld judged "
                   "points passes.</li>", judged);
        else
            add(h, "</b> whose captures all pass PerceptualDiff: <b>%s</b>.</li>", val ? val : "?");
        free(val);
    } else if (judged) {
        add(h, "<li>Points whose captures all pass PerceptualDiff: <b>%zu of %lld</b> judged",
            json_array_size(passing), judged);
        name_list(h, passing, 12, ": ");
        add(h, ".</li>");
    }
    json_t *bp = json_object_get(v, "breaking_point");
    if (bp) {
        char *val = dump(json_object_get(bp, "value"), 0);
        add(h, "<li>Breaking point: the largest <b>");
        escaped(h, str(bp, "param"));
        add(h, "</b> at which <b>");
        escaped(h, str(bp, "criterion"));
        add(h, "</b> still holds: <b>%s</b> (%s, after %lld probes).</li>", val ? val : "?",
            str(bp, "outcome"), (long long)json_integer_value(json_object_get(bp, "probes")));
        free(val);
    }
    json_t *f;
    json_array_foreach(json_object_get(v, "front"), i, f) {
        add(h, "<li>Pareto front of speed against worst SSIM");
        if (str(f, RK_WORKLOAD)[0]) {
            add(h, " (");
            escaped(h, str(f, RK_WORKLOAD));
            add(h, ")");
        }
        add(h, ", only where intervals separate: ");
        size_t k;
        json_t *p;
        bool tied = false;
        json_array_foreach(json_object_get(f, "points"), k, p) {
            add(h, "%s", k ? ", " : "");
            escaped(h, str(p, "name"));
            add(h, " (%.3f ms, SSIM %.6f%s)", json_number_value(json_object_get(p, "ms")),
                json_number_value(json_object_get(p, RK_WORST_SSIM)),
                json_is_true(json_object_get(p, "tied")) ? ", tied" : "");
            tied = tied || json_is_true(json_object_get(p, "tied"));
        }
        add(h, "%s.</li>", tied ? "; tied points are equally accurate and their times are not "
                                  "distinguishable at this noise" : "");
    }
    json_t *c;
    size_t stated = 0;
    json_array_foreach(json_object_get(v, "crossovers"), i, c) {
        json_t *bt = json_object_get(c, "between");
        bool sure = json_is_true(json_object_get(c, "distinguishable"));
        stated += sure;
        if (sure) {
            add(h, "<li>Crossover on %s: <b>", str(v, "series"));
            escaped(h, str(c, "faster_below"));
            add(h, "</b> is faster below <b>");
            escaped(h, str(c, "param"));
            add(h, " &asymp; %.4g</b> (between %.4g and %.4g, where the intervals separate on "
                   "both sides), <b>",
                json_number_value(json_object_get(c, "at")), json_number_value(json_array_get(bt, 0)),
                json_number_value(json_array_get(bt, 1)));
            escaped(h, str(c, "faster_above"));
            add(h, "</b> above it");
        } else {
            add(h, "<li>By their medians ");
            escaped(h, str(c, "faster_below"));
            add(h, " and ");
            escaped(h, str(c, "faster_above"));
            add(h, " cross between ");
            escaped(h, str(c, "param"));
            add(h, " = %.4g and %.4g, but their intervals overlap on at least one side: <b>not "
                   "distinguishable at this noise</b>",
                json_number_value(json_array_get(bt, 0)), json_number_value(json_array_get(bt, 1)));
        }
        if (str(c, RK_WORKLOAD)[0]) {
            add(h, " (");
            escaped(h, str(c, RK_WORKLOAD));
            add(h, ")");
        }
        add(h, ".</li>");
    }
    if (!json_array_size(json_object_get(v, "crossovers")))
        add(h, "<li>No crossover: along the first swept numeric parameter no technique overtakes "
               "another on the same workload.</li>");
    json_t *w;
    json_array_foreach(json_object_get(v, "against_reference"), i, w) {
        json_t *rm = json_object_get(w, RK_REFERENCE_MS);
        if (!rm)
            continue;
        json_t *rci = json_object_get(w, "reference_ci");
        add(h, "<li>");
        if (str(w, RK_WORKLOAD)[0]) {
            escaped(h, str(w, RK_WORKLOAD));
            add(h, ": ");
        }
        escaped(h, str(w, "reference"));
        add(h, " (the reference) takes %.3f ms [%.3f, %.3f]", json_number_value(rm),
            json_number_value(json_array_get(rci, 0)), json_number_value(json_array_get(rci, 1)));
        if (json_object_get(w, "fastest"))
            against_html(h, json_object_get(w, "fastest"), "the fastest point");
        if (json_object_get(w, "fastest_passing"))
            against_html(h, json_object_get(w, "fastest_passing"),
                         "the fastest passing PerceptualDiff");
        else
            add(h, "; no point passes PerceptualDiff");
        add(h, ".</li>");
    }
    add(h, "</ul>");
}

/* The sweep with what its rows do not carry: each point job's interference
 * figures (from its result.json), so that the verdict, the table and the
 * charts mark the same noisy points. New reference. */
static json_t *with_interference(const json_t *sweep, report_job_dir_fn job_dir, void *ctx)
{
    json_t *copy = json_deep_copy(sweep);
    size_t i;
    json_t *row;
    json_array_foreach(json_object_get(copy, "points"), i, row) {
        char dir[PATH_MAX], path[PATH_MAX + 16];
        int frame = 0;
        const char *job = json_string_value(json_object_get(row, "job"));
        if (!job_dir || !job || !job_dir(ctx, job, dir, sizeof(dir), &frame) ||
            !job_file_path(dir, JOB_FILE_RESULT, path, sizeof(path)))
            continue;
        json_t *result = json_load_file(path, 0, NULL);
        json_t *inter = json_object_get(result, RK_INTERFERENCE);
        if (inter)
            json_object_set_new(row, RK_INTERFERENCE,
                                json_pack("{s:O, s:b}", "other_cpu_share",
                                          json_object_get(inter, "other_cpu_share"), "noisy",
                                          noise_interference_noisy(inter)));
        json_decref(result);
    }
    return copy;
}

/* The thesis's chapter 4 for this device: execution time of the timed
 * frames per scene and technique (mean, median, standard deviation over the
 * runs), the factor between the two techniques, PerceptualDiff at 22.6
 * degrees and the SSIM range. */
static void thesis_tables(struct html *h, const json_t *spec, const json_t *points)
{
    struct thesis_size size;
    struct job_error err;
    if (!sweep_thesis_size(spec, &size, &err)) /* the sweep was accepted: never */
        size = (struct thesis_size){1, 1080, 720, 256};
    add(h, "<h2>The thesis's experiment on this device (its chapter 4)</h2>");
    if (size.scale == 1)
        add(h, "<p>At the thesis's size: %dx%d, OSL's tiles %d texels a side.</p>", size.width,
            size.height, size.osl_resolution);
    else
        add(h, "<p>Smaller than the thesis's (scale %g): %dx%d, OSL's tiles %d texels a side, "
               "against the thesis's 1080x720 and 256 (the same texels per pixel).</p>",
            size.scale, size.width, size.height, size.osl_resolution);
    add(h, "<table><tr><th class=\"l\">scene</th><th class=\"l\">technique</th><th>runs</th>"
           "<th>mean execution time (s)</th><th>median (s)</th><th>standard deviation</th>"
           "<th>OSL / forward</th><th>PerceptualDiff (22.6&deg;)</th><th>worst SSIM</th></tr>");
    char osl_label[32];
    snprintf(osl_label, sizeof(osl_label), "OSL (%d, async 20)", size.osl_resolution);
    for (int dynamic = 1; dynamic >= 0; dynamic--) {
        const json_t *rows[2] = {NULL, NULL}; /* forward, osl */
        size_t i;
        json_t *row;
        json_array_foreach(points, i, row) {
            json_t *values = json_object_get(row, "values");
            if (json_is_true(json_object_get(values, "scene.dynamic")) != (dynamic == 1))
                continue;
            rows[strcmp(str(row, "technique"), "osl") == 0] = row;
        }
        double fwd = json_number_value(json_object_get(json_object_get(rows[0], RK_WALL_S), RK_MEAN));
        for (int t = 0; t < 2; t++) {
            const json_t *r = rows[t];
            if (!r)
                continue;
            json_t *wall = json_object_get(r, RK_WALL_S);
            double mean = json_number_value(json_object_get(wall, RK_MEAN));
            add(h, "<tr><td class=\"l\">%s lights</td><td class=\"l\">%s</td><td>%lld</td>"
                   "<td>%.3f</td><td>%.3f</td><td>%.3f</td>",
                dynamic ? "moving" : "still", t ? osl_label : "forward",
                (long long)json_integer_value(json_object_get(wall, RK_RUNS)), mean,
                json_number_value(json_object_get(wall, RK_MEDIAN)),
                json_number_value(json_object_get(wall, RK_STDDEV)));
            if (t && fwd > 0)
                add(h, "<td>%.2f</td>", mean / fwd);
            else
                add(h, "<td></td>");
            json_t *pf = json_object_get(r, RK_PDIFF_FAILED_CAPTURES);
            add(h, "<td class=\"%s\">%s</td>", json_integer_value(pf) ? "fail" : "pass",
                json_integer_value(pf) ? "fail" : "pass");
            num_cell(h, json_object_get(r, RK_WORST_SSIM), "<td>%.5f</td>");
            add(h, "</tr>");
        }
    }
    add(h, "</table><p>The thesis measured OSL / forward = 0.84 to 1.07 with still lights and "
           "5.12 to 11.75 with moving lights on three NVIDIA GPUs, every PerceptualDiff test "
           "passing and SSIM from 0.99991 to 0.99994.</p>");
}

char *report_sweep_html(const json_t *posted, const json_t *device, report_job_dir_fn job_dir,
                        void *ctx, size_t *len)
{
    /* One copy of the table, with the points' noise, for the verdict, the
     * table and the charts alike. */
    json_t *sweep = with_interference(posted, job_dir, ctx);
    struct html h = {0};
    char title[128];
    snprintf(title, sizeof(title), "shadebench sweep %s", str(sweep, "id"));
    head(&h, title, device);
    add(&h, "<p>Status: <b>%s</b>; %lld of %lld points.", str(sweep, "status"),
        (long long)json_integer_value(json_object_get(json_object_get(sweep, "progress"), "points_done")),
        (long long)json_integer_value(json_object_get(json_object_get(sweep, "progress"), "points_total")));
    if (json_object_get(sweep, "error")) {
        add(&h, " ");
        escaped(&h, str(sweep, "error"));
    }
    add(&h, "</p>");
    const char *series = charts_default_series(device);
    json_t *verdict = sweep_verdict_json(sweep, series);
    summary_html(&h, verdict);
    verdict_html(&h, verdict);
    json_decref(verdict);
    json_t *points = json_object_get(sweep, "points");
    if (strcmp(str(sweep, "preset"), "thesis") == 0)
        thesis_tables(&h, json_object_get(sweep, "spec"), points);
    json_t *base_ref =
        json_object_get(json_object_get(json_object_get(sweep, "spec"), "base"), "reference");
    if (json_is_object(base_ref)) /* {"technique", "supersample"} */
        base_ref = json_object_get(base_ref, "technique");
    const char *reference = json_string_value(base_ref);
    reference = reference ? reference : "forward";
    add(&h, "<h2>Table</h2><table><tr><th class=\"l\">parameters</th><th class=\"l\">technique</th>"
            "<th class=\"l\">job</th><th>frame_ms median [95%%]</th><th>gpu_ms median [95%%]</th>"
            "<th>worst SSIM</th><th>worst FLIP</th><th>PerceptualDiff failures</th>"
            "<th>others' CPU</th></tr>");
    size_t i;
    json_t *row;
    json_array_foreach(points, i, row) {
        char *values = dump(json_object_get(row, "values"), JSON_COMPACT);
        bool done = !strcmp(str(row, "status"), "done");
        add(&h, "<tr%s><td class=\"l\">", done ? "" : " class=\"fail\"");
        escaped(&h, values);
        add(&h, "</td><td class=\"l\">");
        escaped(&h, str(row, "technique"));
        add(&h, "</td><td class=\"l\">");
        escaped(&h, str(row, "job"));
        add(&h, " (%s)%s</td>", done ? "done" : str(row, "status"),
            !strcmp(str(row, "technique"), reference) ? " reference, timed" : "");
        free(values);
        ms_cell(&h, json_object_get(row, RK_FRAME_MS));
        ms_cell(&h, json_object_get(row, RK_GPU_MS));
        num_cell(&h, json_object_get(row, RK_WORST_SSIM), "<td>%.6f</td>");
        num_cell(&h, json_object_get(row, RK_WORST_FLIP), "<td>%.5f</td>");
        json_t *pf = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
        if (json_is_integer(pf))
            add(&h, "<td class=\"%s\">%lld</td>", json_integer_value(pf) ? "fail" : "pass",
                (long long)json_integer_value(pf));
        else
            add(&h, "<td>-</td>");
        json_t *inter = json_object_get(row, RK_INTERFERENCE);
        json_t *share = json_object_get(inter, "other_cpu_share");
        if (json_is_number(share))
            add(&h, "<td class=\"%s\">%s%.0f%%</td>", noise_interference_noisy(inter)
                ? "noisy" : "", noise_interference_noisy(inter) ? "noisy: " : "",
                100 * json_number_value(share));
        else
            add(&h, "<td>-</td>");
        add(&h, "</tr>");
    }
    long long planned = json_integer_value(json_object_get(json_object_get(sweep, "progress"),
                                                           "points_total"));
    if (planned > (long long)json_array_size(points))
        add(&h, "<tr class=\"fail\"><td class=\"l\" colspan=\"9\">%lld planned point%s not run "
                "(the sweep is %s)</td></tr>", planned - (long long)json_array_size(points),
            planned - (long long)json_array_size(points) == 1 ? "" : "s", str(sweep, "status"));
    add(&h, "</table><p>Intervals are 95%%; a lower end below zero is shown as 0 (times are "
            "never negative). Others' CPU: the share of the machine's CPU time other processes "
            "took during the point's timed frames; the noise rule, the same for the daemon, the "
            "client and reports: %s.</p><h2>Charts</h2>",
        INTERFERENCE_RULE);
    struct chart_options o = {.device = device};
    chart(&h, sweep, "speed_accuracy", true, &o, "speed against accuracy (SSIM)");
    o.flip = true;
    chart(&h, sweep, "speed_accuracy", true, &o, "speed against accuracy (FLIP)");
    o.flip = false;
    chart(&h, sweep, "time_vs_param", true, &o, "frame time against the parameter");
    chart(&h, sweep, "distribution", true, &o, "frame-time distributions");

    add(&h, "<h2>Captures</h2><p>Last capture of each point: the frame, the reference, "
            "the SSIM map and the FLIP map, their contrast stretched%s.</p>",
        json_array_size(points) > THUMB_POINTS ? " (the first 64 points)" : "");
    json_array_foreach(points, i, row) {
        if (i >= THUMB_POINTS)
            break;
        char dir[PATH_MAX];
        int frame = 0;
        if (!job_dir || !job_dir(ctx, str(row, "job"), dir, sizeof(dir), &frame) || frame <= 0)
            continue;
        char *values = dump(json_object_get(row, "values"), JSON_COMPACT);
        add(&h, "<div><h3>");
        escaped(&h, str(row, "technique"));
        add(&h, " ");
        escaped(&h, values);
        add(&h, "</h3>");
        free(values);
        thumbnail(&h, dir, JOB_IMAGE_FRAME, frame, "frame");
        thumbnail(&h, dir, JOB_IMAGE_REFERENCE, frame, "reference");
        stretched_thumbnail(&h, dir, JOB_IMAGE_SSIM, frame, GAIN_SSIM, "SSIM map, shortfall x 8");
        stretched_thumbnail(&h, dir, JOB_IMAGE_FLIP, frame, GAIN_FLIP, "FLIP map x 4");
        add(&h, "</div>");
    }
    add(&h, "<h2>The sweep as posted</h2>");
    json_block(&h, json_object_get(sweep, "spec"));
    add(&h, "</body></html>\n");
    json_decref(sweep);
    if (h.failed) {
        free(h.data);
        return NULL;
    }
    *len = h.len;
    return h.data;
}

static void stats_row(struct html *h, const char *name, const json_t *s)
{
    add(h, "<tr><td class=\"l\">%s</td>", name);
    static const char *const keys[] = {RK_MEAN, RK_MEDIAN, RK_STDDEV, RK_MIN, RK_P5, RK_P95, RK_P99, RK_MAX, RK_CV};
    for (size_t k = 0; k < sizeof(keys) / sizeof(keys[0]); k++)
        num_cell(h, json_object_get(s, keys[k]), "<td>%.4f</td>");
    add(h, "</tr>");
}

/* Per-frame samples from a job's timings.csv: {"frame_ms": [...], ...}. */
static json_t *read_timings(const char *dir)
{
    char path[PATH_MAX + 16];
    job_file_path(dir ? dir : "", JOB_FILE_TIMINGS, path, sizeof(path));
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    char line[1024];
    json_t *out = json_object(), *cols = json_array();
    if (fgets(line, sizeof(line), f)) {
        line[strcspn(line, "\r\n")] = '\0';
        for (char *save = NULL, *t = strtok_r(line, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
            json_t *arr = json_array();
            json_array_append(cols, arr);
            json_object_set_new(out, t, arr);
        }
    }
    while (fgets(line, sizeof(line), f)) {
        char *p = line;
        for (size_t c = 0; c < json_array_size(cols); c++) {
            double v = strtod(p, &p);
            json_array_append_new(json_array_get(cols, c), json_real(v));
            if (*p == ',')
                p++;
        }
    }
    fclose(f);
    json_decref(cols);
    return out;
}

/* The technique's own figures (result.<technique>, as its describe hook
 * wrote them) and its per-pass GPU times. */
static void technique_figures(struct html *h, const json_t *r, const char *technique)
{
    json_t *own = json_object_get(r, technique);
    json_t *sections = json_object_get(r, "gpu_sections_ms");
    add(h, "<h2>Technique figures (%s)</h2><table><tr><th class=\"l\">figure</th>"
           "<th class=\"l\">value</th></tr>", technique);
    add(h, "<tr><td class=\"l\">triangles a frame, instances, lights</td><td class=\"l\">%lld, "
           "%lld, %lld</td></tr>",
        (long long)json_integer_value(json_object_get(r, "triangles_per_frame")),
        (long long)json_integer_value(json_object_get(r, "instances")),
        (long long)json_integer_value(json_object_get(r, "lights")));
    add(h, "<tr><td class=\"l\">timer query stalls</td><td class=\"l\">%lld</td></tr>",
        (long long)json_integer_value(json_object_get(r, "timer_query_stalls")));
    const char *key;
    json_t *v;
    json_object_foreach(own, key, v) {
        add(h, "<tr><td class=\"l\">");
        escaped(h, key);
        add(h, "</td><td class=\"l\">");
        value_html(h, v);
        add(h, "</td></tr>");
    }
    json_object_foreach(sections, key, v) {
        add(h, "<tr><td class=\"l\">gpu_ms of pass ");
        escaped(h, key);
        add(h, "</td><td class=\"l\">median %.4f, p95 %.4f</td></tr>",
            json_number_value(json_object_get(v, RK_MEDIAN)),
            json_number_value(json_object_get(v, RK_P95)));
    }
    add(h, "</table>");
}

static void runs_table(struct html *h, const json_t *r)
{
    json_t *runs = json_object_get(r, RK_RUNS);
    if (!json_array_size(runs))
        return;
    json_t *rep = json_object_get(r, RK_REPEAT);
    add(h, "<h2>Runs</h2><p>%lld runs (%s); across runs, the median frame_ms of the run "
           "medians is %.4f ms.</p><table><tr><th>run</th><th>frame_ms median</th>"
           "<th>gpu_ms median</th><th>cpu_ms median</th><th>wall s</th></tr>",
        (long long)json_integer_value(json_object_get(rep, RK_RUNS)),
        json_is_true(json_object_get(rep, RK_STABLE)) ? "stable" : "not stable to 2.5%",
        json_number_value(json_object_get(json_object_get(rep, RK_FRAME_MS), RK_MEDIAN)));
    size_t i;
    json_t *run;
    json_array_foreach(runs, i, run) {
        add(h, "<tr><td>%lld</td>", (long long)json_integer_value(json_object_get(run, "run")));
        num_cell(h, json_object_get(json_object_get(run, RK_FRAME_MS), RK_MEDIAN), "<td>%.4f</td>");
        num_cell(h, json_object_get(json_object_get(run, RK_GPU_MS), RK_MEDIAN), "<td>%.4f</td>");
        num_cell(h, json_object_get(json_object_get(run, RK_CPU_MS), RK_MEDIAN), "<td>%.4f</td>");
        num_cell(h, json_object_get(run, RK_WALL_S), "<td>%.3f</td>");
        add(h, "</tr>");
    }
    add(h, "</table>");
}

/* What disturbed the run, where people look first: the CPU other processes
 * took during the timed frames and the load, and whether that makes the
 * run noisy by the noise rule (common/noise.h). */
static void noise_html(struct html *h, const json_t *inter)
{
    json_t *share = json_object_get(inter, "other_cpu_share");
    if (!json_is_number(share)) {
        if (inter && json_object_get(inter, "error")) {
            add(h, "<p>Noise: not measured (");
            escaped(h, str(inter, "error"));
            add(h, ").</p>");
        }
        return;
    }
    bool noisy = noise_interference_noisy(inter);
    json_t *ls = json_object_get(inter, "loadavg_start"), *le = json_object_get(inter, "loadavg_end");
    add(h, "<p class=\"%s\">%s other processes took <b>%.0f%%</b> of the machine's CPU time "
           "during the timed frames (1-minute load %.2f to %.2f on %lld CPUs)",
        noisy ? "noisy" : "", noisy ? "<b>A noisy run:</b>" : "Quiet run:",
        100 * json_number_value(share), json_number_value(json_array_get(ls, 0)),
        json_number_value(json_array_get(le, 0)),
        (long long)json_integer_value(json_object_get(inter, "cpus")));
    add(h, noisy ? "; its times may be inflated by them, so compare them with care (the "
                   "noise rule, the same for the daemon, the client and reports: %s).</p>"
                 : " (the noise rule, the same for the daemon, the client and reports: %s).</p>",
        INTERFERENCE_RULE);
}

char *report_job_html(const json_t *job, const char *dir, const json_t *device, size_t *len)
{
    struct html h = {0};
    char title[128];
    snprintf(title, sizeof(title), "shadebench job %s (%s)", str(job, "id"), str(job, "technique"));
    head(&h, title, device);
    json_t *r = json_object_get(job, RK_RESULT);
    add(&h, "<p>Status: <b>%s</b>", str(job, "status"));
    if (json_object_get(job, "error")) {
        add(&h, ": ");
        escaped(&h, str(job, "error"));
    }
    add(&h, ".</p>");
    noise_html(&h, json_object_get(r, RK_INTERFERENCE));
    if (r) {
        add(&h, "<h2>Timings</h2><p>%lld timed frames after %lld warm-up, %.3f s, %.1f fps, "
                "%lld triangles a frame.</p>",
            (long long)json_integer_value(json_object_get(r, "frames")),
            (long long)json_integer_value(json_object_get(r, "warmup_frames")),
            json_number_value(json_object_get(r, RK_WALL_S)), json_number_value(json_object_get(r, RK_FPS)),
            (long long)json_integer_value(json_object_get(r, "triangles_per_frame")));
        add(&h, "<table><tr><th class=\"l\">ms</th><th>mean</th><th>median</th><th>stddev</th>"
                "<th>min</th><th>p5</th><th>p95</th><th>p99</th><th>max</th><th>cv</th></tr>");
        stats_row(&h, RK_FRAME_MS, json_object_get(r, RK_FRAME_MS));
        stats_row(&h, RK_GPU_MS, json_object_get(r, RK_GPU_MS));
        stats_row(&h, RK_CPU_MS, json_object_get(r, RK_CPU_MS));
        add(&h, "</table>");
        struct chart_options o = {.device = device};
        json_t *samples = read_timings(dir);
        char err[256];
        size_t tlen = 0;
        char *png = samples ? charts_job_timeline(job, samples, CHART_PNG, &o, &tlen, err,
                                                  sizeof(err))
                            : NULL;
        if (png)
            png_img(&h, (unsigned char *)png, tlen, "frame times over the run", "chart");
        free(png);
        json_decref(samples);
        chart(&h, job, "distribution", false, &o, "frame-time distribution");
        runs_table(&h, r);
        technique_figures(&h, r, str(job, "technique"));
        json_t *q = json_object_get(r, RK_QUALITY);
        if (q) {
            json_int_t ss = json_integer_value(json_object_get(q, "reference_supersample"));
            add(&h, "<h2>Quality against %s", str(q, "reference"));
            if (ss > 1)
                add(&h, ", supersampled %lldx%lld", (long long)ss, (long long)ss);
            add(&h, "</h2><p>Worst SSIM %.6f, worst FLIP mean %.5f, "
                    "PerceptualDiff failed on %lld of %lld captures.</p>",
                json_number_value(json_object_get(json_object_get(q, RK_WORST_SSIM), "value")),
                json_number_value(json_object_get(json_object_get(q, RK_WORST_FLIP), "mean")),
                (long long)json_integer_value(json_object_get(q, RK_PDIFF_FAILED_CAPTURES)),
                (long long)json_integer_value(json_object_get(q, "captures_compared")));
        }
        add(&h, "<h2>Captures</h2>");
        size_t i;
        json_t *c;
        json_array_foreach(json_object_get(r, RK_CAPTURES), i, c) {
            int frame = (int)json_integer_value(json_object_get(c, "frame"));
            json_t *m = json_object_get(c, "metrics");
            add(&h, "<div><h3>Frame %d", frame);
            if (m) {
                json_t *pd = json_object_get(m, "pdiff");
                add(&h, ": SSIM %.6f, FLIP %.5f, PerceptualDiff <span class=\"%s\">%s</span>",
                    json_number_value(json_object_get(m, "ssim")),
                    json_number_value(json_object_get(json_object_get(m, "flip"), "mean")),
                    json_is_true(json_object_get(pd, "pass")) ? "pass" : "fail",
                    pd ? (json_is_true(json_object_get(pd, "pass")) ? "pass" : "fail") : "-");
            }
            json_t *tf = json_object_get(c, RK_TEMPORAL);
            if (tf)
                add(&h, "; flicker over frames %lld to %lld: %.6f",
                    (long long)json_integer_value(json_array_get(json_object_get(tf, "frames"), 0)),
                    (long long)json_integer_value(json_array_get(json_object_get(tf, "frames"), 1)),
                    json_number_value(json_object_get(tf, "flicker")));
            add(&h, "</h3>");
            capture_views(&h, job, dir, c);
            add(&h, "</div>");
        }
    }
    add(&h, "<h2>The job as understood</h2>");
    json_block(&h, json_object_get(job, "spec"));
    add(&h, "</body></html>\n");
    if (h.failed) {
        free(h.data);
        return NULL;
    }
    *len = h.len;
    return h.data;
}
