#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/queue.h"

#include "common/fsutil.h"
#include "common/clock.h"
#include "common/log.h"
#include "common/result_keys.h"

#include <dirent.h>
#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

struct queue {
    /* Guards everything below and the jobs' store-owned fields. Never held
     * across file I/O: see struct snapshot. */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct job **jobs; /* sorted by id: submission order */
    size_t count, cap;
    int queued, max_queued; /* queued counts submissions in progress too */
    bool stopping;
    int keep_jobs;
    double keep_days;
    struct record_kind kind; /* STATE_DIR/jobs/ID/job.json */
    const struct technique_catalog *techniques; /* for queue_load */
    void (*listener)(void *ctx);
    void *listener_ctx;
};

/* A job's state as taken under the store lock, written after it is
 * released. The job stays alive until then (pending). */
struct snapshot {
    struct job *job;
    uint64_t seq;
    json_t *json;
};

void queue_set_listener(struct queue *q, void (*fn)(void *ctx), void *ctx)
{
    q->listener = fn;
    q->listener_ctx = ctx;
}

#define NOTIFY_LISTENER(q) ((q)->listener ? (q)->listener((q)->listener_ctx) : (void)0)

const char *job_status_name(enum job_status s)
{
    static const char *const names[] = {"queued",    "running",  "done",
                                        "failed",    "cancelled", "interrupted"};
    return names[s];
}

/* The parts of a job's state that its JSON shows and that change. */
struct job_state {
    enum job_status status;
    const char *phase;
    double started, finished;
    const char *error;
    int frames_done;
};

static struct job_state state_of(const struct job *job);
static json_t *state_json(const struct job *job, const struct job_state *st, bool full);
static json_t *state_record(const struct job *job, const struct job_state *st);
static json_t *job_json_locked(const struct job *job, bool full);
static json_t *job_record_locked(const struct job *job);
static void apply_retention(struct queue *q);

static bool finished(const struct job *job)
{
    return job->status != JOB_QUEUED && job->status != JOB_RUNNING;
}

/* Under the lock: the job's state changed; number it and copy it. */
static void snapshot_locked(struct job *job, struct snapshot *snap)
{
    snap->job = job;
    snap->seq = ++job->seq;
    snap->json = job_record_locked(job);
    job->pending++;
}

/* Without the lock: writes the snapshot unless a newer one is on disk, and
 * releases the job. Failures are logged with the file and errno. */
static bool write_snapshot(struct queue *q, struct snapshot *snap, char *err, size_t errlen)
{
    struct job *job = snap->job;
    char path[PATH_MAX + 16], why[PATH_MAX + 128] = "";
    bool ok = true;
    snprintf(path, sizeof(path), "%s/job.json", job->dir);
    if (!snap->json) {
        ok = false;
        snprintf(why, sizeof(why), "cannot write %s: out of memory", path);
    } else {
        ok = record_writer_write(&job->writer, snap->seq, path, snap->json, why, sizeof(why));
    }
    if (!ok)
        LOG(LOG_ERROR, "job %s: %s (its state in memory stays right; written again at exit)",
            job->id, why);
    if (err)
        snprintf(err, errlen, "%s", why);
    json_decref(snap->json);
    snap->json = NULL;
    pthread_mutex_lock(&q->lock);
    job->pending--;
    pthread_mutex_unlock(&q->lock);
    return ok;
}

struct queue *queue_create(const char *state_dir, int max_queued)
{
    struct queue *q = calloc(1, sizeof(*q));
    if (!q)
        return NULL;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->changed, NULL);
    q->max_queued = max_queued;
    record_kind_init(&q->kind, state_dir, "jobs", "job.json");
    return q;
}

static void job_free(struct job *job)
{
    if (!job)
        return;
    json_decref(job->result);
    record_writer_finish(&job->writer);
    free(job);
}

void queue_destroy(struct queue *q)
{
    if (!q)
        return;
    /* Every other thread is gone: state a full disk held back gets one more
     * try, so that a restart does not find it stale. */
    for (size_t i = 0; i < q->count; i++) {
        struct job *job = q->jobs[i];
        if (job->writer.written < job->seq) {
            struct snapshot snap;
            pthread_mutex_lock(&q->lock);
            snap.job = job;
            snap.seq = job->seq;
            snap.json = job_record_locked(job);
            job->pending++;
            pthread_mutex_unlock(&q->lock);
            write_snapshot(q, &snap, NULL, 0);
        }
    }
    for (size_t i = 0; i < q->count; i++)
        job_free(q->jobs[i]);
    free(q->jobs);
    pthread_cond_destroy(&q->changed);
    pthread_mutex_destroy(&q->lock);
    free(q);
}

