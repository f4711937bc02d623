#define _DEFAULT_SOURCE /* timegm */
#include "client/verdicts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client/term.h"
#include "common/fsutil.h"
#include "common/result_keys.h"

double iso_unix_s(const char *s)
{
    struct tm tm;
    memset(&tm, 0, sizeof(tm));
    int ms = 0;
    if (!s || sscanf(s, "%d-%d-%dT%d:%d:%d.%dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                     &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &ms) < 6)
        return NAN;
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    return (double)timegm(&tm) + ms / 1000.0;
}

void job_classname(const json_t *spec, char *out, size_t cap)
{
    const char *t = json_string_value(json_object_get(spec, "technique"));
    snprintf(out, cap, "shadebench.%s", t ? t : "job");
}

void quality_cases(const struct options *o, const json_t *result, const char *classname,
                   const char *name, struct junit *j)
{
    size_t i;
    json_t *capture;
    json_array_foreach(json_object_get(result, RK_CAPTURES), i, capture) {
        char cname[400];
        snprintf(cname, sizeof(cname), "%s: frame %lld quality", name,
                 (long long)json_integer_value(json_object_get(capture, "frame")));
        struct junit_case *t = junit_add(j, classname, cname);
        if (!t)
            return;
        json_t *m = json_object_get(capture, "metrics");
        if (!m) {
            if (!isnan(o->min_ssim) || !isnan(o->max_flip))
                junit_fail(t, JUNIT_QUALITY, "no metrics: submit the job with a \"reference\" "
                           "technique");
            else
                junit_skip(t, "SKIP", "no reference technique: nothing judged");
            continue;
        }
        t->time_s = json_number_value(json_object_get(json_object_get(m, "timing_ms"), "total")) / 1e3;
        json_t *pdiff = json_object_get(m, "pdiff");
        json_t *ssim = json_object_get(m, "ssim");
        json_t *flip = json_object_get(json_object_get(m, "flip"), "mean");
        if (pdiff && !json_is_true(json_object_get(pdiff, "pass")))
            junit_fail(t, JUNIT_QUALITY, "PerceptualDiff failed: %lld pixels at %g degrees",
                       (long long)json_integer_value(json_object_get(pdiff, "failing_pixels")),
                       json_number_value(json_object_get(pdiff, "fov")));
        if (!isnan(o->min_ssim) && (!ssim || json_number_value(ssim) < o->min_ssim))
            junit_fail(t, JUNIT_QUALITY, "SSIM %.6f below %.6f", ssim ? json_number_value(ssim) : 0.0,
                       o->min_ssim);
        if (!isnan(o->max_flip) && (!flip || json_number_value(flip) > o->max_flip))
            junit_fail(t, JUNIT_QUALITY, "FLIP mean %.6f above %.6f", flip ? json_number_value(flip) : 1.0,
                       o->max_flip);
        if (ssim)
            junit_prop_num(t, "ssim", json_number_value(ssim));
        if (flip)
            junit_prop_num(t, "flip_mean", json_number_value(flip));
        if (pdiff)
            junit_prop_num(t, "pdiff_failing_pixels",
                           (double)json_integer_value(json_object_get(pdiff, "failing_pixels")));
        junit_out(t, "SSIM %.6f, FLIP mean %.6f, PerceptualDiff %s",
                  ssim ? json_number_value(ssim) : NAN, flip ? json_number_value(flip) : NAN,
                  pdiff ? (json_is_true(json_object_get(pdiff, "pass")) ? "pass" : "fail") : "-");
    }
}

struct junit_case *job_case(struct junit *j, const char *classname, const char *name,
                            const json_t *job, double time_s)
{
    char cname[400];
    snprintf(cname, sizeof(cname), "%s: job", name);
    struct junit_case *t = junit_add(j, classname, cname);
    if (!t)
        return NULL;
    /* Not timed here (fetch): the job's own span, from creation to its end. */
    double span = iso_unix_s(json_string_value(json_object_get(job, "finished"))) -
                  iso_unix_s(json_string_value(json_object_get(job, "created")));
    t->time_s = time_s > 0 ? time_s : isfinite(span) && span > 0 ? span : 0;
    const char *status = json_string_value(json_object_get(job, "status"));
    const char *id = json_string_value(json_object_get(job, "id"));
    junit_prop_str(t, "job", id);
    if (!status || strcmp(status, "done") != 0) {
        const char *error = json_string_value(json_object_get(job, "error"));
        junit_fail(t, JUNIT_JOB_FAILED, "job %s %s: %s", id ? id : "?", status ? status : "unknown",
                   error ? error : "");
        return t;
    }
    json_t *r = json_object_get(job, RK_RESULT);
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    char prop[32];
    for (int k = 0; k < 3; k++) {
        json_t *st = json_object_get(r, series[k]);
        if (!st)
            continue;
        snprintf(prop, sizeof(prop), "%s_median", series[k]);
        junit_prop_num(t, prop, json_number_value(json_object_get(st, RK_MEDIAN)));
        snprintf(prop, sizeof(prop), "%s_p95", series[k]);
        junit_prop_num(t, prop, json_number_value(json_object_get(st, RK_P95)));
    }
    junit_prop_num(t, RK_FPS, json_number_value(json_object_get(r, RK_FPS)));
    junit_prop_num(t, RK_WALL_S, json_number_value(json_object_get(r, RK_WALL_S)));
    junit_prop_str(t, "gl_renderer",
                   json_string_value(json_object_get(json_object_get(r, "device"), "gl_renderer")));
    junit_out(t, "job %s: frame_ms median %.4f, gpu_ms median %.4f, cpu_ms median %.4f, %.1f fps",
              id ? id : "?",
              json_number_value(json_object_get(json_object_get(r, RK_FRAME_MS), RK_MEDIAN)),
              json_number_value(json_object_get(json_object_get(r, RK_GPU_MS), RK_MEDIAN)),
              json_number_value(json_object_get(json_object_get(r, RK_CPU_MS), RK_MEDIAN)),
              json_number_value(json_object_get(r, RK_FPS)));
    return t;
}

void run_set_init(struct run_set *s, struct conn *c, const char *what)
{
    memset(s, 0, sizeof(*s));
    s->conn = c;
    s->what = what;
    s->jobs = json_array();
}

void run_set_finish(struct run_set *s)
{
    if (!s)
        return;
    free(s->runs);
    json_decref(s->jobs);
    json_decref(s->failed);
    memset(s, 0, sizeof(*s));
}

bool run_set_add(struct run_set *s, const struct options *o, const char *text,
                 const char *series, spec_check_fn check, void *ctx)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? s->cap * 2 : 8;
        struct gate_run *grown = realloc(s->runs, cap * sizeof(*grown));
        if (!grown)
            return false;
        s->runs = grown;
        s->cap = cap;
    }
    double start = clock_mono_s();
    json_t *reply = conn_json(s->conn, "POST", "/v1/jobs", text, NULL);
    if (!reply)
        return false;
    char id[64], path[128], what[128];
    snprintf(id, sizeof(id), "%s", json_string_value(json_object_get(reply, "id")) ?
                                       json_string_value(json_object_get(reply, "id")) : "");
    json_decref(reply);
    printf("%s\n", id);
    fflush(stdout);
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    /* A terminal gets the progress bar; a CI log gets one line a run, at
     * its end, instead of progress lines that would bury it. */
    bool bar = !o->quiet && term_is_tty(stderr);
    if (check) {
        json_t *queued = conn_json(s->conn, "GET", path, NULL, NULL);
        bool ok = queued && check(json_object_get(queued, "spec"), ctx);
        json_decref(queued);
        if (!ok) {
            json_decref(conn_json(s->conn, "DELETE", path, NULL, NULL));
            return false;
        }
    }
    /* "run 7 of up to 15": where this run stands in what may be run. */
    if (s->planned)
        snprintf(what, sizeof(what), "%s %zu of up to %zu, job %s", s->what, s->n + 1,
                 s->planned + (size_t)(s->budget > 0 ? s->budget : 0), id);
    else
        snprintf(what, sizeof(what), "%s %zu, job %s", s->what, s->n + 1, id);
    json_t *job = conn_follow_job(s->conn, id, what, !bar, o->timeout_s);
    if (!job)
        return false;
    double took = clock_mono_s() - start;
    s->elapsed_s += took;
    const char *status = json_string_value(json_object_get(job, "status"));
    if (!status || strcmp(status, "done") != 0) {
        json_decref(s->failed);
        s->failed = job;
        return true;
    }
    struct gate_run *r = &s->runs[s->n];
    if (!gate_run_from_result(json_object_get(job, RK_RESULT), id, series, r)) {
        fprintf(stderr, "shadebench: job %s has no %s figures\n", id, series);
        json_decref(job);
        return false;
    }
    r->elapsed_s = took;
    s->n++;
    json_array_append_new(s->jobs, job);
    if (!o->quiet) {
        char line[512];
        run_set_line(s, s->n - 1, series, line, sizeof(line));
        fprintf(stderr, "%s\n", line);
    }
    return true;
}

