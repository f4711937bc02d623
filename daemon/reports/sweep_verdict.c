#define _POSIX_C_SOURCE 200809L
#include "daemon/reports/sweep_verdict.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/noise.h"
#include "common/result_keys.h"

static double num(const json_t *v, double fallback)
{
    return json_is_number(v) ? json_number_value(v) : fallback;
}

static bool workload_key(const char *k)
{
    /* As sweep_spec.c's workload_param: points scored against different
     * references (reference.supersample) are never on one front. */
    return !strncmp(k, "scene.", 6) || !strcmp(k, "frames") || !strcmp(k, "warmup_frames") ||
           !strcmp(k, "reference.supersample");
}

/* "k=v, ..." of the values keep() accepts, in their order; short_keys
 * drops the "scene." of a path (labels next to points are short). */
static void values_text(const json_t *values, bool (*keep)(const char *key, const char *skip),
                        const char *skip, bool short_keys, char *out, size_t cap)
{
    out[0] = '\0';
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)values, k, v) {
        if (!keep(k, skip))
            continue;
        char *t = json_dumps(v, JSON_ENCODE_ANY | SV_DUMP_REALS);
        size_t used = strlen(out);
        const char *key = short_keys && strrchr(k, '.') ? strrchr(k, '.') + 1 : k;
        snprintf(out + used, cap - used, "%s%s=%s", used ? ", " : "", key, t ? t : "?");
        free(t);
    }
}

static bool keep_workload(const char *k, const char *skip)
{
    return workload_key(k) && (!skip || strcmp(k, skip) != 0);
}

static bool keep_not_technique(const char *k, const char *skip)
{
    return strcmp(k, "technique") != 0 && (!skip || strcmp(k, skip) != 0);
}

static bool keep_variant(const char *k, const char *skip)
{
    return !workload_key(k) && strcmp(k, "technique") != 0 && (!skip || strcmp(k, skip) != 0);
}

static int workload_index(struct sweep_view *v, const json_t *values)
{
    char key[128];
    values_text(values, keep_workload, NULL, false, key, sizeof(key));
    for (int w = 0; w < v->nworkloads; w++)
        if (!strcmp(v->workloads[w], key))
            return w;
    if (v->nworkloads == SV_MAX_WORKLOADS)
        return SV_MAX_WORKLOADS - 1;
    snprintf(v->workloads[v->nworkloads], sizeof(v->workloads[0]), "%s", key);
    return v->nworkloads++;
}