int queue_max_queued(const struct queue *q) { return q->max_queued; }

const char *queue_state_dir(const struct queue *q) { return q->kind.state_dir; }

void queue_retention(struct queue *q, int *keep_jobs, double *keep_days)
{
    pthread_mutex_lock(&q->lock);
    *keep_jobs = q->keep_jobs;
    *keep_days = q->keep_days;
    pthread_mutex_unlock(&q->lock);
}

const char *queue_submit_error(void) { return records_submit_error(); }

static struct job *find_locked(struct queue *q, const char *id)
{
    for (size_t i = 0; i < q->count; i++)
        if (strcmp(q->jobs[i]->id, id) == 0)
            return q->jobs[i];
    return NULL;
}

/* Keeps the array in id order, which is submission order. */
static bool insert_locked(struct queue *q, struct job *job)
{
    if (q->count == q->cap) {
        size_t cap = q->cap ? q->cap * 2 : 64;
        struct job **jobs = realloc(q->jobs, cap * sizeof(*jobs));
        if (!jobs)
            return false;
        q->jobs = jobs;
        q->cap = cap;
    }
    size_t at = q->count;
    while (at > 0 && strcmp(q->jobs[at - 1]->id, job->id) > 0)
        at--;
    memmove(q->jobs + at + 1, q->jobs + at, (q->count - at) * sizeof(*q->jobs));
    q->jobs[at] = job;
    q->count++;
    return true;
}

static struct job *job_new(void)
{
    struct job *job = calloc(1, sizeof(*job));
    if (!job)
        return NULL;
    atomic_init(&job->cancel, false);
    atomic_init(&job->frames_done, 0);
    record_writer_init(&job->writer);
    return job;
}

/* spec.json: the job as accepted, written once. A damaged job.json is
 * rebuilt from it and result.json. */
static bool write_spec_record(const struct job *job, char *err, size_t errlen)
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/spec.json", job->dir);
    json_t *o = json_pack("{s:s, s:f, s:o}", "id", job->id, "created_unix", job->created, "spec",
                          job_spec_to_json(&job->spec));
    bool ok = o && fs_write_json_atomic(path, o);
    if (!ok)
        snprintf(err, errlen, "cannot write %s: %s", path, o ? strerror(errno) : "out of memory");
    json_decref(o);
    return ok;
}

enum queue_submit_result queue_submit(struct queue *q, const struct job_spec *spec,
                                      const char *dir_override, char id_out[24])
{
    char why[PATH_MAX + 200] = "";
    records_set_submit_error("%s", "");
    pthread_mutex_lock(&q->lock);
    enum queue_submit_result res = q->stopping                  ? QUEUE_STOPPING
                                   : q->queued >= q->max_queued ? QUEUE_FULL
                                                                : QUEUE_OK;
    if (res == QUEUE_OK)
        q->queued++; /* the place is taken while the files are written */
    pthread_mutex_unlock(&q->lock);
    if (res != QUEUE_OK)
        return res;

    /* The directory and both records are written with no lock held; the job
     * joins the store only once they are on disk, so a job that cannot be
     * persisted is refused and nothing of it is left behind. */
    struct job *job = job_new();
    bool made_dir = false;
    if (!job) {
        snprintf(why, sizeof(why), "out of memory");
        goto fail;
    }
    if (!record_create_dir(&q->kind, dir_override, job->id, job->dir, sizeof(job->dir), why,
                           sizeof(why)))
        goto fail;
    made_dir = !dir_override;
    job->spec = *spec;
    job->status = JOB_QUEUED;
    job->frames_total = spec->frames * job_spec_runs(spec);
    job->created = clock_unix_s();
    if (!dir_override && !write_spec_record(job, why, sizeof(why)))
        goto fail;
    json_t *first = job_record_locked(job); /* not shared yet: no lock needed */
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/job.json", job->dir);
    job->seq = 1;
    bool written = first && record_writer_write(&job->writer, 1, path, first, why, sizeof(why));
    if (!first)
        snprintf(why, sizeof(why), "out of memory");
    json_decref(first);
    if (!written)
        goto fail;
    pthread_mutex_lock(&q->lock);
    bool inserted = insert_locked(q, job);
    if (inserted)
        pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    if (!inserted) {
        snprintf(why, sizeof(why), "out of memory");
        goto fail;
    }
    snprintf(id_out, 24, "%s", job->id);
    return QUEUE_OK;

fail:
    records_set_submit_error("the job cannot be persisted in the state directory %s: %s",
                             q->kind.state_dir[0] ? q->kind.state_dir
                             : dir_override       ? dir_override
                                                  : "(none)",
                             why);
    LOG(LOG_ERROR, "job refused: %s", records_submit_error());
    if (made_dir) {
        /* Never accepted, so not a record: remove what was made of it. */
        static const char *const files[] = {"job.json", "job.json.tmp", "spec.json",
                                            "spec.json.tmp"};
        char path2[PATH_MAX + 32];
        for (size_t i = 0; i < sizeof(files) / sizeof(files[0]); i++) {
            snprintf(path2, sizeof(path2), "%s/%s", job->dir, files[i]);
            unlink(path2);
        }
        if (rmdir(job->dir) != 0)
            LOG(LOG_WARN, "cannot remove %s: %s", job->dir, strerror(errno));
    }
    job_free(job);
    pthread_mutex_lock(&q->lock);
    q->queued--;
    pthread_mutex_unlock(&q->lock);
    return QUEUE_IO_ERROR;
}

