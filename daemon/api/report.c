#define _POSIX_C_SOURCE 200809L
#include "daemon/api/report.h"

#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "daemon/api/charts.h"
#include "common/png_io.h"

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
static void thumbnail(struct html *h, const char *dir, const char *prefix, int frame,
                      const char *caption)
{
    char path[PATH_MAX + 64], err[256];
    snprintf(path, sizeof(path), "%s/%s-%06d.png", dir, prefix, frame);
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
    json_t *ci = json_object_get(cell, "ci95");
    if (!json_is_number(json_object_get(cell, "median"))) {
        add(h, "<td>-</td>");
        return;
    }
    if (json_array_size(ci) == 2)
        add(h, "<td>%.3f [%.3f, %.3f]</td>", json_number_value(json_object_get(cell, "median")),
            json_number_value(json_array_get(ci, 0)), json_number_value(json_array_get(ci, 1)));
    else
        add(h, "<td>%.3f</td>", json_number_value(json_object_get(cell, "median")));
}

static void num_cell(struct html *h, const json_t *v, const char *fmt)
{
    if (json_is_number(v))
        add(h, fmt, json_number_value(v));
    else
        add(h, "<td>-</td>");
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
        double fwd = json_number_value(json_object_get(json_object_get(rows[0], "wall_s"), "mean"));
        for (int t = 0; t < 2; t++) {
            const json_t *r = rows[t];
            if (!r)
                continue;
            json_t *wall = json_object_get(r, "wall_s");
            double mean = json_number_value(json_object_get(wall, "mean"));
            add(h, "<tr><td class=\"l\">%s lights</td><td class=\"l\">%s</td><td>%lld</td>"
                   "<td>%.3f</td><td>%.3f</td><td>%.3f</td>",
                dynamic ? "moving" : "still", t ? "OSL (256, async 20)" : "forward",
                (long long)json_integer_value(json_object_get(wall, "runs")), mean,
                json_number_value(json_object_get(wall, "median")),
                json_number_value(json_object_get(wall, "stddev")));
            if (t && fwd > 0)
                add(h, "<td>%.2f</td>", mean / fwd);
            else
                add(h, "<td></td>");
            json_t *pf = json_object_get(r, "pdiff_failed_captures");
            add(h, "<td class=\"%s\">%s</td>", json_integer_value(pf) ? "fail" : "pass",
                json_integer_value(pf) ? "fail" : "pass");
            num_cell(h, json_object_get(r, "worst_ssim"), "<td>%.5f</td>");
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
    json_t *bp = json_object_get(json_object_get(sweep, "result"), "breaking_point");
    if (bp) {
        char *v = json_dumps(json_object_get(bp, "value"), JSON_ENCODE_ANY);
        add(&h, "<h2>Breaking point</h2><p>The largest <b>");
        escaped(&h, str(bp, "param"));
        add(&h, "</b> at which <b>");
        escaped(&h, str(bp, "criterion"));
        add(&h, "</b> still holds: <b>%s</b> (%s, after %lld probes).</p>", v ? v : "?",
            str(bp, "outcome"), (long long)json_integer_value(json_object_get(bp, "probes")));
        free(v);
    }
    json_t *points = json_object_get(sweep, "points");
    if (strcmp(str(sweep, "preset"), "thesis") == 0)
        thesis_tables(&h, points);
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
        add(&h, " (%s)</td>", str(row, "status"));
        free(values);
        ms_cell(&h, json_object_get(row, "frame_ms"));
        ms_cell(&h, json_object_get(row, "gpu_ms"));
        num_cell(&h, json_object_get(row, "worst_ssim"), "<td>%.6f</td>");
        num_cell(&h, json_object_get(row, "worst_flip"), "<td>%.5f</td>");
        json_t *pf = json_object_get(row, "pdiff_failed_captures");
        if (json_is_integer(pf))
            add(&h, "<td class=\"%s\">%lld</td>", json_integer_value(pf) ? "fail" : "pass",
                (long long)json_integer_value(pf));
        else
            add(&h, "<td>-</td>");
        add(&h, "</tr>");
    }
    add(&h, "</table><h2>Charts</h2>");
    struct chart_options o = {0};
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
        thumbnail(&h, dir, "frame", frame, "frame");
        thumbnail(&h, dir, "reference", frame, "reference");
        thumbnail(&h, dir, "ssim", frame, "SSIM map");
        thumbnail(&h, dir, "flip", frame, "FLIP map");
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
    static const char *const keys[] = {"mean", "median", "stddev", "min", "p5", "p95", "p99", "max", "cv"};
    for (size_t k = 0; k < sizeof(keys) / sizeof(keys[0]); k++)
        num_cell(h, json_object_get(s, keys[k]), "<td>%.4f</td>");
    add(h, "</tr>");
}

char *report_job_html(const json_t *job, const char *dir, const json_t *device, size_t *len)
{
    struct html h = {0};
    char title[128];
    snprintf(title, sizeof(title), "shadebench job %s (%s)", str(job, "id"), str(job, "technique"));
    head(&h, title, device);
    json_t *r = json_object_get(job, "result");
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
            json_number_value(json_object_get(r, "wall_s")), json_number_value(json_object_get(r, "fps")),
            (long long)json_integer_value(json_object_get(r, "triangles_per_frame")));
        add(&h, "<table><tr><th class=\"l\">ms</th><th>mean</th><th>median</th><th>stddev</th>"
                "<th>min</th><th>p5</th><th>p95</th><th>p99</th><th>max</th><th>cv</th></tr>");
        stats_row(&h, "frame_ms", json_object_get(r, "frame_ms"));
        stats_row(&h, "gpu_ms", json_object_get(r, "gpu_ms"));
        stats_row(&h, "cpu_ms", json_object_get(r, "cpu_ms"));
        add(&h, "</table>");
        struct chart_options o = {0};
        chart(&h, job, "distribution", false, &o, "frame-time distribution");
        json_t *q = json_object_get(r, "quality");
        if (q) {
            add(&h, "<h2>Quality against %s</h2><p>Worst SSIM %.6f, worst FLIP mean %.5f, "
                    "PerceptualDiff failed on %lld of %lld captures.</p>",
                str(q, "reference"),
                json_number_value(json_object_get(json_object_get(q, "worst_ssim"), "value")),
                json_number_value(json_object_get(json_object_get(q, "worst_flip"), "mean")),
                (long long)json_integer_value(json_object_get(q, "pdiff_failed_captures")),
                (long long)json_integer_value(json_object_get(q, "captures_compared")));
        }
        add(&h, "<h2>Captures</h2>");
        size_t i;
        json_t *c;
        json_array_foreach(json_object_get(r, "captures"), i, c) {
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
            thumbnail(&h, dir, "frame", frame, "frame");
            if (m) {
                thumbnail(&h, dir, "reference", frame, "reference");
                thumbnail(&h, dir, "ssim", frame, "SSIM map");
                thumbnail(&h, dir, "flip", frame, "FLIP map");
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