bool sweep_view_init(struct sweep_view *v, const json_t *sweep, const char *series)
{
    memset(v, 0, sizeof(*v));
    v->series = series;
    const json_t *base = json_object_get(json_object_get(sweep, "spec"), "base");
    /* A supersampled reference ({"technique", "supersample": N > 1}) is not
     * its technique's own image: no point is exact against it. */
    json_t *ref = json_object_get(base, "reference");
    json_int_t base_ss = json_is_object(ref) && json_is_integer(json_object_get(ref, "supersample"))
                             ? json_integer_value(json_object_get(ref, "supersample"))
                             : 1;
    if (json_is_object(ref))
        ref = json_object_get(ref, "technique");
    v->reference = json_string_value(ref);
    v->reference = v->reference ? v->reference : "forward";
    v->status = json_string_value(json_object_get(sweep, "status"));
    v->status = v->status ? v->status : "?";
    json_t *rows = json_object_get(sweep, "points");
    size_t n = json_array_size(rows);
    v->pts = calloc(n + 1, sizeof(*v->pts));
    if (!v->pts)
        return false;
    /* The first numeric swept field: the x of time_vs_param and of the
     * crossovers. */
    size_t i;
    json_t *row;
    json_array_foreach(rows, i, row) {
        const char *k;
        json_t *val;
        json_object_foreach(json_object_get(row, "values"), k, val) if (!v->param &&
                                                                        json_is_number(val))
            v->param = k;
    }
    json_array_foreach(rows, i, row) {
        struct sv_point *p = &v->pts[v->n++];
        json_t *values = json_object_get(row, "values");
        p->row = row;
        p->technique = json_string_value(json_object_get(row, "technique"));
        p->technique = p->technique ? p->technique : "?";
        p->status = json_string_value(json_object_get(row, "status"));
        p->status = p->status ? p->status : "?";
        values_text(values, keep_not_technique, NULL, true, p->label, sizeof(p->label));
        p->workload = workload_index(v, values);
        json_t *ss = json_object_get(values, "reference.supersample");
        p->reference = !strcmp(p->technique, v->reference) &&
                       (json_is_integer(ss) ? json_integer_value(ss) : base_ss) <= 1;
        json_t *cell = json_object_get(row, series);
        p->ms = num(json_object_get(cell, RK_MEDIAN), NAN);
        p->timed = isfinite(p->ms);
        json_t *ci = json_object_get(cell, RK_CI95);
        p->lo = num(json_array_get(ci, 0), p->ms);
        p->hi = num(json_array_get(ci, 1), p->ms);
        p->lo_clamped = p->lo < 0;
        if (p->lo_clamped)
            p->lo = 0;
        json_t *ssim = json_object_get(row, RK_WORST_SSIM), *flip = json_object_get(row, RK_WORST_FLIP);
        /* The reference against itself: exact by definition. */
        p->has_ssim = json_is_number(ssim) || p->reference;
        p->ssim = num(ssim, 1.0);
        p->has_flip = json_is_number(flip) || p->reference;
        p->flip = num(flip, 0.0);
        json_t *pf = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
        p->judged = json_is_integer(pf);
        p->pdiff_pass = p->judged && json_integer_value(pf) == 0;
        json_t *inter = json_object_get(row, RK_INTERFERENCE);
        p->noisy = noise_interference_noisy(inter);
        p->other_share = num(json_object_get(inter, "other_cpu_share"), NAN);
        v->not_done += strcmp(p->status, "done") != 0;
    }
    json_t *progress = json_object_get(sweep, "progress");
    v->points_total = json_is_integer(json_object_get(progress, "points_total"))
                          ? json_integer_value(json_object_get(progress, "points_total"))
                          : (long long)v->n;
    v->not_run = v->points_total > v->n ? (int)(v->points_total - v->n) : 0;
    v->partial = strcmp(v->status, "done") != 0 || v->not_run > 0 || v->not_done > 0;
    /* The largest passing value means something only along a field whose
     * values are all numbers (a sweep over techniques has none). */
    json_t *lp = json_object_get(json_object_get(sweep, RK_RESULT), "largest_pdiff_pass");
    const char *lparam = json_string_value(json_object_get(lp, "param"));
    v->numeric_param = lparam != NULL;
    for (int k = 0; k < v->n && lparam; k++) {
        json_t *val = json_object_get(json_object_get(v->pts[k].row, "values"), lparam);
        if (val && !json_is_number(val))
            v->numeric_param = false;
    }
    return true;
}

void sweep_view_finish(struct sweep_view *v)
{
    free(v->pts);
    memset(v, 0, sizeof(*v));
}

bool sv_faster(const struct sv_point *a, const struct sv_point *b)
{
    return a->timed && b->timed && a->hi < b->lo;
}

static bool has_quality(const struct sv_point *p, bool flip)
{
    return p->timed && (flip ? p->has_flip : p->has_ssim);
}

/* Quality comparison: > 0 when a is more accurate than b. */
static int quality_cmp(const struct sv_point *a, const struct sv_point *b, bool flip)
{
    double qa = flip ? -a->flip : a->ssim, qb = flip ? -b->flip : b->ssim;
    return (qa > qb) - (qa < qb);
}

void sweep_view_front(struct sweep_view *v, bool flip)
{
    for (int a = 0; a < v->n; a++) {
        struct sv_point *p = &v->pts[a];
        p->pareto = p->tied = false;
        if (!has_quality(p, flip))
            continue;
        p->pareto = true;
        for (int b = 0; b < v->n && p->pareto; b++) {
            const struct sv_point *q = &v->pts[b];
            if (a == b || q->workload != p->workload || !has_quality(q, flip))
                continue;
            int qc = quality_cmp(q, p, flip);
            if (!sv_faster(p, q) && qc >= 0 && (sv_faster(q, p) || qc > 0))
                p->pareto = false;
        }
    }
    for (int a = 0; a < v->n; a++) {
        struct sv_point *p = &v->pts[a];
        for (int b = 0; b < v->n && p->pareto && !p->tied; b++) {
            const struct sv_point *q = &v->pts[b];
            p->tied = a != b && q->pareto && q->workload == p->workload && !sv_faster(p, q) &&
                      !sv_faster(q, p);
        }
    }
}