struct job *queue_next(struct queue *q)
{
    struct job *job = NULL;
    struct snapshot snap;
    pthread_mutex_lock(&q->lock);
    while (!q->stopping) {
        for (size_t i = 0; i < q->count && !job; i++)
            if (q->jobs[i]->status == JOB_QUEUED)
                job = q->jobs[i];
        if (job)
            break;
        pthread_cond_wait(&q->changed, &q->lock);
    }
    if (job) {
        job->status = JOB_RUNNING;
        job->phase = "rendering";
        job->started = clock_unix_s();
        q->queued--;
        snapshot_locked(job, &snap);
        pthread_cond_broadcast(&q->changed);
    }
    pthread_mutex_unlock(&q->lock);
    if (job)
        write_snapshot(q, &snap, NULL, 0);
    return job;
}

void queue_progress(struct queue *q, struct job *job, int frames_done)
{
    (void)q;
    atomic_store_explicit(&job->frames_done, frames_done, memory_order_relaxed);
}

void queue_set_phase(struct queue *q, struct job *job, const char *phase)
{
    pthread_mutex_lock(&q->lock);
    job->phase = phase;
    pthread_mutex_unlock(&q->lock);
}

void queue_finish(struct queue *q, struct job *job, enum job_status status,
                  const char *error, json_t *result)
{
    struct snapshot snap;
    pthread_mutex_lock(&q->lock);
    /* Stopped by SIGTERM, not by anyone's wish: it runs again, first, on the
     * next start. */
    bool requeue = status == JOB_CANCELLED && job->requeue_on_stop;
    struct job_state next = state_of(job);
    if (requeue) {
        next.status = JOB_QUEUED;
        next.phase = NULL;
        next.started = 0;
        next.error = "";
        next.frames_done = 0;
    } else {
        next.status = status;
        next.finished = clock_unix_s();
        if (error)
            next.error = error;
    }
    snap.job = job;
    snap.seq = ++job->seq;
    snap.json = state_record(job, &next);
    job->pending++;
    pthread_mutex_unlock(&q->lock);
    /* Written before anyone can see it (the job is running, so only this
     * thread changes its state): a job shown finished is finished on disk,
     * unless the write failed, which is logged. */
    write_snapshot(q, &snap, NULL, 0);

    pthread_mutex_lock(&q->lock);
    if (requeue) {
        job->status = JOB_QUEUED;
        job->phase = NULL;
        job->started = 0;
        job->error[0] = '\0';
        atomic_store(&job->frames_done, 0);
        atomic_store(&job->cancel, false);
        job->requeue_on_stop = false;
        json_decref(result);
        q->queued++;
    } else {
        job->status = status;
        job->finished = next.finished;
        if (error)
            snprintf(job->error, sizeof(job->error), "%s", error);
        json_decref(job->result);
        job->result = result;
    }
    /* Had anyone written an older view meanwhile, the newest goes last. */
    bool again = job->seq != snap.seq;
    if (again)
        snapshot_locked(job, &snap);
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
    if (again)
        write_snapshot(q, &snap, NULL, 0);
    if (requeue)
        LOG(LOG_INFO, "job %s: stopped by the daemon's exit; back to the head of the queue",
            job->id);
    apply_retention(q);
}

