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
#include "daemon/jobs/records.h"
#include "common/result_keys.h"

struct sweep {
    char id[RECORD_ID_LEN];
    char dir[PATH_MAX]; /* STATE_DIR/sweeps/ID: sweep.json */
    struct sweep_spec spec;
    json_t *body;    /* as posted */
    json_t *points;  /* the table, one object per point */
    json_t *result;  /* find: breaking_point */
    enum job_status status;
    char error[512];
    char current_job[RECORD_ID_LEN];
    /* Resumed after a stop: the point job that was running then, which the
     * store requeued; the sweep thread waits for it instead of running the
     * point twice. Sweep thread only. */
    char adopt_job[RECORD_ID_LEN];
    atomic_bool cancel; /* DELETE */
    double created, finished;
    /* Under the sweeps' lock: ordered writes, as for jobs (records.h). */
    uint64_t seq;
    unsigned pending;
    struct record_writer writer;
};

struct sweeps {
    struct queue *queue;
    const struct technique_catalog *techniques;
    pthread_t thread;
    /* Guards the list and the sweeps' state; never held across file I/O. */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct sweep **all; /* in id order */
    size_t count, cap;
    int reserved; /* submissions writing their first record */
    atomic_bool stopping;
    struct record_kind kind; /* STATE_DIR/sweeps/ID/sweep.json */
};

/* A sweep's state taken under the lock, written after it. */
struct snapshot {
    struct sweep *sw;
    uint64_t seq;
    json_t *json;
};

static json_t *sweep_json_locked(const struct sweep *sw, bool full);
static void apply_retention(struct sweeps *s);

static bool sweep_finished(const struct sweep *sw)
{
    return sw->status != JOB_QUEUED && sw->status != JOB_RUNNING;
}

/* sweep.json: what GET /v1/sweeps/ID shows, plus the times. A deep copy:
 * the sweep thread keeps appending to the live table. */
static json_t *sweep_record_locked(const struct sweep *sw)
{
    json_t *live = sweep_json_locked(sw, true);
    json_t *o = live ? json_deep_copy(live) : NULL;
    json_decref(live);
    if (o)
        json_object_set_new(o, "times_unix", json_pack("[f, f]", sw->created, sw->finished));
    return o;
}

static void snapshot_locked(struct sweep *sw, struct snapshot *snap)
{
    snap->sw = sw;
    snap->seq = ++sw->seq;
    snap->json = sweep_record_locked(sw);
    sw->pending++;
}

static bool write_snapshot(struct sweeps *s, struct snapshot *snap, char *err, size_t errlen)
{
    struct sweep *sw = snap->sw;
    char path[PATH_MAX + 16], why[PATH_MAX + 128] = "";
    snprintf(path, sizeof(path), "%s/sweep.json", sw->dir);
    bool ok = snap->json && record_writer_write(&sw->writer, snap->seq, path, snap->json, why,
                                                sizeof(why));
    if (!snap->json)
        snprintf(why, sizeof(why), "cannot write %s: out of memory", path);
    if (!ok)
        LOG(LOG_ERROR, "sweep %s: %s (its state in memory stays right; written again at exit)",
            sw->id, why);
    if (err)
        snprintf(err, errlen, "%s", why);
    json_decref(snap->json);
    snap->json = NULL;
    pthread_mutex_lock(&s->lock);
    sw->pending--;
    pthread_mutex_unlock(&s->lock);
    return ok;
}

/* Under the lock: the sweep changed; write it once the lock is released. */
static void changed_locked(struct sweeps *s, struct sweep *sw, struct snapshot *snap)
{
    snapshot_locked(sw, snap);
    pthread_cond_broadcast(&s->changed);
}

static struct sweep *sweep_new(void)
{
    struct sweep *sw = calloc(1, sizeof(*sw));
    if (!sw)
        return NULL;
    atomic_init(&sw->cancel, false);
    record_writer_init(&sw->writer);
    return sw;
}

static void sweep_free(struct sweep *sw)
{
    if (!sw)
        return;
    sweep_spec_finish(&sw->spec);
    json_decref(sw->body);
    json_decref(sw->points);
    json_decref(sw->result);
    record_writer_finish(&sw->writer);
    free(sw);
}

