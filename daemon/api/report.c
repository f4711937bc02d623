#define _POSIX_C_SOURCE 200809L
#include "daemon/api/report.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "daemon/api/charts.h"
#include "common/job_files.h"
#include "common/png_io.h"
#include "common/result_keys.h"

/* Points of a sweep that get thumbnails: enough to see how the image
 * changes, few enough that the page stays a reasonable size. */
enum { THUMB_POINTS = 64, THUMB_WIDTH = 240 };

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

/* A thumbnail of a PNG file in the job's directory, or a note if missing. */
static void thumbnail(struct html *h, const char *dir, enum job_image image, int frame,
                      const char *caption)
{
    char path[PATH_MAX + JOB_IMAGE_NAME_MAX], err[256];
    job_image_path(dir, image, frame, path, sizeof(path));
    struct image img;
    add(h, "<figure>");
    if (png_read_rgb(path, &img, err, sizeof(err))) {
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
    char *text = json_dumps(v, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
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
           "img.chart{max-width:100%%;border:1px solid #ddd;margin:0.5em 0}"
           "figure{display:inline-block;margin:4px;text-align:center;font-size:12px}"
           "img.thumb{display:block;border:1px solid #ccc}"
           ".missing{width:240px;height:60px;background:#eee}"
           "pre{background:#f7f7f7;padding:1em;overflow:auto;font-size:12px}"
           "</style></head><body><h1>");
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

static bool workload_key(const char *k)
{
    return !strncmp(k, "scene.", 6) || !strcmp(k, "frames") || !strcmp(k, "warmup_frames");
}

/* "key=value, ..." of the values that pass keep(key), in their order. */
static void values_text(const json_t *values, bool (*keep)(const char *key, const char *skip),
                        const char *skip, char *out, size_t cap)
{
    out[0] = '\0';
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)values, k, v) {
        if (!keep(k, skip))
            continue;
        char *t = json_dumps(v, JSON_ENCODE_ANY);
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s=%s", used ? ", " : "", k, t ? t : "?");
        free(t);
    }
}

static bool keep_workload(const char *k, const char *skip)
{
    return workload_key(k) && (!skip || strcmp(k, skip) != 0);
}

static bool keep_variant(const char *k, const char *skip)
{
    return !workload_key(k) && strcmp(k, "technique") != 0 && (!skip || strcmp(k, skip) != 0);
}

static double row_ms(const json_t *row, const char *series)
{
    json_t *m = json_object_get(json_object_get(row, series), RK_MEDIAN);
    return json_is_number(m) ? json_number_value(m) : NAN;
}

/* Adds crossovers between two curves {"name", "workload", "flat", "xs",
 * "ys"} to list. A flat curve (the reference, timed once per workload)
 * holds its value at every x of the other. */
static void cross(const json_t *a, const json_t *b, const char *param, json_t *list)
{
    json_t *xa = json_object_get(a, "xs"), *ya = json_object_get(a, "ys");
    json_t *xb = json_object_get(b, "xs"), *yb = json_object_get(b, "ys");
    bool fa = json_is_true(json_object_get(a, "flat")), fb = json_is_true(json_object_get(b, "flat"));
    if (fa && fb)
        return;
    const json_t *xs = fa ? xb : xa;
    size_t n = json_array_size(xs);
    double *x = malloc((n + 1) * sizeof(double)), *d = malloc((n + 1) * sizeof(double));
    size_t k = 0;
    for (size_t i = 0; x && d && i < n; i++) {
        double xv = json_number_value(json_array_get(xs, i));
        double va = NAN, vb = NAN;
        for (size_t j = 0; j < json_array_size(xa); j++)
            if (fa || json_number_value(json_array_get(xa, j)) == xv)
                va = json_number_value(json_array_get(ya, j));
        for (size_t j = 0; j < json_array_size(xb); j++)
            if (fb || json_number_value(json_array_get(xb, j)) == xv)
                vb = json_number_value(json_array_get(yb, j));
        if (isnan(va) || isnan(vb))
            continue;
        /* Insert sorted by x. */
        size_t at = k;
        while (at > 0 && x[at - 1] > xv) {
            x[at] = x[at - 1];
            d[at] = d[at - 1];
            at--;
        }
        x[at] = xv;
        d[at] = va - vb;
        k++;
    }
    for (size_t i = 0; i + 1 < k; i++) {
        if (!(d[i] * d[i + 1] < 0))
            continue;
        double at = x[i] + (x[i + 1] - x[i]) * d[i] / (d[i] - d[i + 1]);
        /* Below the crossing, the curve with the smaller time is faster. */
        const json_t *below = d[i] < 0 ? a : b, *above = d[i] < 0 ? b : a;
        json_array_append_new(list, json_pack("{s:O, s:O, s:s, s:[f, f], s:f, s:O}", "faster_below",
                                              json_object_get(below, "name"), "faster_above",
                                              json_object_get(above, "name"), "param", param,
                                              "between", x[i], x[i + 1], "at", at, RK_WORKLOAD,
                                              json_object_get(a, RK_WORKLOAD)));
    }
    free(x);
    free(d);
}