void queue_stop(struct queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->stopping = true;
    /* A running job stops at its next frame rather than holding up the exit,
     * and goes back to the queue: the stop is not its fault. */
    for (size_t i = 0; i < q->count; i++)
        if (q->jobs[i]->status == JOB_RUNNING) {
            q->jobs[i]->requeue_on_stop = !q->jobs[i]->user_cancel;
            atomic_store(&q->jobs[i]->cancel, true);
        }
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
}

enum queue_cancel_result queue_cancel(struct queue *q, const char *id)
{
    enum queue_cancel_result res = CANCEL_NOT_FOUND;
    struct snapshot snap = {0};
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    if (!job)
        goto out;
    switch (job->status) {
    case JOB_QUEUED:
        job->status = JOB_CANCELLED;
        job->finished = clock_unix_s();
        snprintf(job->error, sizeof(job->error), "cancelled before it started");
        q->queued--;
        snapshot_locked(job, &snap);
        res = CANCEL_DONE;
        pthread_cond_broadcast(&q->changed);
        NOTIFY_LISTENER(q);
        break;
    case JOB_RUNNING:
        job->user_cancel = true;
        job->requeue_on_stop = false;
        atomic_store(&job->cancel, true);
        res = CANCEL_REQUESTED;
        break;
    default:
        res = CANCEL_FINISHED;
    }
out:
    pthread_mutex_unlock(&q->lock);
    if (snap.job)
        write_snapshot(q, &snap, NULL, 0);
    return res;
}

static json_t *iso_time(double t)
{
    if (t <= 0)
        return json_null();
    time_t s = (time_t)t;
    struct tm tm;
    gmtime_r(&s, &tm);
    char buf[64];
    snprintf(buf, sizeof(buf), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
             tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
             (int)((t - (double)s) * 1000) % 1000);
    return json_string(buf);
}

static struct job_state state_of(const struct job *job)
{
    return (struct job_state){job->status, job->phase, job->started, job->finished, job->error,
                              atomic_load_explicit(&job->frames_done, memory_order_relaxed)};
}

static json_t *state_json(const struct job *job, const struct job_state *st, bool full)
{
    json_t *o = json_pack("{s:s, s:s, s:s, s:{s:i, s:i}, s:o, s:o, s:o}",
                          "id", job->id, "status", job_status_name(st->status),
                          "technique", job->spec.technique, "progress", "frames_done",
                          st->frames_done, "frames_total", job->frames_total, "created",
                          iso_time(job->created), "started", iso_time(st->started),
                          "finished", iso_time(st->finished));
    if (!o)
        return NULL;
    if (st->status == JOB_RUNNING && st->phase)
        json_object_set_new(o, "phase", json_string(st->phase));
    if (st->error && st->error[0])
        json_object_set_new(o, "error", json_string(st->error));
    if (full) {
        json_object_set_new(o, "spec", job_spec_to_json(&job->spec));
        if (job->result)
            json_object_set_new(o, RK_RESULT, json_deep_copy(job->result));
    }
    return o;
}

/* job.json: the job's state, written whenever it changes (the result lives
 * in result.json beside it, written before the job is marked done). */
static json_t *state_record(const struct job *job, const struct job_state *st)
{
    json_t *o = state_json(job, st, false);
    if (!o)
        return NULL;
    json_object_set_new(o, "spec", job_spec_to_json(&job->spec));
    json_object_set_new(o, "times_unix",
                        json_pack("[f, f, f]", job->created, st->started, st->finished));
    return o;
}

static json_t *job_json_locked(const struct job *job, bool full)
{
    struct job_state st = state_of(job);
    return state_json(job, &st, full);
}

static json_t *job_record_locked(const struct job *job)
{
    struct job_state st = state_of(job);
    return state_record(job, &st);
}

