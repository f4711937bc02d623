/* sweep: starts a sweep, follows it by points, downloads its table (JSON
 * and CSV), charts and report, and turns its criteria into test cases. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/client.h"
#include "client/fleet.h"
#include "client/verdicts.h"
#include "client/junit.h"
#include "client/workload.h"
#include "common/fsutil.h"
#include "common/json_fields.h"
#include "common/result_keys.h"

/* The point's job as the sweep file states it: its base with the point's
 * values set at their dotted paths ("scene.lights": 8). New reference. */
static json_t *point_spec(const json_t *base, const json_t *row)
{
    json_t *spec = json_is_object(base) ? json_deep_copy(base) : json_object();
    const char *tech = json_string_value(json_object_get(row, "technique"));
    if (tech)
        json_object_set_new(spec, "technique", json_string(tech));
    const char *key;
    json_t *v;
    json_object_foreach(json_object_get(row, "values"), key, v)
        jf_set_path(spec, key, json_incref(v));
    return spec;
}

/* "forward grid 160x120 8 lights #3f2a91c0, 20 frames [scene.lights=8]":
 * the point's workload (named as a job is, with the hash history prints for
 * it), so that two sweeps in one pipeline never share a case, and its
 * swept values, which the name may otherwise only carry in its hash. */
static void point_name(const json_t *base, const json_t *row, char *out, size_t cap)
{
    json_t *spec = point_spec(base, row);
    junit_job_name(spec, out, cap);
    json_decref(spec);
    const char *key;
    json_t *v;
    const char *sep = " [";
    json_object_foreach(json_object_get(row, "values"), key, v) {
        char *text = json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT);
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s=%s", sep, key, text ? text : "?");
        free(text);
        sep = " ";
    }
    if (strcmp(sep, " [") != 0) {
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "]");
    }
}