static bool insert_locked(struct sweeps *s, struct sweep *sw)
{
    if (s->count == s->cap) {
        size_t cap = s->cap ? s->cap * 2 : 16;
        struct sweep **all = realloc(s->all, cap * sizeof(*all));
        if (!all)
            return false;
        s->all = all;
        s->cap = cap;
    }
    size_t at = s->count;
    while (at > 0 && strcmp(s->all[at - 1]->id, sw->id) > 0)
        at--;
    memmove(s->all + at + 1, s->all + at, (s->count - at) * sizeof(*s->all));
    s->all[at] = sw;
    s->count++;
    return true;
}

/* One row of the table from a finished point job. */
static json_t *point_row(const json_t *job, json_t *values)
{
    json_t *r = json_object_get(job, RK_RESULT);
    json_t *spec = json_object_get(job, "spec");
    json_t *row = json_pack("{s:o, s:s, s:s, s:O}", "values", values, "job",
                            json_string_value(json_object_get(job, "id")), "status",
                            json_string_value(json_object_get(job, "status")), "technique",
                            json_object_get(spec, "technique"));
    if (json_object_get(job, "error"))
        json_object_set(row, "error", json_object_get(job, "error"));
    if (!r)
        return row;
    json_t *rep = json_object_get(r, RK_REPEAT);
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    for (int k = 0; k < 3; k++) {
        json_t *st = json_object_get(r, series[k]);
        json_t *across = rep ? json_object_get(rep, series[k]) : NULL;
        /* Repeated jobs: the mean of run medians and its interval; single runs:
         * the median and its distribution-free interval. */
        json_t *cell =
            across ? json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(across, RK_MEAN), RK_CI95,
                               json_object_get(across, RK_CI95), "over", "runs")
                   : json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(st, RK_MEDIAN), RK_CI95,
                               json_object_get(st, RK_MEDIAN_CI95), "over", "frames");
        /* The distribution of the (first run's) frames, for the charts. */
        static const char *const keep[] = {RK_MIN, RK_P5, RK_P95, RK_P99, RK_MAX};
        for (int i = 0; i < 5; i++)
            json_object_set(cell, keep[i], json_object_get(st, keep[i]));
        json_object_set_new(row, series[k], cell);
    }
    if (rep)
        json_object_set(row, RK_STABLE, json_object_get(rep, RK_STABLE));
    /* Execution time of the timed frames, over runs: what the thesis tabled. */
    json_t *runs = json_object_get(r, RK_RUNS);
    size_t nruns = runs ? json_array_size(runs) : 1;
    double *walls = malloc(nruns * sizeof(double));
    if (walls) {
        for (size_t i = 0; i < nruns; i++)
            walls[i] = json_number_value(json_object_get(runs ? json_array_get(runs, i) : r, RK_WALL_S));
        struct stats st;
        stats_compute(walls, nruns, &st);
        json_object_set_new(row, RK_WALL_S, json_pack("{s:I, s:f, s:f, s:f}", RK_RUNS, (json_int_t)nruns,
                                                     RK_MEAN, st.mean, RK_MEDIAN, st.median, RK_STDDEV,
                                                     st.stddev));
        free(walls);
    }
    json_t *q = json_object_get(r, RK_QUALITY);
    if (q) {
        json_object_set(row, RK_WORST_SSIM, json_object_get(json_object_get(q, RK_WORST_SSIM), "value"));
        json_object_set(row, RK_WORST_SSIM_MIN, json_object_get(json_object_get(q, RK_WORST_SSIM_MIN), "value"));
        json_object_set(row, RK_WORST_FLIP, json_object_get(json_object_get(q, RK_WORST_FLIP), "mean"));
        json_object_set(row, RK_PDIFF_FAILED_CAPTURES, json_object_get(q, RK_PDIFF_FAILED_CAPTURES));
    }
    /* Post hook: the worst capture's non-finite pixels, for breaking points. */
    json_t *nonfinite = json_object_get(r, RK_NONFINITE);
    if (nonfinite)
        json_object_set(row, "nonfinite_pixels", json_object_get(nonfinite, RK_PIXELS_MAX));
    /* Bounded light lists and the shadow atlas: where they overflow. */
    json_int_t lists, shadows;
    sweep_overflow_frames(r, &lists, &shadows);
    if (lists >= 0)
        json_object_set_new(row, "light_overflow_frames", json_integer(lists));
    if (shadows >= 0)
        json_object_set_new(row, "shadow_drop_frames", json_integer(shadows));
    return row;
}