json_t *report_sweep_verdict(const json_t *sweep, const char *series)
{
    json_t *v = json_pack("{s:s}", "series", series);
    json_t *result = json_object_get(sweep, RK_RESULT);
    static const char *const copied[] = {"largest_pdiff_pass", "breaking_point"};
    for (int i = 0; i < 2; i++)
        if (json_object_get(result, copied[i]))
            json_object_set(v, copied[i], json_object_get(result, copied[i]));
    const json_t *base = json_object_get(json_object_get(sweep, "spec"), "base");
    const char *ref = json_string_value(json_object_get(base, "reference"));
    ref = ref ? ref : "forward";
    json_t *points = json_object_get(sweep, "points");
    /* The first numeric parameter of the grid. */
    const char *param = NULL;
    size_t i;
    json_t *row;
    json_array_foreach(points, i, row) {
        const char *k;
        json_t *val;
        json_object_foreach(json_object_get(row, "values"), k, val) if (!param && json_is_number(val))
            param = k;
    }
    /* Curves: one per technique and per value of the other parameters. */
    json_t *curves = json_object();
    json_t *by_workload = json_object();
    char name[160], wl[160], key[400];
    json_array_foreach(points, i, row) {
        double ms = row_ms(row, series);
        const char *tech = json_string_value(json_object_get(row, "technique"));
        json_t *values = json_object_get(row, "values");
        if (isnan(ms) || !tech)
            continue;
        bool is_ref = !strcmp(tech, ref);
        /* Per workload: the reference against the fastest points. */
        values_text(values, keep_workload, NULL, wl, sizeof(wl));
        json_t *w = json_object_get(by_workload, wl);
        if (!w) {
            w = json_pack("{s:s, s:s}", RK_WORKLOAD, wl, "reference", ref);
            json_object_set_new(by_workload, wl, w);
        }
        if (is_ref) {
            json_object_set_new(w, RK_REFERENCE_MS, json_real(ms));
        } else {
            json_t *pt = json_pack("{s:s, s:O, s:f}", "technique", tech, "values", values, "ms", ms);
            json_t *fastest = json_object_get(w, "fastest");
            if (!fastest || ms < json_number_value(json_object_get(fastest, "ms")))
                json_object_set(w, "fastest", pt);
            json_t *pf = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
            json_t *fp = json_object_get(w, "fastest_passing");
            if (json_is_integer(pf) && json_integer_value(pf) == 0 &&
                (!fp || ms < json_number_value(json_object_get(fp, "ms"))))
                json_object_set(w, "fastest_passing", pt);
            json_decref(pt);
        }
        if (!param)
            continue;
        json_t *pv = json_object_get(values, param);
        if (pv && !json_is_number(pv))
            continue;
        values_text(values, keep_workload, param, wl, sizeof(wl));
        values_text(values, keep_variant, param, name, sizeof(name));
        char full[200];
        snprintf(full, sizeof(full), "%s%s%s%s", tech, is_ref ? " (reference)" : "",
                 name[0] ? " " : "", name);
        snprintf(key, sizeof(key), "%s|%s", full, wl);
        json_t *c = json_object_get(curves, key);
        if (!c) {
            c = json_pack("{s:s, s:s, s:b, s:[], s:[]}", "name", full, RK_WORKLOAD, wl, "flat",
                          pv == NULL, "xs", "ys");
            json_object_set_new(curves, key, c);
        }
        json_array_append_new(json_object_get(c, "xs"), json_real(pv ? json_number_value(pv) : 0));
        json_array_append_new(json_object_get(c, "ys"), json_real(ms));
    }
    json_t *crossovers = json_array();
    const char *ka, *kb;
    json_t *a, *b;
    json_object_foreach(curves, ka, a) {
        bool after = false;
        json_object_foreach(curves, kb, b) {
            if (!strcmp(ka, kb)) {
                after = true;
                continue;
            }
            if (after && !strcmp(json_string_value(json_object_get(a, RK_WORKLOAD)),
                                 json_string_value(json_object_get(b, RK_WORKLOAD))))
                cross(a, b, param, crossovers);
        }
    }
    json_object_set_new(v, "crossovers", crossovers);
    json_t *against = json_array();
    const char *k;
    json_t *w;
    json_object_foreach(by_workload, k, w) {
        json_t *rm = json_object_get(w, RK_REFERENCE_MS);
        static const char *const which[] = {"fastest", "fastest_passing"};
        for (int j = 0; j < 2 && rm; j++) {
            json_t *pt = json_object_get(w, which[j]);
            if (pt)
                json_object_set_new(pt, "ratio", json_real(json_number_value(json_object_get(pt, "ms")) /
                                                           json_number_value(rm)));
        }
        json_array_append(against, w);
    }
    json_object_set_new(v, "against_reference", against);
    json_decref(curves);
    json_decref(by_workload);
    return v;
}