void run_set_line(const struct run_set *s, size_t i, const char *series, char *out, size_t cap)
{
    const struct gate_run *r = &s->runs[i];
    int used;
    if (s->planned && i >= s->planned)
        used = snprintf(out, cap, "%s %zu (extra %zu of at most %d): job %s, %s %.3f ms", s->what,
                        i + 1, i + 1 - s->planned, s->budget, r->job, series, r->ms);
    else if (s->planned)
        used = snprintf(out, cap, "%s %zu of %zu: job %s, %s %.3f ms", s->what, i + 1, s->planned,
                        r->job, series, r->ms);
    else
        used = snprintf(out, cap, "%s %zu: job %s, %s %.3f ms", s->what, i + 1, r->job, series,
                        r->ms);
    if (used < 0 || (size_t)used >= cap)
        return;
    if (r->has_share)
        used += snprintf(out + used, cap - (size_t)used, ", others took %.0f%% of the CPU%s",
                         100 * r->other_share, r->noisy_alone ? " (noisy on its own)" : "");
    else if (r->daemon_noisy)
        used += snprintf(out + used, cap - (size_t)used, ", flagged noisy by the daemon");
    if ((size_t)used < cap && r->elapsed_s > 0)
        snprintf(out + used, cap - (size_t)used, ", %.1f s", r->elapsed_s);
}