static void point_cases(struct conn *c, const struct options *o, const json_t *sweep,
                        const json_t *base, const char *sweep_name, struct junit *j)
{
    bool find = !strcmp(json_string_value(json_object_get(sweep, "kind")) ?
                        json_string_value(json_object_get(sweep, "kind")) : "", "find");
    size_t i;
    json_t *row;
    char name[480], cname[760];
    json_array_foreach(json_object_get(sweep, "points"), i, row) {
        point_name(base, row, name, sizeof(name));
        snprintf(cname, sizeof(cname), "%s: job", name);
        struct junit_case *t = junit_add(j, "shadebench.sweep", cname);
        if (!t)
            return;
        const char *status = json_string_value(json_object_get(row, "status"));
        const char *job_id = json_string_value(json_object_get(row, "job"));
        junit_prop_str(t, "job", job_id);
        /* Real times: the point job's span and its metrics' time, which the
         * table does not carry. */
        char path[160];
        snprintf(path, sizeof(path), "/v1/jobs/%s", job_id ? job_id : "");
        json_t *job = job_id ? conn_json(c, "GET", path, NULL, NULL) : NULL;
        double span = iso_unix_s(json_string_value(json_object_get(job, "finished"))) -
                      iso_unix_s(json_string_value(json_object_get(job, "started")));
        json_t *metrics_s = json_object_get(
            json_object_get(json_object_get(job, RK_RESULT), RK_QUALITY), "metrics_s");
        double quality_s = json_is_number(metrics_s) ? json_number_value(metrics_s) : 0;
        json_decref(job);
        t->time_s = isfinite(span) && span > 0 ? span : 0;
        if (!status || strcmp(status, "done") != 0) {
            const char *error = json_string_value(json_object_get(row, "error"));
            junit_fail(t, JUNIT_JOB_FAILED, "point job %s: %s", status ? status : "?", error ? error : "");
            continue;
        }
        static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
        char prop[48];
        for (int s = 0; s < 3; s++) {
            json_t *cell = json_object_get(row, series[s]);
            snprintf(prop, sizeof(prop), "%s_median", series[s]);
            junit_prop_num(t, prop, json_number_value(json_object_get(cell, RK_MEDIAN)));
        }
        junit_prop_num(t, RK_WALL_S, json_number_value(json_object_get(json_object_get(row, RK_WALL_S),
                                                                      RK_MEAN)));
        junit_out(t, "frame_ms median %.4f ms",
                  json_number_value(json_object_get(json_object_get(row, RK_FRAME_MS), RK_MEDIAN)));
        json_t *pf = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
        json_t *ssim = json_object_get(row, RK_WORST_SSIM);
        json_t *flip = json_object_get(row, RK_WORST_FLIP);
        if (!pf && !json_is_number(ssim))
            continue; /* no reference: nothing judged */
        snprintf(cname, sizeof(cname), "%s: quality", name);
        struct junit_case *q = junit_add(j, "shadebench.sweep", cname);
        if (!q)
            return;
        q->time_s = quality_s;
        junit_prop_num(q, RK_WORST_SSIM, json_number_value(ssim));
        junit_prop_num(q, RK_WORST_FLIP, json_number_value(flip));
        junit_prop_num(q, RK_PDIFF_FAILED_CAPTURES, (double)json_integer_value(pf));
        json_t *holds = json_object_get(row, "criterion_holds");
        if (find) {
            /* Probes of a bisection fail above the boundary by design: their
             * verdicts are output, the breaking point is the case. */
            junit_out(q, "criterion %s", json_is_true(holds) ? "holds" : "fails");
        } else if (json_integer_value(pf) > 0) {
            junit_fail(q, JUNIT_QUALITY, "PerceptualDiff failed on %lld captures",
                       (long long)json_integer_value(pf));
        }
        if (!find && !isnan(o->min_ssim) && json_is_number(ssim) &&
            json_number_value(ssim) < o->min_ssim)
            junit_fail(q, JUNIT_QUALITY, "worst SSIM %.6f below %.6f", json_number_value(ssim), o->min_ssim);
        if (!find && !isnan(o->max_flip) && json_is_number(flip) &&
            json_number_value(flip) > o->max_flip)
            junit_fail(q, JUNIT_QUALITY, "worst FLIP mean %.6f above %.6f", json_number_value(flip), o->max_flip);
    }
    json_t *result = json_object_get(sweep, RK_RESULT);
    json_t *bp = json_object_get(result, "breaking_point");
    if (bp) {
        snprintf(cname, sizeof(cname), "%s: breaking point of %s while %s", sweep_name,
                 json_string_value(json_object_get(bp, "param")),
                 json_string_value(json_object_get(bp, "criterion")));
        struct junit_case *t = junit_add(j, "shadebench.sweep", cname);
        if (!t)
            return;
        const char *outcome = json_string_value(json_object_get(bp, "outcome"));
        junit_prop_str(t, "outcome", outcome);
        junit_prop_num(t, "value", json_number_value(json_object_get(bp, "value")));
        junit_prop_num(t, "first_failing", json_number_value(json_object_get(bp, "first_failing")));
        junit_prop_num(t, "probes", (double)json_integer_value(json_object_get(bp, "probes")));
        char *v = json_dumps(json_object_get(bp, "value"), JSON_ENCODE_ANY);
        junit_out(t, "%s: largest value at which it holds %s", outcome ? outcome : "?",
                  v ? v : "?");
        free(v);
        if (!outcome || !strcmp(outcome, "fails everywhere") || !strcmp(outcome, "aborted"))
            junit_fail(t, JUNIT_QUALITY, "no value holds the criterion (%s)", outcome ? outcome : "no outcome");
    }
    /* The largest passing value means something along a numeric field
     * only; a sweep over techniques judges each point in its quality case. */
    json_t *largest = json_object_get(result, "largest_pdiff_pass");
    bool numeric = false;
    json_array_foreach(json_object_get(sweep, "points"), i, row)
        numeric = numeric || json_is_number(json_object_get(
                                 json_object_get(row, "values"),
                                 json_string_value(json_object_get(largest, "param"))));
    if (largest && numeric) {
        snprintf(cname, sizeof(cname), "%s: largest %s passing PerceptualDiff", sweep_name,
                 json_string_value(json_object_get(largest, "param")));
        struct junit_case *t = junit_add(j, "shadebench.sweep", cname);
        if (!t)
            return;
        char *v = json_dumps(json_object_get(largest, "value"), JSON_ENCODE_ANY);
        junit_prop_str(t, "value", v);
        junit_out(t, "%s", v ? v : "null");
        free(v);
    }
}

static bool download_all(struct conn *c, const json_t *sweep, const char *dir)
{
    const char *id = json_string_value(json_object_get(sweep, "id"));
    char path[4096], url[512];
    bool ok = fs_mkdir_p(dir);
    snprintf(path, sizeof(path), "%s/charts", dir);
    ok = ok && fs_mkdir_p(path);
    snprintf(path, sizeof(path), "%s/sweep.json", dir);
    ok = ok && fs_write_json_atomic(path, sweep);
    snprintf(path, sizeof(path), "%s/table.csv", dir);
    ok = ok && sweep_csv_write(sweep, path);
    /* file name, chart name, query */
    static const char *const charts[][3] = {
        {"speed_accuracy", "speed_accuracy", ""},
        {"speed_accuracy_flip", "speed_accuracy", "?y=flip"},
        {"time_vs_param", "time_vs_param", ""},
        {"distribution", "distribution", ""},
    };
    static const char *const formats[] = {"svg", "png"};
    for (size_t k = 0; ok && k < sizeof(charts) / sizeof(charts[0]); k++)
        for (int f = 0; f < 2; f++) {
            snprintf(url, sizeof(url), "/v1/sweeps/%s/charts/%s.%s%s", id, charts[k][1],
                     formats[f], charts[k][2]);
            snprintf(path, sizeof(path), "%s/charts/%s.%s", dir, charts[k][0], formats[f]);
            ok = conn_download(c, url, path) && ok;
        }
    snprintf(url, sizeof(url), "/v1/sweeps/%s/report.html", id);
    snprintf(path, sizeof(path), "%s/report.html", dir);
    return conn_download(c, url, path) && ok;
}