/* ---- the verdict ---- */

/* "osl async_distance=5, scene.lights=8": what a point is, in text. */
static void point_name(const struct sv_point *p, char *out, size_t cap)
{
    char rest[160];
    values_text(json_object_get(p->row, "values"), keep_not_technique, NULL, false, rest,
                sizeof(rest));
    snprintf(out, cap, "%s%s%s", p->technique, rest[0] ? " " : "", rest);
}

/* A curve along param: one technique (and value of the other swept
 * non-workload fields) on one workload; the reference timed once per
 * workload is flat. */
struct curve {
    char name[200], workload[128];
    bool flat;
    int *idx;
    int n;
};

static void add_crossovers(const struct sweep_view *v, const struct curve *a,
                           const struct curve *b, json_t *list)
{
    if (a->flat && b->flat)
        return;
    const struct curve *xs = a->flat ? b : a;
    double *x = malloc((size_t)(xs->n + 1) * sizeof(double)),
           *d = malloc((size_t)(xs->n + 1) * sizeof(double));
    int *sign = malloc((size_t)(xs->n + 1) * sizeof(int));
    int k = 0;
    for (int i = 0; x && d && sign && i < xs->n; i++) {
        double xv = json_number_value(
            json_object_get(json_object_get(v->pts[xs->idx[i]].row, "values"), v->param));
        const struct sv_point *pa = NULL, *pb = NULL;
        for (int j = 0; j < a->n; j++)
            if (a->flat || json_number_value(json_object_get(
                               json_object_get(v->pts[a->idx[j]].row, "values"), v->param)) == xv)
                pa = &v->pts[a->idx[j]];
        for (int j = 0; j < b->n; j++)
            if (b->flat || json_number_value(json_object_get(
                               json_object_get(v->pts[b->idx[j]].row, "values"), v->param)) == xv)
                pb = &v->pts[b->idx[j]];
        if (!pa || !pb)
            continue;
        int at = k;
        while (at > 0 && x[at - 1] > xv) {
            x[at] = x[at - 1], d[at] = d[at - 1], sign[at] = sign[at - 1];
            at--;
        }
        x[at] = xv;
        d[at] = pa->ms - pb->ms;
        /* Which is faster where the intervals say so; 0 where they overlap. */
        sign[at] = sv_faster(pa, pb) ? -1 : sv_faster(pb, pa) ? 1 : 0;
        k++;
    }
    for (int i = 0; i + 1 < k; i++) {
        if (!(d[i] * d[i + 1] < 0))
            continue;
        double at = x[i] + (x[i + 1] - x[i]) * d[i] / (d[i] - d[i + 1]);
        /* Below the crossing, the curve with the smaller time is faster. */
        const struct curve *below = d[i] < 0 ? a : b, *above = d[i] < 0 ? b : a;
        bool supported = sign[i] != 0 && sign[i + 1] == -sign[i];
        json_array_append_new(list, json_pack("{s:s, s:s, s:s, s:[f, f], s:f, s:s, s:b}",
                                              "faster_below", below->name, "faster_above",
                                              above->name, "param", v->param, "between", x[i],
                                              x[i + 1], "at", at, RK_WORKLOAD, a->workload,
                                              "distinguishable", supported));
    }
    free(x);
    free(d);
    free(sign);
}

