/* pthread_setname_np. */
#define _GNU_SOURCE
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
#include "common/fsutil.h"
#include "common/log.h"
#include "common/stats.h"
#include "daemon/store/records.h"
#include "daemon/store/store.h"
#include "daemon/spec/sweep_table.h"
#include "common/result_keys.h"

/* At most this many finished sweeps go at a time (retention). */
#define RETENTION_BATCH 64

struct sweep {
    char id[RECORD_ID_LEN]; /* first: store_live */
    char dir[PATH_MAX]; /* STATE_DIR/sweeps/ID: spec.json */
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
    double created, started, finished;
    /* base.scene.asset's pin, held from acceptance to the end (queue.h's
     * queue_asset_pin), so that every point runs on one hash. */
    struct scene_spec asset;
    bool asset_pinned;
    /* Under the sweeps' lock: ordered writes, as for jobs (queue.h). */
    struct store_version version;
};

struct sweeps {
    struct queue *queue;
    struct store *store;
    const struct technique_catalog *techniques;
    pthread_t thread;
    /* Guards the list and the sweeps' state; never held across file I/O or
     * a store write, and never while calling into the queue. */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct store_live live; /* struct sweep: queued, running, or not yet stored */
    int reserved; /* submissions writing their first record */
    atomic_bool stopping;
};

/* A sweep's state taken under the lock, written after it. */
struct snapshot {
    struct sweep *sw;
    uint64_t seq;
    struct store_row row;
};

static void apply_retention(struct sweeps *s);

static bool sweep_finished(const struct sweep *sw) { return job_status_finished(sw->status); }

/* Points that ran to an end of their own: a point the sweep's cancel
 * stopped has a row (status "cancelled") but is not done. */
static size_t points_done(const struct sweep *sw)
{
    size_t i, done = 0;
    json_t *row;
    json_array_foreach(sw->points, i, row) {
        const char *status = json_string_value(json_object_get(row, "status"));
        done += !status || strcmp(status, "cancelled") != 0;
    }
    return done;
}

/* What GET /v1/sweeps/ID shows of a sweep, live or stored alike; the table
 * and result are the caller's to copy. */
static json_t *sweep_json(const char *id, const char *kind, enum job_status status, size_t done,
                          size_t total, const char *current_job, bool thesis, const char *error,
                          json_t *body, json_t *points, json_t *result, bool full)
{
    json_t *o = json_pack("{s:s, s:s, s:s, s:{s:I, s:I}}", "id", id, "kind", kind, "status",
                          job_status_name(status), "progress", "points_done", (json_int_t)done,
                          "points_total", (json_int_t)total);
    if (!o)
        return NULL;
    if (current_job && current_job[0])
        json_object_set_new(o, "current_job", json_string(current_job));
    if (thesis)
        json_object_set_new(o, "preset", json_string("thesis"));
    if (error && error[0])
        json_object_set_new(o, "error", json_string(error));
    if (full) {
        json_object_set(o, "spec", body ? body : json_null());
        json_object_set_new(o, "points", points ? json_deep_copy(points) : json_array());
        if (result)
            json_object_set_new(o, RK_RESULT, json_deep_copy(result));
    }
    return o;
}

static const char *kind_name(const struct sweep *sw)
{
    return sw->spec.kind == SWEEP_VARY ? "vary" : "find";
}

/* A deep copy: the sweep thread keeps appending to the live table. */
static json_t *live_json_locked(const struct sweep *sw, bool full)
{
    return sweep_json(sw->id, kind_name(sw), sw->status, points_done(sw),
                      sw->spec.npoints, sw->current_job, sw->spec.thesis, sw->error, sw->body,
                      sw->points, sw->result, full);
}

/* The sweep's row: its table and result in extra, copied (the sweep thread
 * goes on appending once the lock is released). */