/* Resumed after a stop: the point job that was queued or running then is
 * still in the store (requeued, same spec); returns its id to wait for, or
 * "" to submit the point afresh. */
static void adopt_point_job(struct sweeps *s, struct sweep *sw, const struct job_spec *spec,
                            char id[RECORD_ID_LEN])
{
    id[0] = '\0';
    if (!sw->adopt_job[0])
        return;
    json_t *job = queue_job_json(s->queue, sw->adopt_job, 0);
    json_t *want = job_spec_to_json(spec);
    const char *st = job ? json_string_value(json_object_get(job, "status")) : NULL;
    if (st && json_equal(json_object_get(job, "spec"), want) &&
        (strcmp(st, "queued") == 0 || strcmp(st, "running") == 0 || strcmp(st, "done") == 0)) {
        snprintf(id, RECORD_ID_LEN, "%s", sw->adopt_job);
        LOG(LOG_INFO, "sweep %s: resumes with its point job %s (%s)", sw->id, id, st);
    }
    json_decref(job);
    json_decref(want);
    sw->adopt_job[0] = '\0';
}

/* Submits one point job and waits for it. Returns the finished job JSON, or
 * NULL when the sweep was cancelled or stopped, or the job could not be
 * submitted. On a stop the job is left in the store: it is requeued and
 * this sweep adopts it when it resumes. */
static json_t *run_point(struct sweeps *s, struct sweep *sw, json_t *job_body)
{
    struct job_spec spec;
    struct job_error err;
    if (!job_spec_parse(job_body, s->techniques, &spec, &err)) {
        snprintf(sw->error, sizeof(sw->error), "point job refused: %s: %s", err.field, err.message);
        return NULL;
    }
    char id[RECORD_ID_LEN];
    adopt_point_job(s, sw, &spec, id);
    while (!id[0]) {
        if (atomic_load(&sw->cancel) || atomic_load(&s->stopping))
            return NULL;
        enum queue_submit_result r = queue_submit(s->queue, &spec, NULL, id);
        if (r == QUEUE_OK)
            break;
        id[0] = '\0';
        if (r == QUEUE_IO_ERROR) {
            snprintf(sw->error, sizeof(sw->error), "cannot queue a point job: %.400s",
                     queue_submit_error());
            return NULL;
        }
        if (r != QUEUE_FULL) {
            snprintf(sw->error, sizeof(sw->error), "cannot queue a point job");
            return NULL;
        }
        sleep(1); /* the job queue is full: wait for room */
    }
    struct snapshot snap;
    pthread_mutex_lock(&s->lock);
    snprintf(sw->current_job, sizeof(sw->current_job), "%s", id);
    changed_locked(s, sw, &snap); /* so that a restart knows which job to adopt */
    pthread_mutex_unlock(&s->lock);
    write_snapshot(s, &snap, NULL, 0);
    for (;;) {
        json_t *job = queue_job_json(s->queue, id, 1.0);
        const char *st = job ? json_string_value(json_object_get(job, "status")) : "failed";
        if (job && (strcmp(st, "queued") == 0 || strcmp(st, "running") == 0)) {
            json_decref(job);
            if (atomic_load(&s->stopping))
                return NULL;
            if (atomic_load(&sw->cancel))
                queue_cancel(s->queue, id);
            continue;
        }
        return job;
    }
}

static void add_row(struct sweeps *s, struct sweep *sw, json_t *row)
{
    struct snapshot snap;
    pthread_mutex_lock(&s->lock);
    json_array_append_new(sw->points, row);
    sw->current_job[0] = '\0';
    changed_locked(s, sw, &snap);
    pthread_mutex_unlock(&s->lock);
    write_snapshot(s, &snap, NULL, 0);
}

struct probe_ctx {
    struct sweeps *s;
    struct sweep *sw;
};

/* A resumed find: the probes made before the stop are in the table. */
static bool cached_probe(struct sweep *sw, double v, int *holds)
{
    size_t i;
    json_t *row;
    json_array_foreach(sw->points, i, row) {
        json_t *value = json_object_get(json_object_get(row, "values"), sw->spec.params[0]);
        if (json_is_number(value) && json_number_value(value) == v) {
            json_t *h = json_object_get(row, "criterion_holds");
            *holds = json_is_boolean(h) ? json_is_true(h) : -1;
            return true;
        }
    }
    return false;
}

