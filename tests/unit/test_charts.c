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

#include "daemon/reports/charts.h"
#include "daemon/reports/report.h"
#include "daemon/reports/sweep_verdict.h"
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

/* A row from its values (JSON text), a time with interval, quality (ssim
 * < 0: not judged) and a status. */
static json_t *trow(const char *tech, const char *values, double ms, double lo, double hi,
                    double ssim, int pdiff_failed, const char *status)
{
    json_t *r = json_pack("{s:o, s:s, s:s, s:s}", "values", json_loads(values, 0, NULL),
                          "technique", tech, "job", "j", "status", status);
    if (!strcmp(status, "done")) {
        json_t *cell = json_pack("{s:f, s:[f, f], s:f, s:f, s:f, s:f, s:f}", "median", ms, "ci95",
                                 lo, hi, "min", ms * 0.9, "p5", ms * 0.95, "p95", ms * 1.1, "p99",
                                 ms * 1.2, "max", ms * 1.3);
        json_object_set(r, "frame_ms", cell);
        json_object_set(r, "gpu_ms", cell);
        json_object_set_new(r, "cpu_ms", cell);
    }
    if (ssim >= 0) {
        json_object_set_new(r, "worst_ssim", json_real(ssim));
        json_object_set_new(r, "worst_flip", json_real((1 - ssim) * 10));
        json_object_set_new(r, "pdiff_failed_captures", json_integer(pdiff_failed));
    }
    return r;
}

static json_t *tsweep(json_t *points, const char *status, int total, const char *largest_param)
{
    json_t *sw = json_pack("{s:s, s:s, s:s, s:{s:{s:s, s:s}}, s:o, s:{s:i, s:i}}", "id", "s2",
                           "kind", "vary", "status", status, "spec", "base", "technique", "forward",
                           "reference", "forward", "points", points, "progress", "points_done",
                           (int)json_array_size(points), "points_total", total);
    if (largest_param)
        json_object_set_new(sw, "result", json_pack("{s:{s:s, s:n}}", "largest_pdiff_pass",
                                                    "param", largest_param, "value"));
    return sw;
}

static bool point_is(const json_t *pts, size_t i, const char *key)
{
    return json_is_true(json_object_get(json_array_get(pts, i), key));
}

/* The reproducer: a sweep over techniques, every point passing
 * PerceptualDiff. Its verdict must not say "none passes" (the sweep's
 * largest value is null only because techniques are not numbers); its
 * front only separates points whose intervals do (tiled 53 [43, 60] is
 * not better than clustered deferred 56 [34, 92]); and the chart draws the
 * same front. */
