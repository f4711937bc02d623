/* Charts that cannot mislead, checked on the layout each SVG carries: a
 * Pareto front never joins points of different workloads, the reference is
 * a point of its own at exact quality, intervals never go below zero, labels
 * never overlap, a log axis where values span decades, the series chosen
 * for the device and said so; and the verdict a sweep's report writes
 * (crossovers, the reference against the fastest points). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/api/charts.h"
#include "daemon/api/report.h"
#include "tests/unit/check.h"

static json_t *row(const char *tech, double lights, double async, double ms, double lo, double hi,
                   double ssim, int pdiff_failed)
{
    json_t *values = json_pack("{s:f}", "scene.lights", lights);
    if (!strcmp(tech, "forward"))
        json_object_set_new(values, "technique", json_string("forward"));
    else
        json_object_set_new(values, "async_distance", json_real(async));
    json_t *cell = json_pack("{s:f, s:[f, f], s:f, s:f, s:f, s:f, s:f}", "median", ms, "ci95", lo,
                             hi, "min", ms * 0.9, "p5", ms * 0.95, "p95", ms * 1.1, "p99",
                             ms * 1.2, "max", ms * 1.3);
    json_t *r = json_pack("{s:o, s:s, s:s, s:s, s:o, s:O, s:O}", "values", values, "technique", tech,
                          "job", "j", "status", "done", "frame_ms", cell, "gpu_ms", cell,
                          "cpu_ms", cell);
    if (ssim >= 0) {
        json_object_set_new(r, "worst_ssim", json_real(ssim));
        json_object_set_new(r, "worst_flip", json_real(1 - ssim));
        json_object_set_new(r, "pdiff_failed_captures", json_integer(pdiff_failed));
    }
    return r;
}

/* The layout JSON inside the SVG's <metadata>. */
static json_t *layout(const char *svg, size_t len)
{
    const char *open = strstr(svg, "<metadata id=\"shadebench-chart\">");
    const char *close = open ? strstr(open, "</metadata>") : NULL;
    if (!open || !close || (size_t)(close - svg) > len)
        return NULL;
    open += strlen("<metadata id=\"shadebench-chart\">");
    char *text = strndup(open, (size_t)(close - open));
    /* Undo the XML escapes. */
    char *w = text;
    for (const char *p = text; *p;) {
        if (!strncmp(p, "&lt;", 4))
            *w++ = '<', p += 4;
        else if (!strncmp(p, "&gt;", 4))
            *w++ = '>', p += 4;
        else if (!strncmp(p, "&amp;", 5))
            *w++ = '&', p += 5;
        else
            *w++ = *p++;
    }
    *w = '\0';
    json_t *j = json_loads(text, 0, NULL);
    free(text);
    return j;
}

static json_t *chart(const json_t *sweep, const char *name, const struct chart_options *o)
{
    char err[256];
    size_t len = 0;
    char *svg = charts_sweep(sweep, name, CHART_SVG, o, &len, err, sizeof(err));
    CHECK(svg != NULL);
    json_t *l = svg ? layout(svg, len) : NULL;
    CHECK(l != NULL);
    free(svg);
    return l;
}