static void verdict_html(struct html *h, const json_t *v)
{
    add(h, "<h2>Verdict</h2><ul class=\"verdict\">");
    json_t *lp = json_object_get(v, "largest_pdiff_pass");
    if (lp) {
        char *val = json_dumps(json_object_get(lp, "value"), JSON_ENCODE_ANY);
        add(h, "<li>Largest <b>");
        escaped(h, str(lp, "param"));
        add(h, "</b> whose captures all pass PerceptualDiff: <b>%s</b>.</li>",
            json_is_null(json_object_get(lp, "value")) ? "none passes" : (val ? val : "?"));
        free(val);
    }
    json_t *bp = json_object_get(v, "breaking_point");
    if (bp) {
        char *val = json_dumps(json_object_get(bp, "value"), JSON_ENCODE_ANY);
        add(h, "<li>Breaking point: the largest <b>");
        escaped(h, str(bp, "param"));
        add(h, "</b> at which <b>");
        escaped(h, str(bp, "criterion"));
        add(h, "</b> still holds: <b>%s</b> (%s, after %lld probes).</li>", val ? val : "?",
            str(bp, "outcome"), (long long)json_integer_value(json_object_get(bp, "probes")));
        free(val);
    }
    size_t i;
    json_t *c;
    json_array_foreach(json_object_get(v, "crossovers"), i, c) {
        add(h, "<li>Crossover on %s: <b>", str(v, "series"));
        escaped(h, str(c, "faster_below"));
        add(h, "</b> is faster below <b>");
        escaped(h, str(c, "param"));
        json_t *bt = json_object_get(c, "between");
        add(h, " &asymp; %.4g</b> (between %.4g and %.4g), <b>",
            json_number_value(json_object_get(c, "at")), json_number_value(json_array_get(bt, 0)),
            json_number_value(json_array_get(bt, 1)));
        escaped(h, str(c, "faster_above"));
        add(h, "</b> above it");
        if (str(c, RK_WORKLOAD)[0]) {
            add(h, " (");
            escaped(h, str(c, RK_WORKLOAD));
            add(h, ")");
        }
        add(h, ".</li>");
    }
    if (!json_array_size(json_object_get(v, "crossovers")))
        add(h, "<li>No crossover: along the first swept parameter no technique overtakes "
               "another on the same workload.</li>");
    json_t *w;
    json_array_foreach(json_object_get(v, "against_reference"), i, w) {
        json_t *rm = json_object_get(w, RK_REFERENCE_MS);
        if (!rm)
            continue;
        add(h, "<li>");
        if (str(w, RK_WORKLOAD)[0]) {
            escaped(h, str(w, RK_WORKLOAD));
            add(h, ": ");
        }
        escaped(h, str(w, "reference"));
        add(h, " (the reference) takes %.3f ms", json_number_value(rm));
        static const char *const which[][2] = {{"fastest", "the fastest point"},
                                               {"fastest_passing", "the fastest passing PerceptualDiff"}};
        for (int k = 0; k < 2; k++) {
            json_t *pt = json_object_get(w, which[k][0]);
            if (!pt)
                continue;
            char *vals = json_dumps(json_object_get(pt, "values"), JSON_COMPACT);
            add(h, "; %s is ", which[k][1]);
            escaped(h, str(pt, "technique"));
            add(h, " ");
            escaped(h, vals);
            add(h, " at %.3f ms (<b>%.2f&times;</b> the reference)",
                json_number_value(json_object_get(pt, "ms")),
                json_number_value(json_object_get(pt, "ratio")));
            free(vals);
        }
        if (!json_object_get(w, "fastest_passing"))
            add(h, "; no point passes PerceptualDiff");
        add(h, ".</li>");
    }
    add(h, "</ul>");
}

/* The thesis's chapter 4 for this device: execution time of the timed
 * frames per scene and technique (mean, median, standard deviation over the
 * runs), the factor between the two techniques, PerceptualDiff at 22.6
 * degrees and the SSIM range. */