json_t *run_set_json(const struct run_set *s)
{
    json_t *list = json_array();
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    for (size_t i = 0; i < s->n; i++) {
        json_t *job = json_array_get(s->jobs, i);
        json_t *r = json_object_get(job, RK_RESULT);
        json_t *o = json_pack("{s:s}", "job", s->runs[i].job);
        for (int k = 0; k < 3; k++) {
            json_t *m = json_object_get(json_object_get(r, series[k]), RK_MEDIAN);
            if (json_is_number(m))
                json_object_set(o, series[k], m);
        }
        json_t *inter = json_object_get(r, RK_INTERFERENCE);
        if (inter)
            json_object_set(o, RK_INTERFERENCE, inter);
        json_object_set_new(o, "noisy", json_boolean(s->runs[i].noisy));
        if (s->runs[i].noisy)
            json_object_set_new(o, "why", json_string(s->runs[i].why));
        json_array_append_new(list, o);
    }
    return list;
}

bool run_set_write(const struct run_set *s, const char *dir)
{
    bool ok = true;
    char sub[4096];
    for (size_t i = 0; i < s->n; i++) {
        snprintf(sub, sizeof(sub), "%s/runs/%s", dir, s->runs[i].job);
        json_t *r = fetch_job_files(s->conn, json_array_get(s->jobs, i), sub, false, NULL);
        ok = r && ok;
        json_decref(r);
    }
    return ok;
}

void run_set_print(const struct run_set *s, const char *series, FILE *f)
{
    for (size_t i = 0; i < s->n; i++) {
        const struct gate_run *r = &s->runs[i];
        fprintf(f, "  %s %zu  job %s  %s %.4f ms", s->what, i + 1, r->job, series, r->ms);
        if (r->has_share)
            fprintf(f, "  other processes %.0f%% of the CPU", 100 * r->other_share);
        if (!isnan(r->load_start))
            fprintf(f, "  load %.2f -> %.2f", r->load_start, r->load_end);
        if (r->noisy)
            fprintf(f, "  NOISY, left out: %s", r->why);
        fputc('\n', f);
    }
}

int junit_conclude(const struct options *o, struct junit *j, const char *suite, double time_s)
{
    size_t failed = junit_real_failures(j), undecided = junit_undecided(j);
    size_t nothing = junit_judged_nothing(j);
    int rc = failed ? EXIT_FAIL : undecided && o->fail_inconclusive ? EXIT_INCONCLUSIVE : EXIT_PASS;
    if (!o->quiet) {
        junit_print(j, stderr, term_color(stderr));
        fprintf(stderr, "%zu checks: %zu passed, %zu failed, %zu inconclusive, %zu judged "
                "nothing\n", j->count, j->count - failed - undecided - nothing, failed, undecided,
                nothing);
        if (undecided && !failed)
            fprintf(stderr, "shadebench: warning: %zu check%s could not decide (too noisy to "
                    "tell); %s\n", undecided, undecided == 1 ? "" : "s",
                    o->fail_inconclusive
                        ? "exit status 3 (--fail-inconclusive or SHADEBENCH_FAIL_INCONCLUSIVE=1)"
                        : "exit status 0, but not a pass: JUnit marks it skipped "
                          "(--fail-inconclusive or SHADEBENCH_FAIL_INCONCLUSIVE=1 exits 3)");
        if (nothing)
            fprintf(stderr, "shadebench: warning: %zu check%s judged nothing (JUnit marks %s "
                    "skipped, not passed)\n", nothing, nothing == 1 ? "" : "s",
                    nothing == 1 ? "it" : "them");
    }
    if (o->junit && !junit_write(j, o->junit, suite, time_s)) {
        fprintf(stderr, "shadebench: cannot write %s\n", o->junit);
        rc = EXIT_ERROR;
    }
    return rc;
}