int main(void)
{
    /* Two workloads (2 and 40 lights); on 40 lights OSL is faster than
     * forward, on 2 it is slower; one interval reaches below zero. */
    json_t *points = json_array();
    json_array_append_new(points, row("osl", 2, 0, 30, 28, 32, 0.9999, 0));
    json_array_append_new(points, row("osl", 2, 5, 12, -3, 27, 0.996, 2));
    json_array_append_new(points, row("osl", 40, 0, 31, 29, 33, 0.9999, 0));
    json_array_append_new(points, row("osl", 40, 5, 13, 12, 14, 0.996, 2));
    json_array_append_new(points, row("forward", 2, 0, 20, 19, 21, -1, 0));
    json_array_append_new(points, row("forward", 40, 0, 400, 380, 420, -1, 0));
    json_t *sweep = json_pack("{s:s, s:s, s:{s:{s:s}}, s:O, s:{s:{s:s, s:i}}}", "id", "s1", "kind",
                              "vary", "spec", "base", "technique", "osl", "points", points,
                              "result", "largest_pdiff_pass", "param", "async_distance", "value",
                              0);
    json_t *llvmpipe = json_pack("{s:s}", "gl_renderer", "llvmpipe (LLVM 15.0.6, 256 bits)");
    json_t *gpu = json_pack("{s:s}", "gl_renderer", "NVIDIA GeForce RTX 3070/PCIe/SSE2");
    struct chart_options o = {.device = llvmpipe};

    json_t *l = chart(sweep, "speed_accuracy", &o);
    json_t *pts = json_object_get(l, "points");
    CHECK(json_array_size(pts) == 6);
    /* Fronts: each within one workload; here each workload has its own. */
    json_t *fronts = json_object_get(l, "fronts");
    CHECK(json_array_size(fronts) == 2 && json_array_size(json_object_get(l, "workloads")) == 2);
    size_t i, k;
    json_t *front, *member;
    json_array_foreach(fronts, i, front) {
        CHECK(json_array_size(front) >= 1);
        json_array_foreach(front, k, member) {
            json_t *p = json_array_get(pts, (size_t)json_integer_value(member));
            CHECK(json_integer_value(json_object_get(p, "workload")) == (json_int_t)i);
        }
    }
    /* A global front would have dropped the 40-light OSL points (the
     * 2-light ones are as accurate and faster): per workload they stay. */
    json_t *p2 = json_array_get(pts, 2), *p3 = json_array_get(pts, 3);
    CHECK(json_is_true(json_object_get(p2, "pareto")) && json_is_true(json_object_get(p3, "pareto")));
    /* The reference: its own point, at SSIM 1, on its workload's front. */
    json_t *ref = json_array_get(pts, 4);
    CHECK(json_is_true(json_object_get(ref, "reference")) &&
          json_real_value(json_object_get(ref, "y")) == 1.0 &&
          !strcmp(json_string_value(json_object_get(ref, "series")), "forward (reference)"));
    CHECK(json_is_true(json_object_get(json_array_get(pts, 5), "pareto")));
    CHECK(json_is_false(json_object_get(json_array_get(pts, 0), "pareto"))); /* forward beats it */
    /* No interval below zero: the one that reached -3 is cut and marked. */
    json_t *p;
    json_array_foreach(pts, i, p) CHECK(json_real_value(json_object_get(p, "x_lo")) >= 0);
    CHECK(json_is_true(json_object_get(json_array_get(pts, 1), "lo_clamped")));
    /* Frame times from 12 to 420 ms span decades: a log axis. */
    CHECK(json_is_true(json_object_get(l, "x_log")));
    /* Labels: placed where they overlap nothing, or left out and counted. */
    int placed = 0;
    json_array_foreach(pts, i, p) {
        json_t *a = json_object_get(p, "label_box");
        if (json_is_null(a))
            continue;
        placed++;
        json_t *q;
        json_array_foreach(pts, k, q) {
            json_t *b = json_object_get(q, "label_box");
            if (k <= i || json_is_null(b))
                continue;
            double ax = json_real_value(json_array_get(a, 0)), ay = json_real_value(json_array_get(a, 1));
            double aw = json_real_value(json_array_get(a, 2)), ah = json_real_value(json_array_get(a, 3));
            double bx = json_real_value(json_array_get(b, 0)), by = json_real_value(json_array_get(b, 1));
            double bw = json_real_value(json_array_get(b, 2)), bh = json_real_value(json_array_get(b, 3));
            CHECK(!(ax < bx + bw && bx < ax + aw && ay < by + bh && by < ay + ah));
        }
    }
    CHECK(placed + json_integer_value(json_object_get(l, "labels_left_out")) == 6 && placed >= 4);
    /* The series: frame_ms on llvmpipe, and the chart says why. */
    CHECK(strstr(json_string_value(json_object_get(l, "xlabel")), "frame_ms") &&
          strstr(json_string_value(json_object_get(l, "subtitle")), "llvmpipe"));
    json_decref(l);
    o.device = gpu;
    l = chart(sweep, "speed_accuracy", &o);
    CHECK(strstr(json_string_value(json_object_get(l, "xlabel")), "gpu_ms"));
    json_decref(l);
    o.device = llvmpipe;
    o.flip = true; /* FLIP: the reference at 0 */
    l = chart(sweep, "speed_accuracy", &o);
    CHECK(json_real_value(json_object_get(json_array_get(json_object_get(l, "points"), 4), "y")) == 0.0);
    json_decref(l);
    o.flip = false;

    /* time_vs_param over lights: forward is a line of its own; the time
     * axis is logarithmic. */
    l = chart(sweep, "time_vs_param", &o);
    CHECK(json_array_size(json_object_get(l, "points")) == 6 && json_is_true(json_object_get(l, "y_log")));
    json_array_foreach(json_object_get(l, "points"), i, p)
        CHECK(json_real_value(json_object_get(p, "y_lo")) >= 0);
    json_decref(l);
    l = chart(sweep, "distribution", &o);
    CHECK(json_array_size(json_object_get(l, "points")) == 6);
    json_decref(l);
    char err[256];
    size_t len;
    CHECK(charts_sweep(sweep, "pie", CHART_SVG, &o, &len, err, sizeof(err)) == NULL &&
          strstr(err, "no chart named pie"));
    /* PNG too. */
    char *png = charts_sweep(sweep, "speed_accuracy", CHART_PNG, &o, &len, err, sizeof(err));
    CHECK(png && len > 1000 && !memcmp(png, "\x89PNG", 4));
    free(png);

    /* The verdict: on 2 lights forward (20 ms) beats OSL at d 0 (30 ms);
     * on 40 lights OSL wins. Along lights, OSL at d 0 and forward cross
     * between 2 and 40. */
    json_t *v = report_sweep_verdict(sweep, "frame_ms");
    json_t *cr = json_object_get(v, "crossovers");
    int found = 0;
    json_t *c;
    json_array_foreach(cr, i, c) {
        const char *below = json_string_value(json_object_get(c, "faster_below"));
        const char *above = json_string_value(json_object_get(c, "faster_above"));
        if (strstr(below, "forward") && strstr(above, "osl async_distance=0")) {
            found++;
            double at = json_real_value(json_object_get(c, "at"));
            /* forward - osl: -10 at 2, +369 at 40: zero at 2 + 38 * 10/379. */
            CHECK(fabs(at - (2 + 38.0 * 10 / 379)) < 1e-6);
            CHECK(!strcmp(json_string_value(json_object_get(c, "param")), "scene.lights"));
        }
    }
    CHECK(found == 1);
    json_t *against = json_object_get(v, "against_reference");
    CHECK(json_array_size(against) == 2);
    json_array_foreach(against, i, c) {
        double rm = json_real_value(json_object_get(c, "reference_ms"));
        json_t *fp = json_object_get(c, "fastest_passing");
        CHECK(fp && !strcmp(json_string_value(json_object_get(fp, "technique")), "osl"));
        CHECK(fabs(json_real_value(json_object_get(fp, "ratio")) -
                   json_real_value(json_object_get(fp, "ms")) / rm) < 1e-12);
    }
    CHECK(json_object_get(v, "largest_pdiff_pass") != NULL);
    json_decref(v);

    /* The report writes the verdict out. */
    size_t hl = 0;
    char *html = report_sweep_html(sweep, llvmpipe, NULL, NULL, &hl);
    CHECK(html && strstr(html, "<h2>Verdict</h2>") && strstr(html, "Crossover") &&
          strstr(html, "the reference) takes") && strstr(html, "reference, timed"));
    CHECK(html && !strstr(html, "[-3.000"));
    free(html);

    /* A job's timeline from its samples. */
    json_t *job = json_pack("{s:s, s:s, s:{s:{s:f}, s:O}}", "id", "j1", "technique", "forward",
                            "result", "frame_ms", "median", 10.0, "device", llvmpipe);
    json_t *samples = json_pack("{s:[f, f, f, f]}", "frame_ms", 9.0, 10.0, 11.0, 10.0);
    char *svg = charts_job_timeline(job, samples, CHART_SVG, &(struct chart_options){0}, &len, err,
                                    sizeof(err));
    json_t *tl = svg ? layout(svg, len) : NULL;
    CHECK(tl && json_array_size(json_object_get(tl, "points")) == 4 &&
          json_array_size(json_object_get(tl, "levels")) == 1);
    json_decref(tl);
    free(svg);
    json_decref(samples);
    samples = json_object();
    CHECK(!charts_job_timeline(job, samples, CHART_SVG, &(struct chart_options){0}, &len, err,
                               sizeof(err)));
    json_decref(samples);
    json_decref(job);

    json_decref(sweep);
    json_decref(points);
    json_decref(llvmpipe);
    json_decref(gpu);
    return check_finish("test_charts");
}