static int probe(double v, void *arg)
{
    struct probe_ctx *c = arg;
    int holds = -1;
    if (cached_probe(c->sw, v, &holds))
        return holds;
    json_t *body = sweep_probe_job(&c->sw->spec, v);
    json_t *job = run_point(c->s, c->sw, body);
    json_decref(body);
    if (!job)
        return -1;
    json_t *values = json_object();
    json_object_set_new(values, c->sw->spec.params[0],
                        c->sw->spec.integer ? json_integer((json_int_t)v) : json_real(v));
    json_t *row = point_row(job, values);
    const char *unjudged = NULL;
    if (strcmp(json_string_value(json_object_get(job, "status")), "done") != 0)
        snprintf(c->sw->error, sizeof(c->sw->error), "probe at %g %s: %s", v,
                 json_string_value(json_object_get(job, "status")),
                 json_string_value(json_object_get(job, "error")) ? json_string_value(json_object_get(job, "error")) : "");
    else if ((unjudged = sweep_criterion_unjudged(&c->sw->spec, json_object_get(job, RK_RESULT))))
        snprintf(c->sw->error, sizeof(c->sw->error), "find.while: %s", unjudged);
    else
        holds = sweep_criterion_holds(&c->sw->spec, json_object_get(job, RK_RESULT));
    if (holds >= 0)
        json_object_set_new(row, "criterion_holds", json_boolean(holds));
    add_row(c->s, c->sw, row);
    json_decref(job);
    return holds;
}

/* With one numeric parameter, the question the thesis answered by hand:
 * the largest value whose captures all pass PerceptualDiff. Over the whole
 * table, so that a resumed sweep counts the points run before the stop. */
static json_t *vary_result(const struct sweep *sw)
{
    json_t *passing = json_array(), *best = NULL, *row;
    size_t i;
    json_array_foreach(sw->points, i, row) {
        json_t *failed = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
        if (json_is_integer(failed) && json_integer_value(failed) == 0)
            json_array_append(passing, json_object_get(row, "values"));
    }
    json_t *res = json_pack("{s:o}", "pdiff_passing", passing);
    if (sw->spec.nparams == 1) {
        json_t *values;
        json_array_foreach(passing, i, values) {
            json_t *v = json_object_get(values, sw->spec.params[0]);
            if (json_is_number(v) && (!best || json_number_value(v) > json_number_value(best)))
                best = v;
        }
        json_object_set_new(res, "largest_pdiff_pass",
                            json_pack("{s:s, s:O}", "param", sw->spec.params[0], "value",
                                      best ? best : json_null()));
    }
    return res;
}

