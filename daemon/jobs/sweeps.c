#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/sweeps.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"
#include "common/stats.h"

struct sweep {
    char id[24];
    struct sweep_spec spec;
    json_t *body;    /* as posted */
    json_t *points;  /* the table, one object per point */
    json_t *result;  /* find: breaking_point */
    enum job_status status;
    char error[512];
    char current_job[24];
    atomic_bool cancel;
    double created, finished;
};

struct sweeps {
    struct queue *queue;
    const struct technique_catalog *techniques;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct sweep **all;
    size_t count, cap;
    unsigned serial;
    bool stopping;
};

/* One row of the table from a finished point job. */
static json_t *point_row(const json_t *job, json_t *values)
{
    json_t *r = json_object_get(job, "result");
    json_t *spec = json_object_get(job, "spec");
    json_t *row = json_pack("{s:o, s:s, s:s, s:O}", "values", values, "job",
                            json_string_value(json_object_get(job, "id")), "status",
                            json_string_value(json_object_get(job, "status")), "technique",
                            json_object_get(spec, "technique"));
    if (json_object_get(job, "error"))
        json_object_set(row, "error", json_object_get(job, "error"));
    if (!r)
        return row;
    json_t *rep = json_object_get(r, "repeat");
    static const char *const series[] = {"frame_ms", "gpu_ms", "cpu_ms"};
    for (int k = 0; k < 3; k++) {
        json_t *st = json_object_get(r, series[k]);
        json_t *across = rep ? json_object_get(rep, series[k]) : NULL;
        /* Repeated jobs: the mean of run medians and its interval; single runs:
         * the median and its distribution-free interval. */
        json_t *cell =
            across ? json_pack("{s:O, s:O, s:s}", "median", json_object_get(across, "mean"), "ci95",
                               json_object_get(across, "ci95"), "over", "runs")
                   : json_pack("{s:O, s:O, s:s}", "median", json_object_get(st, "median"), "ci95",
                               json_object_get(st, "median_ci95"), "over", "frames");
        /* The distribution of the (first run's) frames, for the charts. */
        static const char *const keep[] = {"min", "p5", "p95", "p99", "max"};
        for (int i = 0; i < 5; i++)
            json_object_set(cell, keep[i], json_object_get(st, keep[i]));
        json_object_set_new(row, series[k], cell);
    }
    if (rep)
        json_object_set(row, "stable", json_object_get(rep, "stable"));
    /* Execution time of the timed frames, over runs: what the thesis tabled. */
    json_t *runs = json_object_get(r, "runs");
    size_t nruns = runs ? json_array_size(runs) : 1;
    double *walls = malloc(nruns * sizeof(double));
    if (walls) {
        for (size_t i = 0; i < nruns; i++)
            walls[i] = json_number_value(json_object_get(runs ? json_array_get(runs, i) : r, "wall_s"));
        struct stats st;
        stats_compute(walls, nruns, &st);
        json_object_set_new(row, "wall_s", json_pack("{s:I, s:f, s:f, s:f}", "runs", (json_int_t)nruns,
                                                     "mean", st.mean, "median", st.median, "stddev",
                                                     st.stddev));
        free(walls);
    }
    json_t *q = json_object_get(r, "quality");
    if (q) {
        json_object_set(row, "worst_ssim", json_object_get(json_object_get(q, "worst_ssim"), "value"));
        json_object_set(row, "worst_ssim_min", json_object_get(json_object_get(q, "worst_ssim_min"), "value"));
        json_object_set(row, "worst_flip", json_object_get(json_object_get(q, "worst_flip"), "mean"));
        json_object_set(row, "pdiff_failed_captures", json_object_get(q, "pdiff_failed_captures"));
    }
    return row;
}

/* Submits one point job and waits for it. Returns the finished job JSON, or
 * NULL when the sweep was cancelled or the job could not be submitted. */