static void row_of_locked(const struct sweep *sw, struct store_row *row)
{
    store_row_init(row, STORE_SWEEPS);
    snprintf(row->id, sizeof(row->id), "%s", sw->id);
    row->status = sw->status;
    snprintf(row->technique, sizeof(row->technique), "%s", kind_name(sw));
    row->created = sw->created;
    row->started = sw->started;
    row->finished = sw->finished;
    row->done = (int)points_done(sw);
    row->total = (int)sw->spec.npoints;
    snprintf(row->error, sizeof(row->error), "%s", sw->error);
    row->spec = json_deep_copy(sw->body);
    row->extra = json_pack("{s:o}", "points", json_deep_copy(sw->points));
    if (sw->result)
        json_object_set_new(row->extra, RK_RESULT, json_deep_copy(sw->result));
    if (sw->current_job[0])
        json_object_set_new(row->extra, "current_job", json_string(sw->current_job));
    if (sw->spec.thesis)
        json_object_set_new(row->extra, "preset", json_string("thesis"));
}

static void snapshot_locked(struct sweep *sw, struct snapshot *snap)
{
    snap->sw = sw;
    snap->seq = store_version_take(&sw->version);
    row_of_locked(sw, &snap->row);
}

static void sweep_free(struct sweep *sw)
{
    if (!sw)
        return;
    sweep_spec_finish(&sw->spec);
    json_decref(sw->body);
    json_decref(sw->points);
    json_decref(sw->result);
    free(sw);
}

/* A finished sweep whose last state is stored leaves memory; returns it to
 * free once the lock is released, or NULL. */
static struct sweep *evict_locked(struct sweeps *s, struct sweep *sw)
{
    if (!sweep_finished(sw) || !store_version_stored(&sw->version))
        return NULL;
    store_live_remove(&s->live, sw);
    return sw;
}

static bool write_snapshot(struct sweeps *s, struct snapshot *snap, char *err, size_t errlen)
{
    struct sweep *sw = snap->sw;
    char why[PATH_MAX + 300] = "";
    bool ok = store_put(s->store, &snap->row, snap->seq, &sw->version.written, why, sizeof(why));
    if (!ok)
        LOG(LOG_ERROR, "sweep %s: %s (its state in memory stays right; written again at exit)",
            sw->id, why);
    if (err)
        snprintf(err, errlen, "%s", why);
    store_row_finish(&snap->row);
    pthread_mutex_lock(&s->lock);
    store_version_back(&sw->version, snap->seq, ok);
    struct sweep *gone = evict_locked(s, sw);
    pthread_mutex_unlock(&s->lock);
    sweep_free(gone);
    return ok;
}

/* Under the lock: the sweep changed; write it once the lock is released. */
static void changed_locked(struct sweeps *s, struct sweep *sw, struct snapshot *snap)
{
    snapshot_locked(sw, snap);
    pthread_cond_broadcast(&s->changed);
}

/* base.scene's asset and pinned hash, if it names one. */
static bool base_asset(const json_t *base, struct scene_spec *out)
{
    json_t *scene = json_object_get(base, "scene");
    const char *name = json_string_value(json_object_get(scene, "asset"));
    const char *sha = json_string_value(json_object_get(scene, "asset_sha256"));
    memset(out, 0, sizeof(*out));
    if (!name || strlen(name) >= sizeof(out->asset))
        return false;
    snprintf(out->asset, sizeof(out->asset), "%s", name);
    if (sha && strlen(sha) < sizeof(out->asset_sha256))
        snprintf(out->asset_sha256, sizeof(out->asset_sha256), "%s", sha);
    return true;
}

/* The sweep's pin goes (it ended, or was never accepted). */
static void unpin_sweep(struct sweeps *s, struct sweep *sw)
{
    if (!sw->asset_pinned)
        return;
    sw->asset_pinned = false;
    queue_asset_unpin(s->queue, &sw->asset);
}

static struct sweep *sweep_new(void)
{
    struct sweep *sw = calloc(1, sizeof(*sw));
    if (!sw)
        return NULL;
    atomic_init(&sw->cancel, false);
    return sw;
}