static void run_sweep(struct sweeps *s, struct sweep *sw)
{
    bool ok = true;
    json_t *result = NULL;
    if (sw->spec.kind == SWEEP_VARY) {
        /* A resumed sweep goes on after the points it has. */
        for (size_t i = json_array_size(sw->points); ok && i < sw->spec.npoints; i++) {
            json_t *values, *body = sweep_point_job(&sw->spec, i, &values);
            json_t *job = run_point(s, sw, body);
            json_decref(body);
            if (!job) {
                json_decref(values);
                ok = false;
                break;
            }
            add_row(s, sw, point_row(job, values));
            json_decref(job);
        }
        if (ok)
            result = vary_result(sw);
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
        result = json_pack("{s:o}", "breaking_point", bp);
        ok = r.outcome != BISECT_ABORTED;
    }
    struct snapshot snap;
    pthread_mutex_lock(&s->lock);
    bool stopped = !ok && atomic_load(&s->stopping) && !atomic_load(&sw->cancel);
    if (stopped) {
        /* The daemon is stopping, not the sweep failing: it goes back to the
         * queue and resumes on the next start, current_job and all. */
        json_decref(result);
        sw->status = JOB_QUEUED;
        sw->error[0] = '\0';
    } else {
        json_decref(sw->result);
        sw->result = result;
        sw->status = ok ? JOB_DONE : (atomic_load(&sw->cancel) ? JOB_CANCELLED : JOB_FAILED);
        if (sw->status == JOB_CANCELLED)
            snprintf(sw->error, sizeof(sw->error), "cancelled; the finished points stay");
        sw->finished = clock_unix_s();
        sw->current_job[0] = '\0';
    }
    changed_locked(s, sw, &snap);
    pthread_mutex_unlock(&s->lock);
    write_snapshot(s, &snap, NULL, 0);
    if (stopped)
        LOG(LOG_INFO, "sweep %s: stopped with the daemon after %zu points; resumes on the next start",
            sw->id, json_array_size(sw->points));
    else
        LOG(LOG_INFO, "sweep %s %s (%zu points)", sw->id, job_status_name(sw->status),
            json_array_size(sw->points));
    apply_retention(s);
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
        if (atomic_load(&s->stopping))
            break;
        if (!next) {
            pthread_cond_wait(&s->changed, &s->lock);
            continue;
        }
        struct snapshot snap;
        next->status = JOB_RUNNING;
        changed_locked(s, next, &snap);
        pthread_mutex_unlock(&s->lock);
        write_snapshot(s, &snap, NULL, 0);
        run_sweep(s, next);
        pthread_mutex_lock(&s->lock);
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

static bool status_from_name(const char *name, enum job_status *out)
{
    for (int st = JOB_QUEUED; st <= JOB_INTERRUPTED; st++)
        if (name && strcmp(name, job_status_name((enum job_status)st)) == 0) {
            *out = (enum job_status)st;
            return true;
        }
    return false;
}

/* Startup: one sweep's record. Whatever cannot be read is quarantined. */
static void load_sweep(void *ctx, const char *id, const char *dir)
{
    struct sweeps *s = ctx;
    char path[PATH_MAX + 16], why[600] = "";
    snprintf(path, sizeof(path), "%s/sweep.json", dir);
    json_t *o = record_read(path, why, sizeof(why));
    struct sweep *sw = NULL;
    enum job_status status = JOB_FAILED;
    struct job_error jerr;
    if (o) {
        const char *rid = json_string_value(json_object_get(o, "id"));
        json_t *points = json_object_get(o, "points");
        if (!rid || strcmp(rid, id) != 0)
            snprintf(why, sizeof(why), "its id does not match its directory");
        else if (!status_from_name(json_string_value(json_object_get(o, "status")), &status))
            snprintf(why, sizeof(why), "no valid status");
        else if (!json_is_array(points))
            snprintf(why, sizeof(why), "no points table");
        else if (!(sw = sweep_new()))
            snprintf(why, sizeof(why), "out of memory");
        else if (!sweep_spec_parse(json_object_get(o, "spec"), s->techniques, &sw->spec, &jerr))
            snprintf(why, sizeof(why), "not a sweep this daemon can read (%s: %s)", jerr.field,
                     jerr.message);
    }
    if (why[0]) {
        json_decref(o);
        sweep_free(sw);
        char reason[800];
        snprintf(reason, sizeof(reason), "sweep.json: %s", why);
        record_quarantine(&s->kind, id, dir, reason, NULL, 0);
        return;
    }
    snprintf(sw->id, sizeof(sw->id), "%s", id);
    snprintf(sw->dir, sizeof(sw->dir), "%s", dir);
    sw->body = json_incref(json_object_get(o, "spec"));
    sw->points = json_incref(json_object_get(o, "points"));
    sw->result = json_incref(json_object_get(o, RK_RESULT));
    sw->status = status;
    json_t *times = json_object_get(o, "times_unix");
    sw->created = json_number_value(json_array_get(times, 0));
    sw->finished = json_number_value(json_array_get(times, 1));
    const char *error = json_string_value(json_object_get(o, "error"));
    const char *current = json_string_value(json_object_get(o, "current_job"));
    if (error)
        snprintf(sw->error, sizeof(sw->error), "%s", error);
    if (current && record_id_valid(current))
        snprintf(sw->current_job, sizeof(sw->current_job), "%s", current);
    json_decref(o);
    bool changed = false;
    if (sw->status == JOB_RUNNING) {
        /* Killed or crashed: its point job is interrupted too (queue.c). */
        sw->status = JOB_INTERRUPTED;
        sw->finished = clock_unix_s();
        sw->current_job[0] = '\0';
        snprintf(sw->error, sizeof(sw->error),
                 "interrupted: the daemon stopped (killed or crashed) while this sweep ran; "
                 "its %zu finished points stay, submit it again to run the rest",
                 json_array_size(sw->points));
        changed = true;
    } else if (sw->status == JOB_QUEUED && sw->current_job[0]) {
        snprintf(sw->adopt_job, sizeof(sw->adopt_job), "%s", sw->current_job);
    }
    record_note_id(&s->kind, id);
    struct snapshot snap = {0};
    pthread_mutex_lock(&s->lock);
    bool inserted = insert_locked(s, sw);
    if (inserted && changed)
        snapshot_locked(sw, &snap);
    pthread_mutex_unlock(&s->lock);
    if (!inserted) {
        LOG(LOG_ERROR, "sweep %s: out of memory loading it", id);
        sweep_free(sw);
        return;
    }
    if (snap.sw)
        write_snapshot(s, &snap, NULL, 0);
}

struct sweeps *sweeps_create(struct queue *q, const struct technique_catalog *techniques)
{
    struct sweeps *s = calloc(1, sizeof(*s));
    if (!s)
        return NULL;
    s->queue = q;
    s->techniques = techniques;
    atomic_init(&s->stopping, false);
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->changed, NULL);
    record_kind_init(&s->kind, queue_state_dir(q), "sweeps", "sweep.json");
    char err[PATH_MAX + 64];
    int loaded = record_scan(&s->kind, load_sweep, s, err, sizeof(err));
    if (loaded < 0)
        LOG(LOG_ERROR, "sweeps: %s; none reloaded", err);
    else if (loaded > 0)
        LOG(LOG_INFO, "loaded %d sweep(s) from %s", loaded, s->kind.root);
    apply_retention(s);
    if (pthread_create(&s->thread, NULL, sweeps_main, s) != 0) {
        for (size_t i = 0; i < s->count; i++)
            sweep_free(s->all[i]);
        free(s->all);
        pthread_cond_destroy(&s->changed);
        pthread_mutex_destroy(&s->lock);
        free(s);
        return NULL;
    }
    return s;
}