static json_t *crossovers(const struct sweep_view *v)
{
    json_t *list = json_array();
    if (!v->param)
        return list;
    struct curve *curves = calloc((size_t)v->n + 1, sizeof(*curves));
    int *of = calloc((size_t)v->n + 1, sizeof(int)), *idx = calloc((size_t)v->n + 1, sizeof(int));
    int nc = 0;
    for (int i = 0; curves && of && idx && i < v->n; i++) {
        const struct sv_point *p = &v->pts[i];
        json_t *values = json_object_get(p->row, "values");
        json_t *pv = json_object_get(values, v->param);
        of[i] = -1;
        if (!p->timed || (pv && !json_is_number(pv)))
            continue;
        char variant[160], wl[128], name[200];
        values_text(values, keep_workload, v->param, false, wl, sizeof(wl));
        values_text(values, keep_variant, v->param, false, variant, sizeof(variant));
        snprintf(name, sizeof(name), "%s%s%s%s", p->technique, p->reference ? " (reference)" : "",
                 variant[0] ? " " : "", variant);
        int c = 0;
        while (c < nc && (strcmp(curves[c].name, name) || strcmp(curves[c].workload, wl)))
            c++;
        if (c == nc) {
            snprintf(curves[c].name, sizeof(curves[c].name), "%s", name);
            snprintf(curves[c].workload, sizeof(curves[c].workload), "%s", wl);
            curves[c].flat = pv == NULL;
            nc++;
        }
        of[i] = c;
        curves[c].n++;
    }
    /* Each curve's points, a slice of one array. */
    for (int c = 0, at = 0; c < nc; c++) {
        curves[c].idx = idx + at;
        at += curves[c].n;
        curves[c].n = 0;
    }
    for (int i = 0; i < v->n && nc; i++)
        if (of[i] >= 0)
            curves[of[i]].idx[curves[of[i]].n++] = i;
    for (int a = 0; a < nc; a++)
        for (int b = a + 1; b < nc; b++)
            if (!strcmp(curves[a].workload, curves[b].workload))
                add_crossovers(v, &curves[a], &curves[b], list);
    free(curves);
    free(of);
    free(idx);
    return list;
}

/* A point against the reference: its ratio with the interval the two
 * intervals allow, and whether that excludes 1. */
static json_t *against(const struct sweep_view *v, const struct sv_point *p,
                       const struct sv_point *ref)
{
    json_t *o = json_pack("{s:s, s:O, s:f}", "technique", p->technique, "values",
                          json_object_get(p->row, "values"), "ms", p->ms);
    json_t *tied = json_array();
    char name[200];
    for (int i = 0; i < v->n; i++) {
        const struct sv_point *q = &v->pts[i];
        if (q == p || q->reference || !q->timed || q->workload != p->workload ||
            sv_faster(p, q) || sv_faster(q, p))
            continue;
        point_name(q, name, sizeof(name));
        json_array_append_new(tied, json_string(name));
    }
    json_object_set_new(o, "tied_with", tied);
    if (ref) {
        double lo = ref->hi > 0 ? p->lo / ref->hi : NAN;
        double hi = ref->lo > 0 ? p->hi / ref->lo : INFINITY;
        json_object_set_new(o, "ratio", json_real(p->ms / ref->ms));
        json_object_set_new(o, "ratio_ci", json_pack("[f, f]", isfinite(lo) ? lo : 0.0,
                                                     isfinite(hi) ? hi : 1e300));
        json_object_set_new(o, "distinguishable", json_boolean(sv_faster(p, ref) ||
                                                               sv_faster(ref, p)));
    }
    return o;
}