static void test_technique_sweep(const json_t *llvmpipe)
{
    json_t *points = json_array();
    json_array_append_new(points, trow("tiled_deferred", "{\"technique\":\"tiled_deferred\"}", 53,
                                       43, 60, 0.99998, 0, "done"));
    json_array_append_new(points, trow("clustered_deferred",
                                       "{\"technique\":\"clustered_deferred\"}", 56, 34, 92,
                                       0.99998, 0, "done"));
    json_array_append_new(points, trow("deferred", "{\"technique\":\"deferred\"}", 140, 130,
                                       150, 0.99998, 0, "done"));
    json_array_append_new(points, trow("forward_plus", "{\"technique\":\"forward_plus\"}", 58,
                                       50, 66, 0.99997, 0, "done"));
    json_array_append_new(points, trow("forward", "{\"technique\":\"forward\"}", 150, 140, 160,
                                       -1, 0, "done"));
    json_t *sw = tsweep(points, "done", 5, "technique");
    json_t *v = sweep_verdict_json(sw, "frame_ms");
    CHECK(!json_object_get(v, "largest_pdiff_pass"));
    CHECK(json_array_size(json_object_get(v, "pdiff_passing")) == 4 &&
          json_integer_value(json_object_get(v, "pdiff_judged")) == 4);
    /* The front: tiled and clustered deferred tied (equal quality, times
     * not distinguishable); deferred dominated by them (measurably slower);
     * forward_plus overlaps both but is less accurate: dominated; forward,
     * the reference, exact and slowest: on the front. */
    json_t *front = json_object_get(json_array_get(json_object_get(v, "front"), 0), "points");
    CHECK(json_array_size(front) == 3);
    size_t i;
    json_t *m;
    int tied = 0;
    json_array_foreach(front, i, m) {
        const char *n = json_string_value(json_object_get(m, "name"));
        CHECK(strstr(n, "tiled_deferred") || strstr(n, "clustered_deferred") ||
              !strcmp(n, "forward"));
        tied += json_is_true(json_object_get(m, "tied"));
    }
    CHECK(tied == 2);
    /* The fastest is not distinguishable from its tied neighbours. */
    json_t *fastest = json_object_get(json_array_get(json_object_get(v, "against_reference"), 0),
                                      "fastest");
    CHECK(json_array_size(json_object_get(fastest, "tied_with")) == 2 &&
          json_is_true(json_object_get(fastest, "distinguishable")));
    json_decref(v);
    /* The chart draws that front: the same points, two tied. */
    struct chart_options o = {.device = llvmpipe};
    json_t *l = chart(sw, "speed_accuracy", &o);
    json_t *pts = json_object_get(l, "points");
    CHECK(json_array_size(pts) == 5);
    CHECK(point_is(pts, 0, "pareto") && point_is(pts, 0, "tied") && point_is(pts, 1, "pareto") &&
          point_is(pts, 1, "tied") && !point_is(pts, 2, "pareto") && !point_is(pts, 3, "pareto") &&
          point_is(pts, 4, "pareto") && !point_is(pts, 4, "tied"));
    /* SSIM 0.99997 to 1 on -log10(1 - SSIM): the axis starts at 0.99 or
     * below and ends above the best inexact score (exact at its top), and
     * 0.99997 and 0.99998 are apart, not squeezed into the top 2% of a
     * linear 0.99 to 1. */
    json_t *yr = json_object_get(l, "y_range");
    double ylo = json_real_value(json_array_get(yr, 0)), yhi = json_real_value(json_array_get(yr, 1));
    const char *scale = json_string_value(json_object_get(l, "y_scale"));
    CHECK(scale && strcmp(scale, "one_minus_log") == 0);
    CHECK(ylo <= 0.99 && yhi > 0.999995 && yhi < 1.0);
    double spread = (log10(1 - 0.99997) - log10(1 - 0.99998)) / (log10(1 - ylo) - log10(1 - yhi));
    CHECK(spread > 0.04);
    /* Every point is labelled, numbered with its label in the key, or the
     * only point of its series (named in the legend). */
    json_t *p, *q;
    json_array_foreach(pts, i, p) {
        size_t k, same = 0;
        json_array_foreach(pts, k, q) same += json_equal(json_object_get(p, "series"),
                                                         json_object_get(q, "series"));
        CHECK(!json_is_null(json_object_get(p, "label_box")) ||
              json_is_integer(json_object_get(p, "tag")) ||
              (!json_string_length(json_object_get(p, "label")) && same == 1));
    }
    json_decref(l);
    size_t hl = 0;
    char *html = report_sweep_html(sw, llvmpipe, NULL, NULL, &hl);
    CHECK(html && !strstr(html, "none passes") && !strstr(html, "none</b>") &&
          strstr(html, "<b>4 of 4</b> judged") && strstr(html, ", tied"));
    free(html);
    json_decref(sw);
}

/* A sweep of OSL against a reference that is faster than every point (the
 * dashboard's demo sweep: forward 10.5 ms, OSL 47 and 74): the reference
 * wins, however fast the fastest swept point is among its own. */
static void test_reference_wins(const json_t *llvmpipe)
{
    json_t *points = json_array();
    json_array_append_new(points, trow("osl", "{\"async_distance\":0}", 74, 70, 78, 0.9986, 0, "done"));
    json_array_append_new(points, trow("osl", "{\"async_distance\":20}", 47, 45, 49, 0.9984, 0, "done"));
    json_array_append_new(points, trow("forward", "{\"technique\":\"forward\"}", 10.5, 9.3, 12,
                                       -1, 0, "done"));
    json_t *sw = tsweep(points, "done", 3, "async_distance");
    json_t *v = sweep_verdict_json(sw, "frame_ms");
    json_t *w = json_array_get(json_object_get(v, "against_reference"), 0);
    json_t *win = json_object_get(w, "winner");
    CHECK(win && !strcmp(json_string_value(json_object_get(win, "technique")), "forward") &&
          json_is_true(json_object_get(win, "reference")) &&
          json_is_null(json_object_get(win, "values")));
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(w, "fastest"), "technique")),
                  "osl"));
    json_decref(v);
    size_t hl = 0;
    char *html = report_sweep_html(sw, llvmpipe, NULL, NULL, &hl);
    CHECK(html && strstr(html, "<b>forward</b> (the reference)"));
    free(html);
    json_decref(sw);
}