static json_t *run_point(struct sweeps *s, struct sweep *sw, json_t *job_body)
{
    struct job_spec spec;
    struct job_error err;
    if (!job_spec_parse(job_body, s->techniques, &spec, &err)) {
        snprintf(sw->error, sizeof(sw->error), "point job refused: %s: %s", err.field, err.message);
        return NULL;
    }
    char id[24];
    for (;;) {
        if (atomic_load(&sw->cancel))
            return NULL;
        enum queue_submit_result r = queue_submit(s->queue, &spec, NULL, id);
        if (r == QUEUE_OK)
            break;
        if (r != QUEUE_FULL) {
            snprintf(sw->error, sizeof(sw->error), "cannot queue a point job");
            return NULL;
        }
        sleep(1); /* the job queue is full: wait for room */
    }
    pthread_mutex_lock(&s->lock);
    snprintf(sw->current_job, sizeof(sw->current_job), "%s", id);
    pthread_mutex_unlock(&s->lock);
    for (;;) {
        json_t *job = queue_job_json(s->queue, id, 1.0);
        const char *st = job ? json_string_value(json_object_get(job, "status")) : "failed";
        if (job && (strcmp(st, "queued") == 0 || strcmp(st, "running") == 0)) {
            json_decref(job);
            if (atomic_load(&sw->cancel))
                queue_cancel(s->queue, id);
            continue;
        }
        return job;
    }
}

static void add_row(struct sweeps *s, struct sweep *sw, json_t *row)
{
    pthread_mutex_lock(&s->lock);
    json_array_append_new(sw->points, row);
    sw->current_job[0] = '\0';
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
}

struct probe_ctx {
    struct sweeps *s;
    struct sweep *sw;
};

static int probe(double v, void *arg)
{
    struct probe_ctx *c = arg;
    json_t *body = sweep_probe_job(&c->sw->spec, v);
    json_t *job = run_point(c->s, c->sw, body);
    json_decref(body);
    if (!job)
        return -1;
    json_t *values = json_object();
    json_object_set_new(values, c->sw->spec.params[0],
                        c->sw->spec.integer ? json_integer((json_int_t)v) : json_real(v));
    json_t *row = point_row(job, values);
    int holds = -1;
    if (strcmp(json_string_value(json_object_get(job, "status")), "done") == 0)
        holds = sweep_criterion_holds(&c->sw->spec, json_object_get(job, "result"));
    else
        snprintf(c->sw->error, sizeof(c->sw->error), "probe at %g %s: %s", v,
                 json_string_value(json_object_get(job, "status")),
                 json_string_value(json_object_get(job, "error")) ? json_string_value(json_object_get(job, "error")) : "");
    if (holds >= 0)
        json_object_set_new(row, "criterion_holds", json_boolean(holds));
    add_row(c->s, c->sw, row);
    json_decref(job);
    return holds;
}