json_t *sweep_verdict_json(const json_t *sweep, const char *series)
{
    struct sweep_view v;
    if (!sweep_view_init(&v, sweep, series))
        return json_pack("{s:s}", "series", series);
    sweep_view_front(&v, false);
    json_t *out = json_pack("{s:s, s:b, s:s, s:I, s:i}", "series", series, "partial", v.partial,
                            "status", v.status, "points_total", (json_int_t)v.points_total,
                            "not_run", v.not_run);
    json_t *result = json_object_get(sweep, RK_RESULT);
    if (json_object_get(result, "breaking_point"))
        json_object_set(out, "breaking_point", json_object_get(result, "breaking_point"));
    json_t *missing = json_array(), *noisy = json_array(), *passing = json_array();
    int judged = 0;
    json_t *largest = NULL;
    const char *lparam = json_string_value(
        json_object_get(json_object_get(result, "largest_pdiff_pass"), "param"));
    char name[200];
    for (int i = 0; i < v.n; i++) {
        const struct sv_point *p = &v.pts[i];
        json_t *values = json_object_get(p->row, "values");
        if (strcmp(p->status, "done") != 0)
            json_array_append_new(missing, json_pack("{s:s, s:O, s:s, s:O}", "technique",
                                                     p->technique, "values", values, "status",
                                                     p->status, "error",
                                                     json_object_get(p->row, "error")
                                                         ? json_object_get(p->row, "error")
                                                         : json_null()));
        if (p->noisy)
            json_array_append_new(noisy, json_pack("{s:s, s:O, s:f}", "technique", p->technique,
                                                   "values", values, "other_cpu_share",
                                                   isfinite(p->other_share) ? p->other_share : -1.0));
        if (!p->judged)
            continue;
        judged++;
        if (!p->pdiff_pass)
            continue;
        point_name(p, name, sizeof(name));
        json_array_append_new(passing, json_string(name));
        json_t *lv = lparam ? json_object_get(values, lparam) : NULL;
        if (json_is_number(lv) && (!largest || json_number_value(lv) > json_number_value(largest)))
            largest = lv;
    }
    json_object_set_new(out, "missing", missing);
    json_object_set_new(out, "noisy", noisy);
    json_object_set_new(out, "pdiff_passing", passing);
    json_object_set_new(out, "pdiff_judged", json_integer(judged));
    /* The largest passing value, from the same passing set as the rest of
     * the verdict, and only along a numeric field. */
    if (lparam && v.numeric_param)
        json_object_set_new(out, "largest_pdiff_pass",
                            json_pack("{s:s, s:O}", "param", lparam, "value",
                                      largest ? largest : json_null()));
    json_t *fronts = json_array();
    for (int w = 0; w < v.nworkloads; w++) {
        json_t *members = json_array();
        for (int i = 0; i < v.n; i++) {
            const struct sv_point *p = &v.pts[i];
            if (!p->pareto || p->workload != w)
                continue;
            point_name(p, name, sizeof(name));
            json_array_append_new(members, json_pack("{s:s, s:f, s:f, s:b}", "name", name, "ms",
                                                     p->ms, RK_WORST_SSIM, p->ssim, "tied",
                                                     p->tied));
        }
        if (json_array_size(members))
            json_array_append_new(fronts, json_pack("{s:s, s:o}", RK_WORKLOAD, v.workloads[w],
                                                    "points", members));
        else
            json_decref(members);
    }
    json_object_set_new(out, "front", fronts);
    json_object_set_new(out, "crossovers", crossovers(&v));
    json_t *vs = json_array();
    for (int w = 0; w < v.nworkloads; w++) {
        const struct sv_point *ref = NULL, *fastest = NULL, *fastest_passing = NULL;
        for (int i = 0; i < v.n; i++) {
            const struct sv_point *p = &v.pts[i];
            if (p->workload != w || !p->timed)
                continue;
            if (p->reference) {
                ref = p;
                continue;
            }
            if (!fastest || p->ms < fastest->ms)
                fastest = p;
            if (p->pdiff_pass && (!fastest_passing || p->ms < fastest_passing->ms))
                fastest_passing = p;
        }
        if (!fastest && !ref)
            continue;
        json_t *o = json_pack("{s:s, s:s}", RK_WORKLOAD, v.workloads[w], "reference", v.reference);
        if (ref) {
            json_object_set_new(o, RK_REFERENCE_MS, json_real(ref->ms));
            json_object_set_new(o, "reference_ci", json_pack("[f, f]", ref->lo, ref->hi));
        }
        if (fastest)
            json_object_set_new(o, "fastest", against(&v, fastest, ref));
        /* Who wins, the reference included: the reference when it is
         * measurably faster than the fastest point (a sweep of one
         * technique against a faster reference has no swept winner). */
        const struct sv_point *win = !fastest || (ref && sv_faster(ref, fastest)) ? ref : fastest;
        json_object_set_new(
            o, "winner",
            json_pack("{s:s, s:O?, s:f, s:b, s:b}", "technique", win->technique, "values",
                      win == ref ? NULL : json_object_get(win->row, "values"), "ms", win->ms,
                      "reference", win == ref,
                      "tied_with_reference", ref && win != ref && !sv_faster(win, ref)));
        if (fastest_passing)
            json_object_set_new(o, "fastest_passing", against(&v, fastest_passing, ref));
        json_array_append_new(vs, o);
    }
    json_object_set_new(out, "against_reference", vs);
    sweep_view_finish(&v);
    return out;
}