/* Crossovers and ratios stated only where the intervals support them. */
static void test_noise_in_verdicts(const json_t *llvmpipe)
{
    json_t *points = json_array();
    /* Along async_distance, osl and forward (timed once) cross near 14
     * by their medians, with intervals overlapping at 20. */
    json_array_append_new(points, trow("osl", "{\"async_distance\":5}", 40, 35, 45, 0.997, 1, "done"));
    json_array_append_new(points, trow("osl", "{\"async_distance\":20}", 60, 40, 90, 0.9999, 0, "done"));
    json_array_append_new(points, trow("forward", "{\"technique\":\"forward\"}", 55, 50, 60,
                                       -1, 0, "done"));
    json_t *sw = tsweep(points, "done", 3, "async_distance");
    json_t *v = sweep_verdict_json(sw, "frame_ms");
    json_t *cr = json_array_get(json_object_get(v, "crossovers"), 0);
    CHECK(json_array_size(json_object_get(v, "crossovers")) == 1 &&
          json_is_false(json_object_get(cr, "distinguishable")));
    /* The fastest passing point (d 20, 60 [40, 90]) against the reference
     * (55 [50, 60]): 1.09 by the medians, not distinguishable. */
    json_t *w = json_array_get(json_object_get(v, "against_reference"), 0);
    json_t *fp = json_object_get(w, "fastest_passing");
    CHECK(fp && json_is_false(json_object_get(fp, "distinguishable")) &&
          json_real_value(json_array_get(json_object_get(fp, "ratio_ci"), 0)) < 1 &&
          json_real_value(json_array_get(json_object_get(fp, "ratio_ci"), 1)) > 1);
    /* The fastest (d 5, 40 [35, 45]) is measurably faster: stated. */
    CHECK(json_is_true(json_object_get(json_object_get(w, "fastest"), "distinguishable")));
    /* ... and so it wins the workload, the reference included. */
    json_t *win = json_object_get(w, "winner");
    CHECK(win && !strcmp(json_string_value(json_object_get(win, "technique")), "osl") &&
          json_is_false(json_object_get(win, "reference")));
    CHECK(json_integer_value(json_object_get(json_object_get(v, "largest_pdiff_pass"), "value")) == 20);
    json_decref(v);
    /* Noisy points (the report adds each point job's interference). */
    json_object_set_new(json_array_get(points, 1), "interference",
                        json_pack("{s:f, s:b}", "other_cpu_share", 0.79, "noisy", 1));
    v = sweep_verdict_json(sw, "frame_ms");
    CHECK(json_array_size(json_object_get(v, "noisy")) == 1);
    json_decref(v);
    size_t hl = 0;
    char *html = report_sweep_html(sw, llvmpipe, NULL, NULL, &hl);
    CHECK(html && strstr(html, "not distinguishable at this noise") &&
          strstr(html, "not distinguishable from the reference at this noise") &&
          strstr(html, "<b>Noise:</b> 1 point ran") && strstr(html, "(79%)") &&
          !strstr(html, "0.10000000"));
    free(html);
    struct chart_options o = {.device = llvmpipe};
    json_t *l = chart(sw, "speed_accuracy", &o);
    json_t *pts = json_object_get(l, "points");
    CHECK(point_is(pts, 1, "noisy") && !point_is(pts, 0, "noisy"));
    /* PerceptualDiff's verdicts separate at SSIM 0.9999: the line is there. */
    CHECK(fabs(json_real_value(json_object_get(l, "jnd")) - 0.9999) < 1e-12);
    CHECK(json_is_false(json_object_get(json_array_get(pts, 0), "pdiff_pass")));
    json_decref(l);
    json_decref(sw);
}

/* A cancelled sweep says so in its verdict and its charts, and names the
 * points it could not draw. */