static void run_sweep(struct sweeps *s, struct sweep *sw)
{
    bool ok = true;
    if (sw->spec.kind == SWEEP_VARY) {
        json_t *passing = json_array();
        for (size_t i = 0; ok && i < sw->spec.npoints; i++) {
            json_t *values, *body = sweep_point_job(&sw->spec, i, &values);
            json_t *job = run_point(s, sw, body);
            json_decref(body);
            if (!job) {
                json_decref(values);
                ok = false;
                break;
            }
            json_t *row = point_row(job, values);
            if (json_is_integer(json_object_get(row, "pdiff_failed_captures")) &&
                json_integer_value(json_object_get(row, "pdiff_failed_captures")) == 0)
                json_array_append(passing, json_object_get(row, "values"));
            add_row(s, sw, row);
            json_decref(job);
        }
        /* With one numeric parameter, the question the thesis answered by hand:
         * the largest value whose captures all pass PerceptualDiff. */
        json_t *best = NULL;
        size_t k;
        json_t *values;
        if (sw->spec.nparams == 1)
            json_array_foreach(passing, k, values) {
                json_t *v = json_object_get(values, sw->spec.params[0]);
                if (json_is_number(v) && (!best || json_number_value(v) > json_number_value(best)))
                    best = v;
            }
        pthread_mutex_lock(&s->lock);
        sw->result = json_pack("{s:o}", "pdiff_passing", passing);
        if (sw->spec.nparams == 1)
            json_object_set_new(sw->result, "largest_pdiff_pass",
                                json_pack("{s:s, s:O}", "param", sw->spec.params[0], "value",
                                          best ? best : json_null()));
        pthread_mutex_unlock(&s->lock);
    } else {
        struct probe_ctx ctx = {s, sw};
        struct bisect_result r;
        sweep_bisect(sw->spec.from, sw->spec.to, sw->spec.integer, sw->spec.max_probes, probe, &ctx, &r);
        static const char *const outcomes[] = {"boundary", "holds everywhere", "fails everywhere",
                                               "aborted"};
        json_t *value = r.outcome == BISECT_FAILS_EVERYWHERE || r.outcome == BISECT_ABORTED
                            ? json_null()
                            : (sw->spec.integer ? json_integer((json_int_t)r.value) : json_real(r.value));
        json_t *bp = json_pack("{s:s, s:o, s:s, s:s, s:i}", "param", sw->spec.params[0], "value", value,
                               "criterion", sw->spec.criterion_text, "outcome", outcomes[r.outcome],
                               "probes", r.probes);
        if (r.outcome == BISECT_BOUNDARY)
            json_object_set_new(bp, "first_failing", sw->spec.integer ? json_integer((json_int_t)r.first_failing)
                                                                      : json_real(r.first_failing));
        pthread_mutex_lock(&s->lock);
        sw->result = json_pack("{s:o}", "breaking_point", bp);
        pthread_mutex_unlock(&s->lock);
        ok = r.outcome != BISECT_ABORTED;
    }
    pthread_mutex_lock(&s->lock);
    sw->status = ok ? JOB_DONE : (atomic_load(&sw->cancel) ? JOB_CANCELLED : JOB_FAILED);
    if (sw->status == JOB_CANCELLED)
        snprintf(sw->error, sizeof(sw->error), "cancelled; the finished points stay");
    sw->finished = clock_unix_s();
    sw->current_job[0] = '\0';
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
    LOG(LOG_INFO, "sweep %s %s (%zu points)", sw->id, job_status_name(sw->status),
        json_array_size(sw->points));
}

static void *sweeps_main(void *arg)
{
    struct sweeps *s = arg;
    pthread_mutex_lock(&s->lock);
    for (;;) {
        struct sweep *next = NULL;
        for (size_t i = 0; i < s->count && !next; i++)
            if (s->all[i]->status == JOB_QUEUED)
                next = s->all[i];
        if (s->stopping)
            break;
        if (!next) {
            pthread_cond_wait(&s->changed, &s->lock);
            continue;
        }
        next->status = JOB_RUNNING;
        pthread_mutex_unlock(&s->lock);
        run_sweep(s, next);
        pthread_mutex_lock(&s->lock);
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

struct sweeps *sweeps_create(struct queue *q, const struct technique_catalog *techniques)
{
    struct sweeps *s = calloc(1, sizeof(*s));
    if (!s)
        return NULL;
    s->queue = q;
    s->techniques = techniques;
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->changed, NULL);
    if (pthread_create(&s->thread, NULL, sweeps_main, s) != 0) {
        free(s);
        return NULL;
    }
    return s;
}

void sweeps_destroy(struct sweeps *s)
{
    if (!s)
        return;
    pthread_mutex_lock(&s->lock);
    s->stopping = true;
    for (size_t i = 0; i < s->count; i++)
        atomic_store(&s->all[i]->cancel, true);
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
    pthread_join(s->thread, NULL);
    for (size_t i = 0; i < s->count; i++) {
        sweep_spec_finish(&s->all[i]->spec);
        json_decref(s->all[i]->body);
        json_decref(s->all[i]->points);
        json_decref(s->all[i]->result);
        free(s->all[i]);
    }
    free(s->all);
    pthread_cond_destroy(&s->changed);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

bool sweeps_submit(struct sweeps *s, struct sweep_spec *spec, const json_t *body, char id_out[24])
{
    pthread_mutex_lock(&s->lock);
    size_t waiting = 0;
    for (size_t i = 0; i < s->count; i++)
        waiting += s->all[i]->status == JOB_QUEUED;
    struct sweep *sw = NULL;
    if (waiting >= SWEEPS_MAX_WAITING || s->stopping)
        goto out;
    if (s->count == s->cap) {
        size_t cap = s->cap ? s->cap * 2 : 16;
        struct sweep **all = realloc(s->all, cap * sizeof(*all));
        if (!all)
            goto out;
        s->all = all;
        s->cap = cap;
    }
    if (!(sw = calloc(1, sizeof(*sw))))
        goto out;
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    char stamp[16];
    strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &tm);
    snprintf(sw->id, sizeof(sw->id), "%.15s-%04u", stamp, ++s->serial % 10000u);
    sw->spec = *spec;
    memset(spec, 0, sizeof(*spec));
    sw->body = json_deep_copy(body);
    sw->points = json_array();
    sw->status = JOB_QUEUED;
    sw->created = clock_unix_s();
    atomic_init(&sw->cancel, false);
    s->all[s->count++] = sw;
    snprintf(id_out, 24, "%s", sw->id);
    pthread_cond_broadcast(&s->changed);
out:
    pthread_mutex_unlock(&s->lock);
    return sw != NULL;
}

static struct sweep *find_locked(struct sweeps *s, const char *id)
{
    for (size_t i = 0; i < s->count; i++)
        if (strcmp(s->all[i]->id, id) == 0)
            return s->all[i];
    return NULL;
}

static json_t *sweep_json_locked(const struct sweep *sw, bool full)
{
    char url[64];
    snprintf(url, sizeof(url), "/v1/sweeps/%s", sw->id);
    json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:{s:I, s:I}}", "id", sw->id, "url", url, "kind",
                          sw->spec.kind == SWEEP_VARY ? "vary" : "find", "status",
                          job_status_name(sw->status), "progress", "points_done",
                          (json_int_t)json_array_size(sw->points), "points_total",
                          (json_int_t)sw->spec.npoints);
    if (sw->current_job[0])
        json_object_set_new(o, "current_job", json_string(sw->current_job));
    if (sw->spec.thesis)
        json_object_set_new(o, "preset", json_string("thesis"));
    if (sw->error[0])
        json_object_set_new(o, "error", json_string(sw->error));
    if (full) {
        json_object_set(o, "spec", sw->body);
        json_object_set(o, "points", sw->points);
        if (sw->result)
            json_object_set(o, "result", sw->result);
    }
    return o;
}