static bool status_from_name(const char *name, enum job_status *out)
{
    for (int s = JOB_QUEUED; s <= JOB_INTERRUPTED; s++)
        if (name && strcmp(name, job_status_name((enum job_status)s)) == 0) {
            *out = (enum job_status)s;
            return true;
        }
    return false;
}

/* A result.json is complete once nothing more would have been added to it:
 * the metrics stage adds "quality" for jobs with a reference, the repeats
 * add "repeat". An earlier version means the job never finished. */
static bool result_complete(const struct job_spec *spec, const json_t *result)
{
    if (spec->reference[0] && !json_object_get(result, RK_QUALITY))
        return false;
    if (job_spec_runs(spec) > 1 && !json_object_get(result, "repeat"))
        return false;
    return true;
}

static double file_mtime(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_mtim.tv_sec + st.st_mtim.tv_nsec / 1e9 : 0;
}

/* Rebuilds a job whose job.json cannot be read from spec.json (written once
 * at submission) and result.json. NULL, with why, when they do not allow it. */
static struct job *rebuild_job(struct queue *q, const char *id, const char *dir, char *why,
                               size_t whylen)
{
    char path[PATH_MAX + 16], rwhy[300] = "", swhy[700] = "";
    snprintf(path, sizeof(path), "%s/spec.json", dir);
    json_t *rec = record_read(path, swhy, sizeof(swhy));
    struct job_spec spec;
    struct job_error jerr;
    const char *rid = json_string_value(json_object_get(rec, "id"));
    if (rec && (!rid || strcmp(rid, id) != 0))
        snprintf(swhy, sizeof(swhy), "its id does not match its directory");
    else if (rec && !job_spec_parse(json_object_get(rec, "spec"), q->techniques, &spec, &jerr))
        snprintf(swhy, sizeof(swhy), "not a job this daemon can run (%s: %s)", jerr.field,
                 jerr.message);
    if (swhy[0]) {
        snprintf(why, whylen, "spec.json: %s", swhy);
        json_decref(rec);
        return NULL;
    }
    struct job *job = job_new();
    if (!job) {
        snprintf(why, whylen, "out of memory");
        json_decref(rec);
        return NULL;
    }
    snprintf(job->id, sizeof(job->id), "%s", id);
    snprintf(job->dir, sizeof(job->dir), "%s", dir);
    job->spec = spec;
    job->frames_total = spec.frames * job_spec_runs(&spec);
    job->created = json_number_value(json_object_get(rec, "created_unix"));
    json_decref(rec);
    snprintf(path, sizeof(path), "%s/result.json", dir);
    json_t *result = record_read(path, rwhy, sizeof(rwhy));
    if (result && result_complete(&job->spec, result)) {
        job->status = JOB_DONE;
        job->result = result;
        job->finished = file_mtime(path);
        atomic_store(&job->frames_done, job->frames_total);
        snprintf(why, whylen, "rebuilt as done from spec.json and result.json");
    } else {
        /* Its state is unknown: it may have been queued, running or failed.
         * Interrupted says so, and nothing is run twice behind anyone's back. */
        json_decref(result);
        job->status = JOB_INTERRUPTED;
        job->finished = clock_unix_s();
        snprintf(job->error, sizeof(job->error),
                 "interrupted: its job.json was damaged and its result.json is %s; "
                 "submit it again to measure it", result ? "incomplete" : "missing or damaged");
        snprintf(why, whylen, "rebuilt as interrupted from spec.json (result.json %s)",
                 result ? "incomplete" : rwhy);
    }
    return job;
}

/* Reads one job's directory (startup: no lock is needed to read files, and
 * none is held). Whatever cannot be read is quarantined, never skipped
 * silently. */