void sweeps_destroy(struct sweeps *s)
{
    if (!s)
        return;
    /* A stop, not a cancel: the running sweep returns to the queue and its
     * point job is left to the store, which requeues it. */
    pthread_mutex_lock(&s->lock);
    atomic_store(&s->stopping, true);
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
    pthread_join(s->thread, NULL);
    for (size_t i = 0; i < s->count; i++) {
        struct sweep *sw = s->all[i];
        if (sw->writer.written < sw->seq) { /* a full disk held it back: one more try */
            struct snapshot snap;
            pthread_mutex_lock(&s->lock);
            snap.sw = sw;
            snap.seq = sw->seq;
            snap.json = sweep_record_locked(sw);
            sw->pending++;
            pthread_mutex_unlock(&s->lock);
            write_snapshot(s, &snap, NULL, 0);
        }
        sweep_free(sw);
    }
    free(s->all);
    pthread_cond_destroy(&s->changed);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

enum queue_submit_result sweeps_submit(struct sweeps *s, struct sweep_spec *spec,
                                       const json_t *body, char id_out[24])
{
    records_set_submit_error("%s", "");
    pthread_mutex_lock(&s->lock);
    size_t waiting = (size_t)s->reserved;
    for (size_t i = 0; i < s->count; i++)
        waiting += s->all[i]->status == JOB_QUEUED;
    enum queue_submit_result res = atomic_load(&s->stopping)     ? QUEUE_STOPPING
                                   : waiting >= SWEEPS_MAX_WAITING ? QUEUE_FULL
                                                                   : QUEUE_OK;
    if (res == QUEUE_OK)
        s->reserved++;
    pthread_mutex_unlock(&s->lock);
    if (res != QUEUE_OK)
        return res;

    /* Accepted only once sweep.json is on disk, written with no lock held. */
    char why[PATH_MAX + 200] = "out of memory";
    struct sweep *sw = sweep_new();
    bool made_dir = false, inserted = false;
    if (!sw || !(sw->body = json_deep_copy(body)) || !(sw->points = json_array()))
        goto fail;
    if (!record_create_dir(&s->kind, NULL, sw->id, sw->dir, sizeof(sw->dir), why, sizeof(why)))
        goto fail;
    made_dir = true;
    sw->spec = *spec;
    sw->status = JOB_QUEUED;
    sw->created = clock_unix_s();
    json_t *first = sweep_record_locked(sw); /* not shared yet: no lock needed */
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/sweep.json", sw->dir);
    sw->seq = 1;
    snprintf(why, sizeof(why), "out of memory");
    bool written = first && record_writer_write(&sw->writer, 1, path, first, why, sizeof(why));
    json_decref(first);
    if (!written) {
        memset(&sw->spec, 0, sizeof(sw->spec)); /* still the caller's */
        goto fail;
    }
    pthread_mutex_lock(&s->lock);
    s->reserved--;
    inserted = insert_locked(s, sw);
    if (inserted)
        pthread_cond_broadcast(&s->changed);
    else
        s->reserved++; /* given back below */
    pthread_mutex_unlock(&s->lock);
    if (!inserted) {
        memset(&sw->spec, 0, sizeof(sw->spec));
        snprintf(why, sizeof(why), "out of memory");
        goto fail;
    }
    memset(spec, 0, sizeof(*spec)); /* ours now */
    snprintf(id_out, 24, "%s", sw->id);
    return QUEUE_OK;

fail:
    records_set_submit_error("the sweep cannot be persisted in the state directory %s: %s",
                             s->kind.state_dir, why);
    LOG(LOG_ERROR, "sweep refused: %s", records_submit_error());
    if (made_dir) {
        /* Never accepted, so not a record: remove what was made of it. */
        char p2[PATH_MAX + 32];
        snprintf(p2, sizeof(p2), "%s/sweep.json", sw->dir);
        unlink(p2);
        snprintf(p2, sizeof(p2), "%s/sweep.json.tmp", sw->dir);
        unlink(p2);
        if (rmdir(sw->dir) != 0)
            LOG(LOG_WARN, "cannot remove %s: %s", sw->dir, strerror(errno));
    }
    sweep_free(sw);
    pthread_mutex_lock(&s->lock);
    s->reserved--;
    pthread_mutex_unlock(&s->lock);
    return QUEUE_IO_ERROR;
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
    json_t *o = json_pack("{s:s, s:s, s:s, s:{s:I, s:I}}", "id", sw->id, "kind",
                          sw->spec.kind == SWEEP_VARY ? "vary" : "find", "status",
                          job_status_name(sw->status), "progress", "points_done",
                          (json_int_t)json_array_size(sw->points), "points_total",
                          (json_int_t)sw->spec.npoints);
    if (!o)
        return NULL;
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
            json_object_set(o, RK_RESULT, sw->result);
    }
    return o;
}