static bool sweep_finished(const struct sweep *sw)
{
    return sw->status != JOB_QUEUED && sw->status != JOB_RUNNING;
}

json_t *sweeps_json(struct sweeps *s, const char *id, double wait_s)
{
    struct timespec deadline = clock_deadline(wait_s);
    pthread_mutex_lock(&s->lock);
    struct sweep *sw = find_locked(s, id);
    while (sw && wait_s > 0 && !sweep_finished(sw) && !s->stopping)
        if (pthread_cond_timedwait(&s->changed, &s->lock, &deadline) == ETIMEDOUT)
            break;
    /* A deep copy: the sweep thread keeps appending to the live table. */
    json_t *live = sw ? sweep_json_locked(sw, true) : NULL;
    json_t *o = live ? json_deep_copy(live) : NULL;
    json_decref(live);
    pthread_mutex_unlock(&s->lock);
    return o;
}

json_t *sweeps_list_json(struct sweeps *s)
{
    json_t *list = json_array();
    pthread_mutex_lock(&s->lock);
    for (size_t i = 0; i < s->count; i++)
        json_array_append_new(list, sweep_json_locked(s->all[i], false));
    pthread_mutex_unlock(&s->lock);
    return json_pack("{s:o}", "sweeps", list);
}

enum queue_cancel_result sweeps_cancel(struct sweeps *s, const char *id)
{
    enum queue_cancel_result r = CANCEL_NOT_FOUND;
    pthread_mutex_lock(&s->lock);
    struct sweep *sw = find_locked(s, id);
    if (sw) {
        if (sweep_finished(sw)) {
            r = CANCEL_FINISHED;
        } else if (sw->status == JOB_QUEUED) {
            sw->status = JOB_CANCELLED;
            sw->finished = clock_unix_s();
            snprintf(sw->error, sizeof(sw->error), "cancelled before it started");
            r = CANCEL_DONE;
            pthread_cond_broadcast(&s->changed);
        } else {
            atomic_store(&sw->cancel, true);
            r = CANCEL_REQUESTED;
        }
    }
    pthread_mutex_unlock(&s->lock);
    return r;
}