static struct sweep *find_locked(struct sweeps *s, const char *id)
{
    return store_live_find(&s->live, id);
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
        if (r == QUEUE_REFUSED) {
            snprintf(sw->error, sizeof(sw->error), "point job refused: %.400s",
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
    json_t *row = sweep_table_row(job, values);
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
            add_row(s, sw, sweep_table_row(job, values));
            json_decref(job);
            /* Cancelled while its last point ran: the point is in the table,
             * cancelled, and the sweep is not done. */
            if (atomic_load(&sw->cancel))
                ok = false;
        }
        if (ok)
            result = sweep_table_result(&sw->spec, sw->points);
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
    /* Logged before the write: once stored, a finished sweep leaves memory. */
    if (stopped)
        LOG(LOG_INFO, "sweep %s: stopped with the daemon after %zu points; resumes on the next start",
            sw->id, json_array_size(sw->points));
    else
        LOG(LOG_INFO, "sweep %s %s (%zu points)", sw->id, job_status_name(sw->status),
            json_array_size(sw->points));
    changed_locked(s, sw, &snap);
    pthread_mutex_unlock(&s->lock);
    if (!stopped) /* before the write, after which it may leave memory */
        unpin_sweep(s, sw);
    write_snapshot(s, &snap, NULL, 0);
    apply_retention(s);
}

static void *sweeps_main(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-sweeps"); /* named in crash reports, top, gdb */
    struct sweeps *s = arg;
    pthread_mutex_lock(&s->lock);
    for (;;) {
        struct sweep *next = NULL;
        for (size_t i = 0; i < s->live.count && !next; i++)
            if (((struct sweep *)s->live.items[i])->status == JOB_QUEUED)
                next = s->live.items[i];
        if (atomic_load(&s->stopping))
            break;
        if (!next) {
            pthread_cond_wait(&s->changed, &s->lock);
            continue;
        }
        struct snapshot snap;
        next->status = JOB_RUNNING;
        next->started = clock_unix_s();
        changed_locked(s, next, &snap);
        pthread_mutex_unlock(&s->lock);
        write_snapshot(s, &snap, NULL, 0);
        run_sweep(s, next);
        pthread_mutex_lock(&s->lock);
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

/* --- Loading -------------------------------------------------------------- */

/* spec.json: the sweep as posted, written once; enough to rebuild its row. */
static bool write_spec_record(const char *dir, const char *id, double created, const json_t *body,
                              char *err, size_t errlen)
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/spec.json", dir);
    json_t *o = json_pack("{s:s, s:f, s:O}", "id", id, "created_unix", created, "spec", body);
    bool ok = o && fs_write_json_atomic(path, o);
    if (!ok)
        snprintf(err, errlen, "cannot write %s: %s", path, o ? strerror(errno) : "out of memory");
    json_decref(o);
    return ok;
}

/* The row of a sweep.json of an earlier version; false with why. */
static bool row_from_legacy(struct sweeps *s, const char *id, const char *dir, json_t *o,
                            struct store_row *row, char *why, size_t whylen)
{
    const char *rid = json_string_value(json_object_get(o, "id"));
    json_t *points = json_object_get(o, "points");
    json_t *body = json_object_get(o, "spec");
    struct sweep_spec spec;
    struct job_error jerr;
    if (!rid || strcmp(rid, id) != 0) {
        snprintf(why, whylen, "its id does not match its directory");
        return false;
    }
    if (!job_status_parse(json_string_value(json_object_get(o, "status")), &row->status)) {
        snprintf(why, whylen, "no valid status");
        return false;
    }
    if (!json_is_array(points)) {
        snprintf(why, whylen, "no points table");
        return false;
    }
    if (!sweep_spec_parse(body, s->techniques, &spec, &jerr)) {
        sweep_spec_finish(&spec);
        snprintf(why, whylen, "not a sweep this daemon can read (%s: %s)", jerr.field,
                 jerr.message);
        return false;
    }
    json_t *times = json_object_get(o, "times_unix");
    snprintf(row->technique, sizeof(row->technique), "%s",
             spec.kind == SWEEP_VARY ? "vary" : "find");
    row->created = json_number_value(json_array_get(times, 0));
    row->finished = json_number_value(json_array_get(times, 1));
    row->done = (int)json_array_size(points);
    row->total = (int)spec.npoints;
    const char *error = json_string_value(json_object_get(o, "error"));
    const char *current = json_string_value(json_object_get(o, "current_job"));
    snprintf(row->error, sizeof(row->error), "%s", error ? error : "");
    row->spec = json_incref(body);
    row->extra = json_pack("{s:O}", "points", points);
    if (json_object_get(o, RK_RESULT))
        json_object_set(row->extra, RK_RESULT, json_object_get(o, RK_RESULT));
    if (current && record_id_valid(current))
        json_object_set_new(row->extra, "current_job", json_string(current));
    if (spec.thesis)
        json_object_set_new(row->extra, "preset", json_string("thesis"));
    char path[PATH_MAX + 16], err[PATH_MAX + 200];
    snprintf(path, sizeof(path), "%s/spec.json", dir);
    if (access(path, F_OK) != 0 && !write_spec_record(dir, id, row->created, body, err, sizeof(err)))
        LOG(LOG_WARN, "sweep %s: %s", id, err);
    sweep_spec_finish(&spec);
    return true;
}

/* store_import: a sweep directory the store has no row for. An earlier
 * version's sweep.json is imported (a running one is then interrupted by
 * load_unfinished); with spec.json alone, the sweep is rebuilt as
 * interrupted, its table lost; what cannot be read is quarantined whole. */
static bool import_sweep(void *ctx, const char *id, const char *dir, struct store_row *row)
{
    struct sweeps *s = ctx;
    char path[PATH_MAX + 16], why[600] = "", reason[800];
    snprintf(path, sizeof(path), "%s/sweep.json", dir);
    if (access(path, F_OK) == 0) {
        json_t *o = record_read(path, why, sizeof(why));
        bool ok = o && row_from_legacy(s, id, dir, o, row, why, sizeof(why));
        json_decref(o);
        if (ok)
            return true;
        snprintf(reason, sizeof(reason), "sweep.json: %s", why);
        record_quarantine(store_record_kind(s->store, STORE_SWEEPS), id, dir, reason, NULL, 0);
        return false;
    }
    snprintf(path, sizeof(path), "%s/spec.json", dir);
    json_t *rec = record_read(path, why, sizeof(why));
    const char *rid = json_string_value(json_object_get(rec, "id"));
    struct sweep_spec spec;
    struct job_error jerr;
    bool parsed = false;
    if (rec && (!rid || strcmp(rid, id) != 0))
        snprintf(why, sizeof(why), "its id does not match its directory");
    else if (rec && !(parsed = sweep_spec_parse(json_object_get(rec, "spec"), s->techniques,
                                                &spec, &jerr)))
        snprintf(why, sizeof(why), "not a sweep this daemon can read (%s: %s)", jerr.field,
                 jerr.message);
    if (!parsed) {
        if (rec)
            sweep_spec_finish(&spec);
        json_decref(rec);
        snprintf(reason, sizeof(reason), "no row in the store and no sweep.json; spec.json: %s",
                 why);
        record_quarantine(store_record_kind(s->store, STORE_SWEEPS), id, dir, reason, NULL, 0);
        return false;
    }
    snprintf(row->technique, sizeof(row->technique), "%s",
             spec.kind == SWEEP_VARY ? "vary" : "find");
    row->created = json_number_value(json_object_get(rec, "created_unix"));
    row->total = (int)spec.npoints;
    row->status = JOB_INTERRUPTED;
    row->finished = clock_unix_s();
    snprintf(row->error, sizeof(row->error),
             "interrupted: its state was not in the store (a submission cut short, or the store "
             "was rebuilt), so its table is lost; submit it again to run it");
    row->spec = json_incref(json_object_get(rec, "spec"));
    row->extra = json_pack("{s:[]}", "points");
    if (spec.thesis)
        json_object_set_new(row->extra, "preset", json_string("thesis"));
    sweep_spec_finish(&spec);
    json_decref(rec);
    LOG(LOG_WARN, "sweep %s: no row in the store; rebuilt from spec.json as interrupted", id);
    return true;
}

/* Startup: a queued sweep joins the queue (resuming after its points); one
 * that was running when the daemon died is interrupted, its points kept. */
static void load_unfinished(void *ctx, const struct store_row *stored)
{
    struct sweeps *s = ctx;
    struct store_row row = *stored; /* its JSON stays the store's */
    struct job_error jerr;
    char err[PATH_MAX + 300];
    json_t *points = json_object_get(row.extra, "points");
    const char *current = json_string_value(json_object_get(row.extra, "current_job"));
    struct sweep *sw = sweep_new();
    if (!sw) {
        LOG(LOG_ERROR, "sweep %s: out of memory loading it", row.id);
        return;
    }
    if (!json_is_array(points) ||
        !sweep_spec_parse(row.spec, s->techniques, &sw->spec, &jerr)) {
        row.status = JOB_FAILED;
        row.finished = clock_unix_s();
        snprintf(row.error, sizeof(row.error), "not a sweep this daemon can run (%s: %s)",
                 json_is_array(points) ? jerr.field : "points",
                 json_is_array(points) ? jerr.message : "no table");
        LOG(LOG_WARN, "sweep %s: %s", row.id, row.error);
        if (!store_put(s->store, &row, 0, NULL, err, sizeof(err)))
            LOG(LOG_ERROR, "sweep %s: %s", row.id, err);
        sweep_free(sw);
        return;
    }
    if (row.status == JOB_RUNNING) {
        /* Killed or crashed: its point job is interrupted too (queue.c). */
        json_t *extra = json_deep_copy(row.extra);
        json_object_del(extra, "current_job");
        row.extra = extra;
        row.status = JOB_INTERRUPTED;
        row.finished = clock_unix_s();
        snprintf(row.error, sizeof(row.error),
                 "interrupted: the daemon stopped (killed or crashed) while this sweep ran; "
                 "its %zu finished points stay, submit it again to run the rest",
                 json_array_size(points));
        if (!store_put(s->store, &row, 0, NULL, err, sizeof(err)))
            LOG(LOG_ERROR, "sweep %s: %s", row.id, err);
        json_decref(extra);
        sweep_free(sw);
        return;
    }
    snprintf(sw->id, sizeof(sw->id), "%s", row.id);
    snprintf(sw->dir, sizeof(sw->dir), "%s", row.dir);
    sw->body = json_incref(row.spec);
    sw->points = json_deep_copy(points);
    sw->result = json_deep_copy(json_object_get(row.extra, RK_RESULT));
    sw->status = JOB_QUEUED;
    sw->created = row.created;
    snprintf(sw->error, sizeof(sw->error), "%.511s", row.error);
    if (current && record_id_valid(current)) {
        snprintf(sw->current_job, sizeof(sw->current_job), "%s", current);
        snprintf(sw->adopt_job, sizeof(sw->adopt_job), "%s", current);
    }
    /* Its hash again, though the name may point elsewhere now (replaced
     * while it ran): its files are still there until the start-up's
     * release, which comes after this. A hash gone fails its next point. */
    if (base_asset(sw->spec.base, &sw->asset) && sw->asset.asset_sha256[0]) {
        sw->asset_pinned = queue_asset_pin(s->queue, &sw->asset, true);
        if (!sw->asset_pinned)
            LOG(LOG_WARN, "sweep %s: %s", row.id, queue_submit_error());
    }
    pthread_mutex_lock(&s->lock);
    bool inserted = store_live_insert(&s->live, sw);
    pthread_mutex_unlock(&s->lock);
    if (!inserted) {
        LOG(LOG_ERROR, "sweep %s: out of memory loading it; it resumes on the next start", row.id);
        unpin_sweep(s, sw);
        sweep_free(sw);
    }
}

/* The queue's retention guard: a point job of a queued or running sweep
 * stays (the one it waits for, the one it adopts, and those in its table,
 * which its report shows). */
static bool needs_job(void *ctx, const char *id)
{
    struct sweeps *s = ctx;
    bool needed = false;
    pthread_mutex_lock(&s->lock);
    for (size_t i = 0; i < s->live.count && !needed; i++) {
        const struct sweep *sw = s->live.items[i];
        if (sweep_finished(sw))
            continue;
        needed = strcmp(sw->current_job, id) == 0 || strcmp(sw->adopt_job, id) == 0;
        size_t k;
        json_t *row;
        json_array_foreach(sw->points, k, row) {
            const char *job = json_string_value(json_object_get(row, "job"));
            if (needed || (job && strcmp(job, id) == 0)) {
                needed = true;
                break;
            }
        }
    }
    pthread_mutex_unlock(&s->lock);
    return needed;
}

struct sweeps *sweeps_create(struct queue *q, const struct technique_catalog *techniques)
{
    struct sweeps *s = calloc(1, sizeof(*s));
    if (!s)
        return NULL;
    s->queue = q;
    s->store = queue_store(q);
    s->techniques = techniques;
    atomic_init(&s->stopping, false);
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->changed, NULL);
    char err[PATH_MAX + 300];
    int imported = store_import(s->store, STORE_SWEEPS, "sweep.json", import_sweep, s, err,
                                sizeof(err));
    if (imported < 0)
        LOG(LOG_ERROR, "sweeps: %s; none imported", err);
    else if (imported > 0)
        LOG(LOG_INFO, "imported %d sweep(s) from their directories", imported);
    if (!store_each_unfinished(s->store, STORE_SWEEPS, load_unfinished, s))
        LOG(LOG_ERROR, "sweeps: cannot read the unfinished sweeps; none resumed");
    apply_retention(s);
    queue_set_retention_guard(q, needs_job, s);
    if (pthread_create(&s->thread, NULL, sweeps_main, s) != 0) {
        queue_set_retention_guard(q, NULL, NULL);
        for (size_t i = 0; i < s->live.count; i++)
            sweep_free(s->live.items[i]);
        store_live_finish(&s->live);
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
    /* The render thread may still finish a job: its retention must not ask
     * a freed guard. */
    queue_set_retention_guard(s->queue, NULL, NULL);
    /* A stop, not a cancel: the running sweep returns to the queue and its
     * point job is left to the store, which requeues it. */
    pthread_mutex_lock(&s->lock);
    atomic_store(&s->stopping, true);
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
    pthread_join(s->thread, NULL);
    for (size_t i = 0; i < s->live.count;) {
        struct sweep *sw = s->live.items[i];
        size_t before = s->live.count;
        if (sw->version.saved < sw->version.seq) { /* a full disk held it back: one more try */
            struct snapshot snap;
            pthread_mutex_lock(&s->lock);
            snapshot_locked(sw, &snap);
            pthread_mutex_unlock(&s->lock);
            write_snapshot(s, &snap, NULL, 0); /* a finished one leaves the list */
        }
        if (s->live.count == before)
            i++;
    }
    for (size_t i = 0; i < s->live.count; i++) {
        unpin_sweep(s, s->live.items[i]);
        sweep_free(s->live.items[i]);
    }
    store_live_finish(&s->live);
    pthread_cond_destroy(&s->changed);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

enum queue_submit_result sweeps_submit(struct sweeps *s, struct sweep_spec *spec,
                                       const json_t *body, char id_out[24])
{
    records_set_submit_error("%s", "");
    if (!queue_room_to_accept(s->queue, "sweep"))
        return QUEUE_IO_ERROR;
    pthread_mutex_lock(&s->lock);
    size_t waiting = (size_t)s->reserved;
    for (size_t i = 0; i < s->live.count; i++)
        waiting += ((struct sweep *)s->live.items[i])->status == JOB_QUEUED;
    enum queue_submit_result res = atomic_load(&s->stopping)     ? QUEUE_STOPPING
                                   : waiting >= SWEEPS_MAX_WAITING ? QUEUE_FULL
                                                                   : QUEUE_OK;
    if (res == QUEUE_OK)
        s->reserved++;
    pthread_mutex_unlock(&s->lock);
    if (res != QUEUE_OK)
        return res;

    /* Accepted only once spec.json and the row are stored, with no lock held. */
    char why[PATH_MAX + 300] = "out of memory";
    struct sweep *sw = sweep_new();
    bool made_dir = false, inserted = false;
    if (!sw || !(sw->body = json_deep_copy(body)) || !(sw->points = json_array()))
        goto fail;
    /* On an asset: its hash pinned for the whole sweep, and written into the
     * base (its points' and the stored spec's), so that a replacing PUT
     * meanwhile changes none of its points. */
    if (base_asset(spec->base, &sw->asset)) {
        if (!queue_asset_pin(s->queue, &sw->asset, false)) {
            sweep_free(sw);
            pthread_mutex_lock(&s->lock);
            s->reserved--;
            pthread_mutex_unlock(&s->lock);
            return QUEUE_REFUSED;
        }
        sw->asset_pinned = true;
        json_t *hash = json_string(sw->asset.asset_sha256);
        json_object_set(json_object_get(spec->base, "scene"), "asset_sha256", hash);
        json_object_set(json_object_get(json_object_get(sw->body, "base"), "scene"),
                        "asset_sha256", hash);
        json_decref(hash);
    }
    if (!record_create_dir(store_record_kind(s->store, STORE_SWEEPS), NULL, sw->id, sw->dir,
                           sizeof(sw->dir), why, sizeof(why)))
        goto fail;
    made_dir = true;
    sw->spec = *spec;
    sw->status = JOB_QUEUED;
    sw->created = clock_unix_s();
    bool written = write_spec_record(sw->dir, sw->id, sw->created, sw->body, why, sizeof(why));
    if (written) {
        struct snapshot first;
        snapshot_locked(sw, &first); /* not shared yet: no lock needed */
        written = store_put(s->store, &first.row, first.seq, &sw->version.written, why,
                            sizeof(why));
        store_row_finish(&first.row);
        store_version_back(&sw->version, first.seq, written);
    }
    if (!written) {
        memset(&sw->spec, 0, sizeof(sw->spec)); /* still the caller's */
        goto fail;
    }
    pthread_mutex_lock(&s->lock);
    s->reserved--;
    inserted = store_live_insert(&s->live, sw);
    if (inserted)
        pthread_cond_broadcast(&s->changed);
    else
        s->reserved++; /* given back below */
    pthread_mutex_unlock(&s->lock);
    if (!inserted) {
        /* Stored but not queued: it runs on the next start. */
        memset(&sw->spec, 0, sizeof(sw->spec));
        snprintf(why, sizeof(why), "out of memory");
        made_dir = false;
        goto fail;
    }
    memset(spec, 0, sizeof(*spec)); /* ours now */
    snprintf(id_out, 24, "%s", sw->id);
    return QUEUE_OK;

fail:
    records_set_submit_error("the sweep cannot be persisted in the state directory %s: %s",
                             store_state_dir(s->store), why);
    LOG(LOG_ERROR, "sweep refused: %s", records_submit_error());
    if (made_dir) {
        /* Never accepted, so not a record: remove what was made of it. */
        char p2[PATH_MAX + 32];
        snprintf(p2, sizeof(p2), "%s/spec.json", sw->dir);
        unlink(p2);
        snprintf(p2, sizeof(p2), "%s/spec.json.tmp", sw->dir);
        unlink(p2);
        if (rmdir(sw->dir) != 0)
            LOG(LOG_WARN, "cannot remove %s: %s", sw->dir, strerror(errno));
    }
    if (sw)
        unpin_sweep(s, sw);
    sweep_free(sw);
    pthread_mutex_lock(&s->lock);
    s->reserved--;
    pthread_mutex_unlock(&s->lock);
    return QUEUE_IO_ERROR;
}

static json_t *row_json(const struct store_row *row, bool full)
{
    const json_t *extra = row->extra;
    return sweep_json(row->id, row->technique, row->status, (size_t)row->done, (size_t)row->total,
                      json_string_value(json_object_get(extra, "current_job")),
                      json_object_get(extra, "preset") != NULL, row->error, row->spec,
                      json_object_get(extra, "points"), json_object_get(extra, RK_RESULT), full);
}

json_t *sweeps_json(struct sweeps *s, const char *id, double wait_s)
{
    struct timespec deadline = clock_deadline(wait_s);
    pthread_mutex_lock(&s->lock);
    struct sweep *sw = find_locked(s, id);
    while (sw && wait_s > 0 && !sweep_finished(sw) && !atomic_load(&s->stopping)) {
        int rc = pthread_cond_timedwait(&s->changed, &s->lock, &deadline);
        sw = find_locked(s, id); /* once finished and stored, it leaves memory */
        if (rc == ETIMEDOUT)
            break;
    }
    json_t *o = sw ? live_json_locked(sw, true) : NULL;
    pthread_mutex_unlock(&s->lock);
    if (sw)
        return o;
    struct store_row row;
    if (store_get(s->store, STORE_SWEEPS, id, true, &row) == STORE_FOUND)
        o = row_json(&row, true);
    store_row_finish(&row);
    return o;
}

struct page {
    json_t *sweeps;
};

static void page_row(void *ctx, const struct store_row *row)
{
    struct page *p = ctx;
    json_t *entry = row_json(row, false);
    if (entry)
        json_array_append_new(p->sweeps, entry);
}

json_t *sweeps_list_page(struct sweeps *s, const struct store_query *query,
                         char next[RECORD_ID_LEN], char *err, size_t errlen)
{
    struct page p = {.sweeps = json_array()};
    if (!p.sweeps || !store_list(s->store, query, page_row, &p, next, err, errlen)) {
        json_decref(p.sweeps);
        return NULL;
    }
    /* Live sweeps: their state in memory is the newest. */
    size_t i;
    json_t *entry;
    pthread_mutex_lock(&s->lock);
    json_array_foreach(p.sweeps, i, entry) {
        const struct sweep *sw = find_locked(s, json_string_value(json_object_get(entry, "id")));
        if (sw)
            json_array_set_new(p.sweeps, i, live_json_locked(sw, false));
    }
    pthread_mutex_unlock(&s->lock);
    return json_pack("{s:o}", "sweeps", p.sweeps);
}

enum queue_cancel_result sweeps_cancel(struct sweeps *s, const char *id)
{
    enum queue_cancel_result r = CANCEL_NOT_FOUND;
    struct snapshot snap = {0};
    struct scene_spec unpinned;
    bool unpin = false;
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
            unpinned = sw->asset;
            unpin = sw->asset_pinned;
            sw->asset_pinned = false;
            changed_locked(s, sw, &snap);
        } else {
            atomic_store(&sw->cancel, true);
            r = CANCEL_REQUESTED;
        }
    }
    pthread_mutex_unlock(&s->lock);
    if (unpin) /* never while holding the sweeps' lock (queue.h) */
        queue_asset_unpin(s->queue, &unpinned);
    if (snap.sw)
        write_snapshot(s, &snap, NULL, 0);
    if (!sw) {
        /* Not live: finished, or no such sweep. */
        struct store_row row;
        if (store_get(s->store, STORE_SWEEPS, id, false, &row) == STORE_FOUND)
            r = CANCEL_FINISHED;
        store_row_finish(&row);
    }
    return r;
}

/* Finished sweeps beyond the jobs' retention settings are removed like jobs
 * (their point jobs follow the jobs' own retention). */
static void apply_retention(struct sweeps *s)
{
    int keep = 0;
    double days = 0;
    queue_retention(s->queue, &keep, &days);
    if (!store_state_dir(s->store)[0] || (keep <= 0 && days <= 0))
        return;
    char ids[RETENTION_BATCH][RECORD_ID_LEN];
    int n = store_retention_victims(s->store, STORE_SWEEPS, keep, days, clock_unix_s(), ids,
                                    RETENTION_BATCH);
    int m = 0;
    for (int i = 0; i < n; i++) {
        pthread_mutex_lock(&s->lock);
        bool live = find_locked(s, ids[i]) != NULL;
        pthread_mutex_unlock(&s->lock);
        if (!live) {
            LOG(LOG_INFO, "retention: removing sweep %s", ids[i]);
            memmove(ids[m++], ids[i], RECORD_ID_LEN);
        }
    }
    store_remove(s->store, STORE_SWEEPS, ids, m);
}