static void thesis_tables(struct html *h, const json_t *points)
{
    add(h, "<h2>The thesis's experiment on this device (its chapter 4)</h2>"
           "<table><tr><th class=\"l\">scene</th><th class=\"l\">technique</th><th>runs</th>"
           "<th>mean execution time (s)</th><th>median (s)</th><th>standard deviation</th>"
           "<th>OSL / forward</th><th>PerceptualDiff (22.6&deg;)</th><th>worst SSIM</th></tr>");
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
                dynamic ? "moving" : "still", t ? "OSL (256, async 20)" : "forward",
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

char *report_sweep_html(const json_t *sweep, const json_t *device, report_job_dir_fn job_dir,
                        void *ctx, size_t *len)
{
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
    json_t *verdict = report_sweep_verdict(sweep, series);
    verdict_html(&h, verdict);
    json_decref(verdict);
    json_t *points = json_object_get(sweep, "points");
    if (strcmp(str(sweep, "preset"), "thesis") == 0)
        thesis_tables(&h, points);
    const char *reference = json_string_value(
        json_object_get(json_object_get(json_object_get(sweep, "spec"), "base"), "reference"));
    reference = reference ? reference : "forward";
    add(&h, "<h2>Table</h2><table><tr><th class=\"l\">parameters</th><th class=\"l\">technique</th>"
            "<th class=\"l\">job</th><th>frame_ms median [95%%]</th><th>gpu_ms median [95%%]</th>"
            "<th>worst SSIM</th><th>worst FLIP</th><th>PerceptualDiff failures</th></tr>");
    size_t i;
    json_t *row;
    json_array_foreach(points, i, row) {
        char *values = json_dumps(json_object_get(row, "values"), JSON_COMPACT);
        add(&h, "<tr><td class=\"l\">");
        escaped(&h, values);
        add(&h, "</td><td class=\"l\">");
        escaped(&h, str(row, "technique"));
        add(&h, "</td><td class=\"l\">");
        escaped(&h, str(row, "job"));
        add(&h, " (%s)%s</td>", str(row, "status"),
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
        add(&h, "</tr>");
    }
    add(&h, "</table><p>Intervals are 95%%; a lower end below zero is shown as 0 (times are "
            "never negative).</p><h2>Charts</h2>");
    struct chart_options o = {.device = device};
    chart(&h, sweep, "speed_accuracy", true, &o, "speed against accuracy (SSIM)");
    o.flip = true;
    chart(&h, sweep, "speed_accuracy", true, &o, "speed against accuracy (FLIP)");
    o.flip = false;
    chart(&h, sweep, "time_vs_param", true, &o, "frame time against the parameter");
    chart(&h, sweep, "distribution", true, &o, "frame-time distributions");

    add(&h, "<h2>Captures</h2><p>Last capture of each point: the frame, the reference, "
            "the SSIM map and the FLIP map%s.</p>",
        json_array_size(points) > THUMB_POINTS ? " (the first 64 points)" : "");
    json_array_foreach(points, i, row) {
        if (i >= THUMB_POINTS)
            break;
        char dir[PATH_MAX];
        int frame = 0;
        if (!job_dir || !job_dir(ctx, str(row, "job"), dir, sizeof(dir), &frame) || frame <= 0)
            continue;
        char *values = json_dumps(json_object_get(row, "values"), JSON_COMPACT);
        add(&h, "<div><h3>");
        escaped(&h, str(row, "technique"));
        add(&h, " ");
        escaped(&h, values);
        add(&h, "</h3>");
        free(values);
        thumbnail(&h, dir, JOB_IMAGE_FRAME, frame, "frame");
        thumbnail(&h, dir, JOB_IMAGE_REFERENCE, frame, "reference");
        thumbnail(&h, dir, JOB_IMAGE_SSIM, frame, "SSIM map");
        thumbnail(&h, dir, JOB_IMAGE_FLIP, frame, "FLIP map");
        add(&h, "</div>");
    }
    add(&h, "<h2>The sweep as posted</h2>");
    json_block(&h, json_object_get(sweep, "spec"));
    add(&h, "</body></html>\n");
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
        char *text = json_is_string(v) ? NULL : json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT);
        add(h, "<tr><td class=\"l\">");
        escaped(h, key);
        add(h, "</td><td class=\"l\">");
        escaped(h, json_is_string(v) ? json_string_value(v) : text);
        add(h, "</td></tr>");
        free(text);
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
            add(&h, "<h2>Quality against %s</h2><p>Worst SSIM %.6f, worst FLIP mean %.5f, "
                    "PerceptualDiff failed on %lld of %lld captures.</p>",
                str(q, "reference"),
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
            add(&h, "</h3>");
            thumbnail(&h, dir, JOB_IMAGE_FRAME, frame, "frame");
            if (m) {
                thumbnail(&h, dir, JOB_IMAGE_REFERENCE, frame, "reference");
                thumbnail(&h, dir, JOB_IMAGE_SSIM, frame, "SSIM map");
                thumbnail(&h, dir, JOB_IMAGE_FLIP, frame, "FLIP map");
            }
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