static void test_partial_sweep(const json_t *llvmpipe)
{
    json_t *points = json_array();
    json_array_append_new(points, trow("osl", "{\"async_distance\":0}", 30, 28, 32, 0.9999, 0, "done"));
    json_array_append_new(points, trow("osl", "{\"async_distance\":5}", 0, 0, 0, -1, 0, "cancelled"));
    json_t *sw = tsweep(points, "cancelled", 4, "async_distance");
    json_t *v = sweep_verdict_json(sw, "frame_ms");
    CHECK(json_is_true(json_object_get(v, "partial")) &&
          json_integer_value(json_object_get(v, "not_run")) == 2 &&
          json_array_size(json_object_get(v, "missing")) == 1);
    json_decref(v);
    struct chart_options o = {.device = llvmpipe};
    static const char *const names[] = {"speed_accuracy", "time_vs_param", "distribution"};
    for (int k = 0; k < 3; k++) {
        json_t *l = chart(sw, names[k], &o);
        json_t *footer = json_object_get(l, "footer");
        char all[2048] = "";
        size_t i;
        json_t *line;
        json_array_foreach(footer, i, line) {
            strncat(all, json_string_value(line), sizeof(all) - strlen(all) - 2);
            strcat(all, "\n");
        }
        CHECK(strstr(json_string_value(json_object_get(l, "title")), "partial sweep") &&
              strstr(all, "PARTIAL") && strstr(all, "async_distance=5 (cancelled)") &&
              strstr(all, "2 planned points not run"));
        json_decref(l);
    }
    size_t hl = 0;
    char *html = report_sweep_html(sw, llvmpipe, NULL, NULL, &hl);
    CHECK(html && strstr(html, "A partial sweep") && strstr(html, "Not measured: osl") &&
          strstr(html, "2 planned points not run"));
    free(html);
    json_decref(sw);
}

/* Points on top of each other: labels that do not fit become numbers, and
 * the key under the chart names every one of them. */
static void test_crowded_labels(const json_t *llvmpipe)
{
    json_t *points = json_array();
    for (int i = 0; i < 12; i++) {
        char values[64];
        snprintf(values, sizeof(values), "{\"async_distance\":%d}", i);
        json_array_append_new(points, trow("osl", values, 30 + 0.01 * i, 29, 31, 0.999, 0, "done"));
    }
    json_t *sw = tsweep(points, "done", 12, "async_distance");
    struct chart_options o = {.device = llvmpipe};
    json_t *l = chart(sw, "speed_accuracy", &o);
    json_t *pts = json_object_get(l, "points");
    int tagged = 0;
    size_t i;
    json_t *p;
    json_array_foreach(pts, i, p) {
        bool labelled = !json_is_null(json_object_get(p, "label_box"));
        json_t *tag = json_object_get(p, "tag");
        CHECK(labelled || json_is_integer(tag));
        if (json_is_integer(tag)) {
            tagged++;
            char needle[64];
            snprintf(needle, sizeof(needle), "%lld: osl, async_distance=%zu ",
                     (long long)json_integer_value(tag), i);
            bool keyed = false;
            size_t k;
            json_t *line;
            json_array_foreach(json_object_get(l, "footer"), k, line)
                keyed = keyed || strstr(json_string_value(line), needle);
            CHECK(keyed);
        }
    }
    CHECK(tagged > 0 && tagged == json_integer_value(json_object_get(l, "labels_left_out")));
    json_decref(l);
    json_decref(sw);
}

/* The job report: numbers for people, and the run's noise where people
 * look. */
static void test_job_report(const json_t *llvmpipe)
{
    json_t *job = json_loads(
        "{\"id\":\"j9\",\"technique\":\"osl\",\"status\":\"done\","
        "\"spec\":{\"technique\":\"osl\",\"metrics\":{\"pdiff\":{\"fov\":22.600000000000001}}},"
        "\"result\":{\"frames\":4,\"frame_ms\":{\"median\":10.0},"
        "\"osl\":{\"texels_shaded_per_frame\":{\"mean\":873813.33333333326}},"
        "\"interference\":{\"other_cpu_share\":0.79,\"noisy\":true,\"cpus\":2,"
        "\"loadavg_start\":[6.1,5,4],\"loadavg_end\":[8.9,6,5]}}}", 0, NULL);
    size_t hl = 0;
    char *html = report_job_html(job, "/nonexistent", llvmpipe, &hl);
    CHECK(html && !strstr(html, "22.600000000000001") && strstr(html, "22.6") &&
          !strstr(html, "873813.33333333326") && strstr(html, "873813.333"));
    CHECK(html && strstr(html, "A noisy run:") && strstr(html, "<b>79%</b>") &&
          strstr(html, "6.10 to 8.90 on 2 CPUs"));
    free(html);
    json_decref(job);
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
    json_t *v = sweep_verdict_json(sweep, "frame_ms");
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

    test_technique_sweep(llvmpipe);
    test_noise_in_verdicts(llvmpipe);
    test_reference_wins(llvmpipe);
    test_partial_sweep(llvmpipe);
    test_crowded_labels(llvmpipe);
    test_job_report(llvmpipe);

    json_decref(sweep);
    json_decref(points);
    json_decref(llvmpipe);
    json_decref(gpu);
    return check_finish("test_charts");
}