static void load_job(void *ctx, const char *id, const char *dir)
{
    struct queue *q = ctx;
    char path[PATH_MAX + 16], why[600] = "", quarantined[PATH_MAX] = "";
    snprintf(path, sizeof(path), "%s/job.json", dir);
    json_t *o = record_read(path, why, sizeof(why));
    struct job_spec spec;
    struct job_error jerr;
    enum job_status status = JOB_INTERRUPTED;
    if (o) {
        const char *jid = json_string_value(json_object_get(o, "id"));
        if (!jid || strcmp(jid, id) != 0)
            snprintf(why, sizeof(why), "its id %.40s does not match its directory",
                     jid ? jid : "(none)");
        else if (!status_from_name(json_string_value(json_object_get(o, "status")), &status))
            snprintf(why, sizeof(why), "no valid status");
        else if (!job_spec_parse(json_object_get(o, "spec"), q->techniques, &spec, &jerr))
            snprintf(why, sizeof(why), "not a job this daemon can read (%s: %s)", jerr.field,
                     jerr.message);
    }
    struct job *job = NULL;
    bool changed = false;
    if (why[0]) {
        json_decref(o);
        char rebuilt[800];
        job = rebuild_job(q, id, dir, rebuilt, sizeof(rebuilt));
        if (!job) {
            char reason[1600];
            snprintf(reason, sizeof(reason), "job.json: %s; cannot be rebuilt: %s", why, rebuilt);
            record_quarantine(&q->kind, id, dir, reason, NULL, 0);
            return;
        }
        char reason[1600];
        snprintf(reason, sizeof(reason), "job.json: %s; job %s", why, rebuilt);
        if (access(path, F_OK) == 0)
            record_quarantine(&q->kind, id, path, reason, quarantined, sizeof(quarantined));
        LOG(LOG_WARN, "job %s: %s", id, reason);
        changed = true;
    } else {
        if (!(job = job_new())) {
            LOG(LOG_ERROR, "job %s: out of memory loading it", id);
            json_decref(o);
            return;
        }
        snprintf(job->id, sizeof(job->id), "%s", id);
        snprintf(job->dir, sizeof(job->dir), "%s", dir);
        job->spec = spec;
        job->status = status;
        json_t *progress = json_object_get(o, "progress");
        job->frames_total = spec.frames * job_spec_runs(&spec);
        atomic_store(&job->frames_done,
                     (int)json_integer_value(json_object_get(progress, "frames_done")));
        json_t *times = json_object_get(o, "times_unix");
        job->created = json_number_value(json_array_get(times, 0));
        job->started = json_number_value(json_array_get(times, 1));
        job->finished = json_number_value(json_array_get(times, 2));
        const char *error = json_string_value(json_object_get(o, "error"));
        if (error)
            snprintf(job->error, sizeof(job->error), "%s", error);
        json_decref(o);

        if (job->status == JOB_RUNNING) {
            /* A complete result.json is the last thing a job writes before it
             * is done: the daemon died (or the disk was full) between that
             * and writing job.json. Anything less was cut short. */
            snprintf(path, sizeof(path), "%s/result.json", dir);
            json_t *result = access(path, F_OK) == 0 ? record_read(path, why, sizeof(why)) : NULL;
            if (result && result_complete(&job->spec, result)) {
                job->status = JOB_DONE;
                job->result = result;
                job->finished = file_mtime(path);
                atomic_store(&job->frames_done, job->frames_total);
                LOG(LOG_WARN, "job %s: job.json says running, but its result.json is complete: "
                    "done", id);
            } else {
                json_decref(result);
                job->status = JOB_INTERRUPTED;
                job->finished = clock_unix_s();
                snprintf(job->error, sizeof(job->error),
                         "interrupted: the daemon stopped (killed or crashed) while this job ran; "
                         "its files may be incomplete, submit it again to measure it");
            }
            changed = true;
        } else if (job->status == JOB_DONE) {
            snprintf(path, sizeof(path), "%s/result.json", dir);
            job->result = record_read(path, why, sizeof(why));
            if (!job->result) {
                bool present = access(path, F_OK) == 0;
                char reason[800];
                snprintf(reason, sizeof(reason), "result.json of a finished job: %s", why);
                if (present)
                    record_quarantine(&q->kind, id, path, reason, quarantined,
                                      sizeof(quarantined));
                else
                    LOG(LOG_WARN, "job %s: %s", id, reason);
                job->status = JOB_FAILED;
                snprintf(job->error, sizeof(job->error), "result.json is missing or damaged: %s%s%s",
                         why, quarantined[0] ? "; moved to " : "", quarantined);
                changed = true;
            }
        }
    }
    record_note_id(&q->kind, id);
    struct snapshot snap = {0};
    pthread_mutex_lock(&q->lock);
    bool inserted = insert_locked(q, job);
    if (inserted && job->status == JOB_QUEUED)
        q->queued++;
    if (inserted && changed)
        snapshot_locked(job, &snap);
    pthread_mutex_unlock(&q->lock);
    if (!inserted) {
        LOG(LOG_ERROR, "job %s: out of memory loading it", id);
        job_free(job);
        return;
    }
    if (snap.job)
        write_snapshot(q, &snap, NULL, 0);
}