void sweep_add_labels(json_t *body, const json_t *labels)
{
    json_t *base = json_object_get(body, "base");
    if (!json_object_size(labels) || !json_is_object(base))
        return;
    /* Labels reach the point jobs through the base job. */
    json_t *into = json_object_get(base, "labels");
    if (!json_is_object(into)) {
        into = json_object();
        json_object_set_new(base, "labels", into);
    }
    json_object_update(into, (json_t *)labels);
}

/* "sweep of forward grid 160x120 #3f2a91c0, 20 frames over scene.lights,
 * technique": the sweep's case, unique to what it sweeps. */
static void sweep_case_name(const json_t *body, char *out, size_t cap)
{
    char base[400];
    junit_job_name(json_object_get(body, "base"), base, sizeof(base));
    snprintf(out, cap, "sweep of %s over", base);
    const char *key;
    json_t *v;
    const char *sep = " ";
    json_object_foreach(json_object_get(body, "vary"), key, v) {
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s", sep, key);
        sep = ", ";
    }
    const char *param = json_string_value(json_object_get(json_object_get(body, "find"), "param"));
    if (param) {
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s (find)", sep, param);
    }
}

int cmd_sweep(struct conn *c, const struct options *o, const char *file)
{
    char err[600];
    if (o->baseline) {
        fprintf(stderr, "shadebench: --baseline belongs to submit\n");
        return EXIT_ERROR;
    }
    if (o->out_dir && !out_dir_claim(o->out_dir, "sweep.json", NULL, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    json_t *body = load_json_file("sweep file", file, err, sizeof(err));
    if (!json_is_object(body)) {
        fprintf(stderr, "shadebench: %s\n", body ? "a sweep is a JSON object" : err);
        json_decref(body);
        return EXIT_ERROR;
    }
    char why[300];
    if ((!isnan(o->min_ssim) || !isnan(o->max_flip)) &&
        !workload_quality_judged(json_object_get(body, "base"), why, sizeof(why)) &&
        !json_object_get(json_object_get(body, "vary"), "reference")) {
        fprintf(stderr, "shadebench: the sweep's points cannot be judged by %s: its base job: "
                "%s\n", !isnan(o->min_ssim) ? "--min-ssim" : "--max-flip", why);
        json_decref(body);
        return EXIT_ERROR;
    }
    sweep_add_labels(body, o->labels);
    char *text = json_dumps(body, JSON_COMPACT);
    /* Case names from the file as written: the base job's workload and
     * what the sweep varies. */
    json_t *base = json_incref(json_object_get(body, "base"));
    char sweep_name[600];
    sweep_case_name(body, sweep_name, sizeof(sweep_name));
    json_decref(body);
    double t0 = clock_mono_s();
    json_t *reply = text ? conn_json(c, "POST", "/v1/sweeps", text, NULL) : NULL;
    free(text);
    if (!reply)
        return EXIT_ERROR;
    char id[64];
    snprintf(id, sizeof(id), "%s", json_string_value(json_object_get(reply, "id")));
    json_decref(reply);
    printf("%s\n", id);
    fflush(stdout);
    if (!o->wait)
        return EXIT_PASS;
    json_t *sweep = conn_follow_sweep(c, id, o->quiet, o->timeout_s);
    if (!sweep)
        return EXIT_ERROR;
    struct junit j;
    junit_init(&j);
    const char *status = json_string_value(json_object_get(sweep, "status"));
    struct junit_case *t = junit_add(&j, "shadebench.sweep", sweep_name);
    if (t) {
        t->time_s = clock_mono_s() - t0;
        junit_prop_str(t, "sweep", id);
        junit_prop_num(t, "points",
                       (double)json_array_size(json_object_get(sweep, "points")));
        json_t *progress = json_object_get(sweep, "progress");
        long long done = json_integer_value(json_object_get(progress, "points_done"));
        long long total = json_integer_value(json_object_get(progress, "points_total"));
        junit_prop_num(t, "points_total", (double)total);
        if (!status || strcmp(status, "done") != 0) {
            const char *error = json_string_value(json_object_get(sweep, "error"));
            junit_fail(t, JUNIT_JOB_FAILED, "sweep %s after %lld of %lld points (a partial sweep)%s%s",
                       status ? status : "?", done, total, error ? ": " : "", error ? error : "");
        }
    }
    point_cases(c, o, sweep, base, sweep_name, &j);
    int rc = junit_conclude(o, &j, sweep_name, clock_mono_s() - t0);
    if (o->out_dir) {
        if (!download_all(c, sweep, o->out_dir))
            rc = EXIT_ERROR;
        else if (!o->quiet)
            fprintf(stderr, "files in %s\n", o->out_dir);
    }
    junit_finish(&j);
    json_decref(sweep);
    json_decref(base);
    return rc;
}