json_t *sweeps_json(struct sweeps *s, const char *id, double wait_s)
{
    struct timespec deadline = clock_deadline(wait_s);
    pthread_mutex_lock(&s->lock);
    struct sweep *sw = find_locked(s, id);
    while (sw && wait_s > 0 && !sweep_finished(sw) && !atomic_load(&s->stopping)) {
        int rc = pthread_cond_timedwait(&s->changed, &s->lock, &deadline);
        sw = find_locked(s, id); /* retention may have removed it meanwhile */
        if (rc == ETIMEDOUT)
            break;
    }
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
    struct snapshot snap = {0};
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
            changed_locked(s, sw, &snap);
        } else {
            atomic_store(&sw->cancel, true);
            r = CANCEL_REQUESTED;
        }
    }
    pthread_mutex_unlock(&s->lock);
    if (snap.sw)
        write_snapshot(s, &snap, NULL, 0);
    return r;
}

/* Finished sweeps beyond the jobs' retention settings are removed like jobs
 * (their point jobs follow the jobs' own retention). */
static void apply_retention(struct sweeps *s)
{
    int keep = 0;
    double days = 0;
    queue_retention(s->queue, &keep, &days);
    pthread_mutex_lock(&s->lock);
    if (!s->kind.state_dir[0] || (keep <= 0 && days <= 0) || !s->count) {
        pthread_mutex_unlock(&s->lock);
        return;
    }
    double *times = malloc(s->count * sizeof(double));
    bool *victim = malloc(s->count * sizeof(bool));
    struct sweep **victims = malloc(s->count * sizeof(*victims));
    size_t nv = 0, kept = 0;
    if (times && victim && victims) {
        for (size_t i = 0; i < s->count; i++)
            times[i] = sweep_finished(s->all[i]) && !s->all[i]->pending ? s->all[i]->finished : -1;
        record_retention(times, s->count, keep, days, clock_unix_s(), victim);
        for (size_t i = 0; i < s->count; i++) {
            if (victim[i])
                victims[nv++] = s->all[i];
            else
                s->all[kept++] = s->all[i];
        }
        s->count = kept;
    }
    pthread_mutex_unlock(&s->lock);
    for (size_t i = 0; i < nv; i++) {
        LOG(LOG_INFO, "retention: removing sweep %s", victims[i]->id);
        record_remove_dir(victims[i]->dir);
        sweep_free(victims[i]);
    }
    free(times);
    free(victim);
    free(victims);
}