int queue_load(struct queue *q, const struct technique_catalog *techniques, char *err, size_t errlen)
{
    q->techniques = techniques;
    size_t before = q->count;
    if (record_scan(&q->kind, load_job, q, err, errlen) < 0)
        return -1;
    pthread_mutex_lock(&q->lock);
    int loaded = (int)(q->count - before);
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    apply_retention(q);
    return loaded;
}

void queue_set_retention(struct queue *q, int keep_jobs, double keep_days)
{
    pthread_mutex_lock(&q->lock);
    q->keep_jobs = keep_jobs;
    q->keep_days = keep_days;
    pthread_mutex_unlock(&q->lock);
}

static void apply_retention(struct queue *q)
{
    pthread_mutex_lock(&q->lock);
    if (!q->kind.state_dir[0] || (q->keep_jobs <= 0 && q->keep_days <= 0) || !q->count) {
        pthread_mutex_unlock(&q->lock);
        return;
    }
    double *times = malloc(q->count * sizeof(double));
    bool *victim = malloc(q->count * sizeof(bool));
    struct job **victims = malloc(q->count * sizeof(*victims));
    size_t nv = 0, kept = 0;
    if (times && victim && victims) {
        /* A job with a write in flight is not finished for retention yet. */
        for (size_t i = 0; i < q->count; i++)
            times[i] = finished(q->jobs[i]) && !q->jobs[i]->pending ? q->jobs[i]->finished : -1;
        record_retention(times, q->count, q->keep_jobs, q->keep_days, clock_unix_s(), victim);
        for (size_t i = 0; i < q->count; i++) {
            if (victim[i])
                victims[nv++] = q->jobs[i];
            else
                q->jobs[kept++] = q->jobs[i];
        }
        q->count = kept;
    }
    pthread_mutex_unlock(&q->lock);
    /* Files are removed with no lock held. */
    for (size_t i = 0; i < nv; i++) {
        LOG(LOG_INFO, "retention: removing job %s", victims[i]->id);
        record_remove_dir(victims[i]->dir);
        job_free(victims[i]);
    }
    free(times);
    free(victim);
    free(victims);
}

json_t *queue_job_json(struct queue *q, const char *id, double wait_s)
{
    json_t *out = NULL;
    struct timespec deadline = clock_deadline(wait_s);
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    while (job && wait_s > 0 && !finished(job) && !q->stopping) {
        int rc = pthread_cond_timedwait(&q->changed, &q->lock, &deadline);
        /* Look it up again: retention may have removed it meanwhile. */
        job = find_locked(q, id);
        if (rc == ETIMEDOUT)
            break;
    }
    if (job)
        out = job_json_locked(job, true);
    pthread_mutex_unlock(&q->lock);
    return out;
}

json_t *queue_list_json(struct queue *q)
{
    json_t *list = json_array();
    pthread_mutex_lock(&q->lock);
    for (size_t i = 0; i < q->count; i++)
        json_array_append_new(list, job_json_locked(q->jobs[i], false));
    pthread_mutex_unlock(&q->lock);
    return json_pack("{s:o}", "jobs", list);
}

json_t *queue_list_json_with(struct queue *q, queue_list_fn fn, void *ctx)
{
    json_t *list = json_array();
    pthread_mutex_lock(&q->lock);
    for (size_t i = 0; i < q->count; i++) {
        const struct job *job = q->jobs[i];
        json_t *entry = job_json_locked(job, false), *labels = json_object();
        for (int k = 0; k < job->spec.nlabels; k++)
            json_object_set_new(labels, job->spec.labels[k].key,
                                json_string(job->spec.labels[k].value));
        json_object_set_new(entry, "labels", labels);
        if ((entry = fn(entry, job->result, ctx)))
            json_array_append_new(list, entry);
    }
    pthread_mutex_unlock(&q->lock);
    return json_pack("{s:o}", "jobs", list);
}

bool queue_job_dir(struct queue *q, const char *id, char *dir, size_t cap,
                   enum job_status *status)
{
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    if (job) {
        snprintf(dir, cap, "%s", job->dir);
        *status = job->status;
    }
    pthread_mutex_unlock(&q->lock);
    return job != NULL;
}
