#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/queue.h"

#include "common/job_files.h"
#include "common/clock.h"
#include "common/log.h"
#include "common/result_keys.h"
#include "daemon/spec/job_cost.h"
#include "daemon/spec/job_figures.h"
#include "daemon/jobs/job_eta.h"
#include "daemon/store/job_dir.h"
#include "daemon/store/store_reserve.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Retention removes at most a batch at a time: after a job finishes (so
 * between jobs, never in a timed region), and at startup for at most
 * RETENTION_START_S, so that a large backlog (a lowered --keep-jobs) never
 * holds up the start; the rest goes a batch per finished job. */
#define RETENTION_BATCH 256
#define RETENTION_START_S 2.0
/* While the disk is full, the render thread asks this often whether there
 * is room again (store_has_room) before it starts a job. */
#define ROOM_POLL_S 1.0

struct queue {
    /* Guards everything below and the live jobs' queue-owned fields. Never
     * held across file I/O or a store write: see struct snapshot. */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct store_live live; /* struct job: queued, running, or not yet stored */
    int queued, max_queued; /* queued counts submissions in progress too */
    bool stopping;
    int keep_jobs;
    double keep_days;
    struct store *store;
    const struct technique_catalog *techniques; /* for queue_load */
    void (*listener)(void *ctx);
    void *listener_ctx;
    /* The retention guard; its lock is held while it is asked, so that it
     * is never asked once unset. */
    pthread_mutex_t guard;
    bool (*needed)(void *ctx, const char *id);
    void *needed_ctx;
    pthread_mutex_t repair;    /* one repair of a damaged result.json at a time */
    pthread_mutex_t retention; /* one retention pass at a time */
    /* scene.asset's pins (queue_set_asset_hooks); hooks_lock is held while
     * one is called, so that none runs once they are unset. */
    pthread_mutex_t hooks_lock;
    struct queue_asset_hooks hooks;
};

/* A job's state as taken under the lock, written after it is released. The
 * job stays in memory until then (pending). */
struct snapshot {
    struct job *job;
    uint64_t seq;
    struct store_row row;
};

/* The parts of a job's state that its JSON shows and that change. */
struct job_state {
    enum job_status status;
    const char *phase;
    double started, finished;
    const char *error;
    int frames_done;
};

static void apply_retention(struct queue *q, bool startup);

void queue_set_listener(struct queue *q, void (*fn)(void *ctx), void *ctx)
{
    q->listener = fn;
    q->listener_ctx = ctx;
}

void queue_set_retention_guard(struct queue *q, bool (*needed)(void *ctx, const char *id),
                               void *ctx)
{
    pthread_mutex_lock(&q->guard);
    q->needed = needed;
    q->needed_ctx = ctx;
    pthread_mutex_unlock(&q->guard);
}

static bool needed_elsewhere(struct queue *q, const char *id)
{
    pthread_mutex_lock(&q->guard);
    bool needed = q->needed && q->needed(q->needed_ctx, id);
    pthread_mutex_unlock(&q->guard);
    return needed;
}

#define NOTIFY_LISTENER(q) ((q)->listener ? (q)->listener((q)->listener_ctx) : (void)0)

static bool finished(const struct job *job) { return job_status_finished(job->status); }

static struct job_state state_of(const struct job *job)
{
    return (struct job_state){job->status, job->phase, job->started, job->finished, job->error,
                              atomic_load_explicit(&job->frames_done, memory_order_relaxed)};
}

/* A finished job's spec is its spec.json, written when it was accepted and
 * never changed: its row keeps the spec only while the job may still run
 * (to queue it again after a restart), or where there is no spec.json
 * (--once). Rows stay small: about 1 KB a job rather than 5. */
static bool row_keeps_spec(enum job_status status, bool dir_given)
{
    return !job_status_finished(status) || dir_given;
}

/* The job's row in the store for state st; figures from result once done. */
static void row_of(const struct job *job, const struct job_state *st, const json_t *result,
                   struct store_row *row)
{
    store_row_init(row, STORE_JOBS);
    snprintf(row->id, sizeof(row->id), "%s", job->id);
    row->status = st->status;
    snprintf(row->technique, sizeof(row->technique), "%s", job->spec.technique);
    row->created = job->created;
    row->started = st->started;
    row->finished = st->finished;
    row->done = st->frames_done;
    row->total = job->frames_total;
    snprintf(row->error, sizeof(row->error), "%s", st->error ? st->error : "");
    if (job->dir_given) {
        snprintf(row->dir, sizeof(row->dir), "%s", job->dir);
        row->dir_given = true;
    }
    row->labels = job_dir_labels(&job->spec);
    row->figures = st->status == JOB_DONE ? job_figures(result) : NULL;
    row->spec = row_keeps_spec(st->status, job->dir_given) ? job_spec_to_json(&job->spec) : NULL;
}

/* Under the lock: the job's state changed; number it and copy it. */
static void snapshot_locked(struct job *job, struct snapshot *snap)
{
    struct job_state st = state_of(job);
    snap->job = job;
    snap->seq = store_version_take(&job->version);
    row_of(job, &st, job->result, &snap->row);
}

static struct job *find_locked(struct queue *q, const char *id)
{
    return store_live_find(&q->live, id);
}

static void job_free(struct job *job)
{
    if (!job)
        return;
    json_decref(job->result);
    free(job);
}

/* A finished job whose newest state is stored leaves memory: from then on
 * it is read from the store. Returns the job to free once the lock is
 * released, or NULL. */
static struct job *evict_locked(struct queue *q, struct job *job)
{
    if (!finished(job) || !store_version_stored(&job->version))
        return NULL;
    store_live_remove(&q->live, job);
    return job;
}

/* Without the lock: stores the snapshot unless a newer one is stored, and
 * releases the job (which may then leave memory). Failures are logged with
 * the database and the system's reason. */
static bool write_snapshot(struct queue *q, struct snapshot *snap, char *err, size_t errlen)
{
    struct job *job = snap->job;
    char why[PATH_MAX + 300] = "";
    bool ok = store_put(q->store, &snap->row, snap->seq, &job->version.written, why, sizeof(why));
    if (!ok)
        LOG(LOG_ERROR, "job %s: its state (%s%s%s) cannot be stored: %s; it is tried again with "
            "the job's next change and at exit", job->id, job_status_name(snap->row.status),
            snap->row.error[0] ? ": " : "", snap->row.error, why);
    if (err)
        snprintf(err, errlen, "%s", why);
    store_row_finish(&snap->row);
    pthread_mutex_lock(&q->lock);
    store_version_back(&job->version, snap->seq, ok);
    struct job *gone = evict_locked(q, job);
    pthread_mutex_unlock(&q->lock);
    job_free(gone);
    return ok;
}

struct queue *queue_create(struct store *store, int max_queued)
{
    struct queue *q = calloc(1, sizeof(*q));
    if (!q)
        return NULL;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->changed, NULL);
    pthread_mutex_init(&q->guard, NULL);
    pthread_mutex_init(&q->repair, NULL);
    pthread_mutex_init(&q->retention, NULL);
    pthread_mutex_init(&q->hooks_lock, NULL);
    q->max_queued = max_queued;
    q->store = store;
    return q;
}

struct store *queue_store(const struct queue *q) { return q->store; }

void queue_destroy(struct queue *q)
{
    if (!q)
        return;
    /* Every other thread is gone: state a full disk held back gets one more
     * try, so that a restart does not find it stale; the log says which
     * state made it and which did not, and what the next start will do. */
    for (size_t i = 0; i < q->live.count;) {
        struct job *job = q->live.items[i];
        size_t before = q->live.count;
        if (job->version.saved < job->version.seq) {
            struct snapshot snap;
            pthread_mutex_lock(&q->lock);
            snapshot_locked(job, &snap);
            pthread_mutex_unlock(&q->lock);
            char id[RECORD_ID_LEN], why[PATH_MAX + 300];
            enum job_status status = snap.row.status;
            snprintf(id, sizeof(id), "%s", job->id);
            if (write_snapshot(q, &snap, why, sizeof(why))) /* a finished one leaves the list */
                LOG(LOG_INFO, "job %s: its state (%s) was stored at exit", id,
                    job_status_name(status));
            else
                LOG(LOG_ERROR, "job %s: its state (%s) could not be stored at exit either (%s); "
                    "it is noted in %s/%s, from which the next start records it", id,
                    job_status_name(status), why, store_state_dir(q->store), STORE_RESERVE_FILE);
        }
        if (q->live.count == before)
            i++;
    }
    for (size_t i = 0; i < q->live.count; i++)
        job_free(q->live.items[i]);
    store_live_finish(&q->live);
    pthread_mutex_destroy(&q->retention);
    pthread_mutex_destroy(&q->hooks_lock);
    pthread_mutex_destroy(&q->repair);
    pthread_mutex_destroy(&q->guard);
    pthread_cond_destroy(&q->changed);
    pthread_mutex_destroy(&q->lock);
    free(q);
}

int queue_max_queued(const struct queue *q) { return q->max_queued; }

void queue_retention(struct queue *q, int *keep_jobs, double *keep_days)
{
    pthread_mutex_lock(&q->lock);
    *keep_jobs = q->keep_jobs;
    *keep_days = q->keep_days;
    pthread_mutex_unlock(&q->lock);
}

const char *queue_submit_error(void) { return records_submit_error(); }

bool queue_room_to_accept(struct queue *q, const char *what)
{
    if (store_has_room(q->store))
        return true;
    records_set_submit_error("the %s cannot be persisted in the state directory %s: %s (its disk "
                             "is full, but for the reserve kept for recording how the jobs "
                             "accepted end, %s); free some space", what,
                             store_state_dir(q->store), strerror(ENOSPC), STORE_RESERVE_FILE);
    /* Once every 10 s: each refusal is answered, a full disk's log need not
     * grow by one line per submission. */
    static _Atomic double last_logged = -1e9;
    double now = clock_mono_s(), then = atomic_load(&last_logged);
    if (now - then >= 10 && atomic_compare_exchange_strong(&last_logged, &then, now))
        LOG(LOG_ERROR, "%s refused (and any more in the next 10 s): %s", what,
            records_submit_error());
    return false;
}

static struct job *job_new(void)
{
    struct job *job = calloc(1, sizeof(*job));
    if (!job)
        return NULL;
    atomic_init(&job->cancel, false);
    atomic_init(&job->frames_done, 0);
    atomic_init(&job->frames_began, 0.0);
    return job;
}

static enum queue_submit_result submit_pinned(struct queue *q, const struct job_spec *spec,
                                              const char *dir_override, char id_out[24]);

static bool pin_spec(struct queue *q, struct job_spec *spec, bool restore, bool *pinned)
{
    char field[64] = "", message[512] = "";
    pthread_mutex_lock(&q->hooks_lock);
    bool ok = !q->hooks.pin || q->hooks.pin(q->hooks.ctx, spec, restore, field, sizeof(field),
                                            message, sizeof(message));
    *pinned = ok && q->hooks.pin;
    pthread_mutex_unlock(&q->hooks_lock);
    if (!ok)
        records_set_submit_error("%s: %s", field, message);
    return ok;
}

static void unpin_spec(struct queue *q, const struct job_spec *spec)
{
    pthread_mutex_lock(&q->hooks_lock);
    if (q->hooks.unpin)
        q->hooks.unpin(q->hooks.ctx, spec);
    pthread_mutex_unlock(&q->hooks_lock);
}

/* A sweep's scene alone, as a spec that names nothing else. */
bool queue_asset_pin(struct queue *q, struct scene_spec *scene, bool restore)
{
    struct job_spec spec;
    memset(&spec, 0, sizeof(spec));
    spec.scene = *scene;
    bool pinned;
    bool ok = pin_spec(q, &spec, restore, &pinned);
    *scene = spec.scene;
    return ok;
}

void queue_asset_unpin(struct queue *q, const struct scene_spec *scene)
{
    struct job_spec spec;
    memset(&spec, 0, sizeof(spec));
    spec.scene = *scene;
    unpin_spec(q, &spec);
}

/* The asset's pin of a submission, resolved and pinned in one step; false
 * with queue_submit_error's text when refused. The job's cost is admitted
 * again with the asset's memory (job_cost.h: a sweep's point too). */
static bool pin_asset(struct queue *q, struct job_spec *spec, bool *pinned)
{
    if (!pin_spec(q, spec, false, pinned))
        return false;
    struct job_cost cost;
    struct job_error err;
    job_cost_estimate(spec, &cost);
    if (!job_cost_admit(&cost, &err)) {
        records_set_submit_error("%s: %s", err.field, err.message);
        return false;
    }
    return true;
}

static void unpin_asset(struct queue *q, const struct job_spec *spec, bool pinned)
{
    if (pinned)
        unpin_spec(q, spec);
}

/* A job on an asset has finished: its hash may go (queue_asset_hooks). */
static void asset_ended(struct queue *q, const struct job_spec *spec)
{
    if (!job_spec_names_asset(spec))
        return;
    pthread_mutex_lock(&q->hooks_lock);
    if (q->hooks.ended)
        q->hooks.ended(q->hooks.ctx, spec);
    pthread_mutex_unlock(&q->hooks_lock);
}

enum queue_submit_result queue_submit(struct queue *q, const struct job_spec *spec,
                                      const char *dir_override, char id_out[24])
{
    records_set_submit_error("%s", "");
    /* Every job naming an asset, a sweep's points included, is pinned to the
     * asset's hash in the step that resolves it, and stays pinned until it
     * is live or refused (daemon/jobs/assets.h). */
    struct job_spec resolved;
    bool pinned = false;
    if (job_spec_names_asset(spec)) {
        resolved = *spec;
        bool ok = pin_asset(q, &resolved, &pinned);
        if (!ok) {
            unpin_asset(q, &resolved, pinned);
            return QUEUE_REFUSED;
        }
        spec = &resolved;
    }
    enum queue_submit_result res = submit_pinned(q, spec, dir_override, id_out);
    unpin_asset(q, spec, pinned);
    return res;
}

/* queue_submit once its asset, if any, is pinned. */
static enum queue_submit_result submit_pinned(struct queue *q, const struct job_spec *spec,
                                              const char *dir_override, char id_out[24])
{
    char why[PATH_MAX + 300] = "";
    if (!queue_room_to_accept(q, "job"))
        return QUEUE_IO_ERROR;
    pthread_mutex_lock(&q->lock);
    enum queue_submit_result res = q->stopping                  ? QUEUE_STOPPING
                                   : q->queued >= q->max_queued ? QUEUE_FULL
                                                                : QUEUE_OK;
    if (res == QUEUE_OK)
        q->queued++; /* the place is taken while the files are written */
    pthread_mutex_unlock(&q->lock);
    if (res != QUEUE_OK)
        return res;

    /* The directory, spec.json and the row are written with no lock held;
     * the job joins the queue only once they are stored, so a job that
     * cannot be persisted is refused and nothing of it is left behind. */
    struct job *job = job_new();
    bool made_dir = false;
    if (!job) {
        snprintf(why, sizeof(why), "out of memory");
        goto fail;
    }
    if (!record_create_dir(store_record_kind(q->store, STORE_JOBS), dir_override, job->id,
                           job->dir, sizeof(job->dir), why, sizeof(why)))
        goto fail;
    made_dir = !dir_override;
    job->dir_given = dir_override != NULL;
    job->spec = *spec;
    job->status = JOB_QUEUED;
    job->frames_total = spec->frames * job_spec_runs(spec);
    job->created = clock_unix_s();
    if (!dir_override && !job_dir_write_spec(job->dir, job->id, job->created, spec, why, sizeof(why)))
        goto fail;
    struct snapshot first;
    snapshot_locked(job, &first); /* not shared yet: no lock needed */
    bool stored = store_put(q->store, &first.row, first.seq, &job->version.written, why,
                            sizeof(why));
    store_row_finish(&first.row);
    store_version_back(&job->version, first.seq, stored);
    if (!stored)
        goto fail;
    pthread_mutex_lock(&q->lock);
    bool inserted = store_live_insert(&q->live, job);
    if (inserted)
        pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    if (!inserted) {
        /* Stored but not queued: it runs on the next start. */
        snprintf(why, sizeof(why), "out of memory");
        made_dir = false;
        goto fail;
    }
    snprintf(id_out, 24, "%s", job->id);
    return QUEUE_OK;

fail:
    records_set_submit_error("the job cannot be persisted in the state directory %s: %s",
                             store_state_dir(q->store)[0] ? store_state_dir(q->store)
                             : dir_override               ? dir_override
                                                          : "(none)",
                             why);
    LOG(LOG_ERROR, "job refused: %s", records_submit_error());
    if (made_dir) {
        /* Never accepted, so not a record: remove what was made of it. */
        static const char *const files[] = {JOB_FILE_SPEC, JOB_FILE_SPEC ".tmp"};
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

/* Under the lock: the first queued job, or NULL. */
static struct job *first_queued_locked(struct queue *q)
{
    for (size_t i = 0; i < q->live.count; i++)
        if (((struct job *)q->live.items[i])->status == JOB_QUEUED)
            return q->live.items[i];
    return NULL;
}

/* Under the lock: waits up to seconds for a change (a stop, a new job). */
static void wait_locked(struct queue *q, double seconds)
{
    struct timespec until = clock_deadline(seconds);
    pthread_cond_timedwait(&q->changed, &q->lock, &until);
}

struct job *queue_next(struct queue *q)
{
    /* A job starts only once the store has recorded that it runs: one that
     * ran unrecorded would run again after a restart, as if it had never
     * run. So while the disk is full (no room in the store's reserve, or
     * the write fails) the queued jobs wait, and say why in the log. */
    bool told = false;
    pthread_mutex_lock(&q->lock);
    while (!q->stopping) {
        struct job *job = first_queued_locked(q);
        if (!job) {
            pthread_cond_wait(&q->changed, &q->lock);
            continue;
        }
        pthread_mutex_unlock(&q->lock);
        bool room = store_has_room(q->store);
        pthread_mutex_lock(&q->lock);
        if (q->stopping || job != first_queued_locked(q))
            continue; /* cancelled meanwhile, or stopping */
        if (!room) {
            if (!told)
                LOG(LOG_ERROR, "job %s waits: the disk of the state directory %s is full, and a "
                    "job starts only once the store can record how it ends",
                    job->id, store_state_dir(q->store));
            told = true;
            wait_locked(q, ROOM_POLL_S);
            continue;
        }
        struct snapshot snap;
        job->status = JOB_RUNNING;
        job->phase = "rendering";
        job->started = clock_unix_s();
        q->queued--;
        snapshot_locked(job, &snap);
        pthread_cond_broadcast(&q->changed);
        pthread_mutex_unlock(&q->lock);
        if (write_snapshot(q, &snap, NULL, 0)) {
            if (told)
                LOG(LOG_INFO, "job %s starts: the store has room again", job->id);
            return job;
        }
        /* Not recorded as running: back to the head of the queue (which the
         * store still says it is in), to start once it can be. */
        pthread_mutex_lock(&q->lock);
        job->status = JOB_QUEUED;
        job->phase = NULL;
        job->started = 0;
        q->queued++;
        told = true;
        wait_locked(q, ROOM_POLL_S);
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

void queue_progress(struct queue *q, struct job *job, int frames_done)
{
    (void)q;
    atomic_store_explicit(&job->frames_done, frames_done, memory_order_relaxed);
    if (frames_done > 0 && atomic_load_explicit(&job->frames_began, memory_order_relaxed) == 0)
        atomic_store_explicit(&job->frames_began, clock_unix_s(), memory_order_relaxed);
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
    struct job_spec ended_spec = job->spec; /* the job may leave memory below */
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
    snap.seq = store_version_take(&job->version);
    row_of(job, &next, result, &snap.row);
    pthread_mutex_unlock(&q->lock);
    /* Stored before anyone can see it (the job is running, so only this
     * thread changes its state): a job shown finished is finished in the
     * store, unless the write failed, which is logged. */
    write_snapshot(q, &snap, NULL, 0);

    pthread_mutex_lock(&q->lock);
    if (requeue) {
        job->status = JOB_QUEUED;
        job->phase = NULL;
        job->started = 0;
        job->error[0] = '\0';
        atomic_store(&job->frames_done, 0);
        atomic_store(&job->frames_began, 0.0);
        atomic_store(&job->cancel, false);
        job->requeue_on_stop = false;
        json_decref(result);
        q->queued++;
    } else {
        job->status = status;
        job->finished = next.finished;
        if (status == JOB_DONE && result && job->started > 0)
            job_eta_observe_result(&job->spec, result, next.finished - job->started);
        if (error)
            snprintf(job->error, sizeof(job->error), "%s", error);
        json_decref(job->result);
        job->result = result;
    }
    /* Had anyone taken a newer view meanwhile, the newest goes last. */
    bool again = job->version.seq != snap.seq;
    if (again)
        snapshot_locked(job, &snap);
    /* The caller's last touch of the job: it may leave memory now. */
    struct job *gone = again ? NULL : evict_locked(q, job);
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
    if (again)
        write_snapshot(q, &snap, NULL, 0);
    if (requeue)
        LOG(LOG_INFO, "job %s: stopped by the daemon's exit; back to the head of the queue",
            job->id);
    job_free(gone);
    if (!requeue)
        asset_ended(q, &ended_spec);
    apply_retention(q, false);
}

void queue_stop(struct queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->stopping = true;
    /* A running job stops at its next frame rather than holding up the exit,
     * and goes back to the queue: the stop is not its fault. */
    for (size_t i = 0; i < q->live.count; i++) {
        struct job *job = q->live.items[i];
        if (job->status == JOB_RUNNING) {
            job->requeue_on_stop = !job->user_cancel;
            atomic_store(&job->cancel, true);
        }
    }
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
}

void queue_store_abandoned(struct queue *q)
{
    struct snapshot snaps[8];
    int n = 0;
    pthread_mutex_lock(&q->lock);
    for (size_t i = 0; i < q->live.count && n < 8; i++) {
        struct job *job = q->live.items[i];
        if (job->status != JOB_RUNNING)
            continue;
        /* What queue_finish would store: a DELETE's cancel stays cancelled,
         * a job stopped by the daemon goes back to the queue. */
        struct job_state next = state_of(job);
        if (job->user_cancel) {
            next.status = JOB_CANCELLED;
            next.finished = clock_unix_s();
            next.error = "cancelled (the daemon stopped while its render thread was still "
                         "letting go of it)";
        } else {
            next.status = JOB_QUEUED;
            next.phase = NULL;
            next.started = 0;
            next.error = "";
            next.frames_done = 0;
        }
        snaps[n].job = job;
        snaps[n].seq = store_version_take(&job->version);
        row_of(job, &next, NULL, &snaps[n].row);
        n++;
    }
    pthread_mutex_unlock(&q->lock);
    for (int i = 0; i < n; i++)
        write_snapshot(q, &snaps[i], NULL, 0);
}

enum queue_cancel_result queue_cancel(struct queue *q, const char *id)
{
    enum queue_cancel_result res = CANCEL_NOT_FOUND;
    struct snapshot snap = {0};
    struct job_spec ended_spec = {0}; /* a queued job's, cancelled: its assets may go */
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    if (!job) {
        pthread_mutex_unlock(&q->lock);
        /* Not live: finished (only live jobs can change), or no such job. */
        struct store_row row;
        enum store_found found = store_get(q->store, STORE_JOBS, id, false, &row);
        store_row_finish(&row);
        return found == STORE_FOUND ? CANCEL_FINISHED : CANCEL_NOT_FOUND;
    }
    switch (job->status) {
    case JOB_QUEUED:
        job->status = JOB_CANCELLED;
        job->finished = clock_unix_s();
        snprintf(job->error, sizeof(job->error), "cancelled before it started");
        q->queued--;
        ended_spec = job->spec;
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
    pthread_mutex_unlock(&q->lock);
    if (snap.job)
        write_snapshot(q, &snap, NULL, 0);
    asset_ended(q, &ended_spec);
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

/* What a job's JSON shows of its state, live or stored alike. */
static json_t *state_json(const char *id, const char *technique, double created,
                          const struct job_state *st, int frames_total)
{
    json_t *o = json_pack("{s:s, s:s, s:s, s:{s:i, s:i}, s:o, s:o, s:o}", "id", id, "status",
                          job_status_name(st->status), "technique", technique, "progress",
                          "frames_done", st->frames_done, "frames_total", frames_total, "created",
                          iso_time(created), "started", iso_time(st->started), "finished",
                          iso_time(st->finished));
    if (!o)
        return NULL;
    if (st->status == JOB_RUNNING && st->phase)
        json_object_set_new(o, "phase", json_string(st->phase));
    if (st->error && st->error[0])
        json_object_set_new(o, "error", json_string(st->error));
    return o;
}

/* A queued or running job's estimate (job_eta.h): the whole job's, and
 * while it runs the time left by the frames it has drawn. */
static json_t *estimate_json(const struct job *job, const struct job_state *st)
{
    struct job_eta e;
    job_eta_estimate(&job->spec, &e);
    json_t *o = json_pack("{s:o}", "estimate", job_eta_json(&e));
    if (st->status != JOB_RUNNING)
        return o;
    double began = atomic_load(&job->frames_began), now = clock_unix_s();
    int done = st->frames_done;
    /* The first counted frame marks when frames began: the rate is over
     * the frames after it. */
    double left = began > 0 ? job_eta_left(done - 1, job->frames_total - 1, now - began) : -1;
    if (left >= 0)
        json_object_set_new(o, "seconds_left",
                            json_pack("{s:f, s:s}", "frames", left, "rule",
                                      "the frames left of every run at the rate of the frames "
                                      "drawn since the first; the reference and metrics, if "
                                      "any, come on top"));
    else if (e.known && st->started > 0)
        json_object_set_new(o, "seconds_left",
                            json_pack("{s:f, s:s}", "estimate",
                                      fmax(0.0, e.duration_s - (now - st->started)), "rule",
                                      "before its first frame: the estimate less the time it "
                                      "has run"));
    return o;
}

static json_t *live_json_locked(const struct job *job, bool full)
{
    struct job_state st = state_of(job);
    json_t *o = state_json(job->id, job->spec.technique, job->created, &st, job->frames_total);
    if (o && (st.status == JOB_QUEUED || st.status == JOB_RUNNING))
        json_object_update_new(o, estimate_json(job, &st));
    if (o && full) {
        json_object_set_new(o, "spec", job_spec_to_json(&job->spec));
        if (job->result)
            json_object_set_new(o, RK_RESULT, json_deep_copy(job->result));
    }
    return o;
}

static struct job_state row_state(const struct store_row *row)
{
    return (struct job_state){row->status, NULL, row->started, row->finished, row->error,
                              row->done};
}

/* A stored (finished) job as GET /v1/jobs/ID shows it; NULL when there is
 * no such job. A done job's result comes from its result.json. */
static json_t *stored_job_json(struct queue *q, const char *id)
{
    struct store_row row;
    if (store_get(q->store, STORE_JOBS, id, true, &row) != STORE_FOUND) {
        store_row_finish(&row);
        return NULL;
    }
    json_t *result = NULL;
    if (row.status == JOB_DONE) {
        char path[PATH_MAX + 16], why[600] = "";
        snprintf(path, sizeof(path), "%s/result.json", row.dir);
        result = record_read(path, why, sizeof(why));
        if (!result) {
            pthread_mutex_lock(&q->repair);
            /* Another reader may have repaired it meanwhile. */
            store_row_finish(&row);
            if (store_get(q->store, STORE_JOBS, id, true, &row) == STORE_FOUND &&
                row.status == JOB_DONE && !(result = record_read(path, why, sizeof(why))))
                job_dir_fail_result(q->store, &row, path, why);
            pthread_mutex_unlock(&q->repair);
        }
    }
    if (!row.spec)
        row.spec = job_dir_read_spec(&row);
    struct job_state st = row_state(&row);
    json_t *o = state_json(row.id, row.technique, row.created, &st, row.total);
    if (o) {
        json_object_set_new(o, "spec", row.spec ? json_incref(row.spec) : json_object());
        if (result && row.status == JOB_DONE)
            json_object_set(o, RK_RESULT, result);
    }
    json_decref(result);
    store_row_finish(&row);
    return o;
}

json_t *queue_job_json(struct queue *q, const char *id, double wait_s)
{
    json_t *out = NULL;
    struct timespec deadline = clock_deadline(wait_s);
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    while (job && wait_s > 0 && !finished(job) && !q->stopping) {
        int rc = pthread_cond_timedwait(&q->changed, &q->lock, &deadline);
        /* Look it up again: once finished and stored, it leaves memory. */
        job = find_locked(q, id);
        if (rc == ETIMEDOUT)
            break;
    }
    if (job)
        out = live_json_locked(job, true);
    pthread_mutex_unlock(&q->lock);
    return job ? out : stored_job_json(q, id);
}

struct page {
    json_t *jobs;
};

static void page_row(void *ctx, const struct store_row *row)
{
    struct page *p = ctx;
    struct job_state st = row_state(row);
    json_t *entry = state_json(row->id, row->technique, row->created, &st, row->total);
    if (!entry)
        return;
    json_object_set_new(entry, "labels", row->labels ? json_incref(row->labels) : json_object());
    if (row->figures)
        json_object_set(entry, "figures", row->figures);
    json_array_append_new(p->jobs, entry);
}

json_t *queue_list_page(struct queue *q, const struct store_query *query,
                        char next[RECORD_ID_LEN], char *err, size_t errlen)
{
    struct page p = {.jobs = json_array()};
    if (!p.jobs || !store_list(q->store, query, page_row, &p, next, err, errlen)) {
        json_decref(p.jobs);
        return NULL;
    }
    /* Queued and running jobs: their state in memory is the newest
     * (progress and phase are never stored while they run). */
    size_t i;
    json_t *entry;
    pthread_mutex_lock(&q->lock);
    json_array_foreach(p.jobs, i, entry) {
        const struct job *job = find_locked(q, json_string_value(json_object_get(entry, "id")));
        if (!job)
            continue;
        json_t *live = live_json_locked(job, false);
        json_object_del(entry, "phase");
        json_object_del(entry, "error");
        json_object_update(entry, live);
        json_decref(live);
    }
    pthread_mutex_unlock(&q->lock);
    return json_pack("{s:o}", "jobs", p.jobs);
}

bool queue_counts(struct queue *q, size_t counts[JOB_STATUS_COUNT])
{
    return store_count(q->store, STORE_JOBS, counts);
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
    if (job)
        return true;
    struct store_row row;
    bool found = store_get(q->store, STORE_JOBS, id, false, &row) == STORE_FOUND;
    if (found) {
        snprintf(dir, cap, "%s", row.dir);
        *status = row.status;
    }
    store_row_finish(&row);
    return found;
}

/* --- Loading -------------------------------------------------------------- */

/* store_import: a job directory the store has no row for (job_dir.h). */
static bool import_job(void *ctx, const char *id, const char *dir, struct store_row *row)
{
    struct queue *q = ctx;
    return job_dir_import(q->store, q->techniques, id, dir, row);
}

/* Startup: a queued job joins the queue; one that was running when the
 * daemon died is interrupted, or done when its result.json is complete. */
static void load_unfinished(void *ctx, const struct store_row *stored)
{
    struct queue *q = ctx;
    struct store_row row = *stored; /* its JSON stays the store's */
    row.figures = NULL;             /* an unfinished job has none */
    struct job_spec spec;
    struct job_error jerr;
    char err[PATH_MAX + 300];
    /* An unfinished row has its spec; should it not, spec.json has. */
    json_t *read = row.spec ? NULL : job_dir_read_spec(&row);
    bool parsed = job_spec_parse(row.spec ? row.spec : read, q->techniques, &spec, &jerr);
    json_decref(read);
    if (!parsed) {
        row.spec = NULL; /* finished: its spec.json has it */
        row.status = JOB_FAILED;
        row.finished = clock_unix_s();
        snprintf(row.error, sizeof(row.error), "not a job this daemon can run (%s: %s)",
                 jerr.field, jerr.message);
        LOG(LOG_WARN, "job %s: %s", row.id, row.error);
        if (!store_put(q->store, &row, 0, NULL, err, sizeof(err)))
            LOG(LOG_ERROR, "job %s: %s", row.id, err);
        return;
    }
    /* A state the last run could not store, for want of space, is in the
     * store's reserve (store_reserve.h): it is newer than the row. */
    enum job_status noted = row.status;
    char noted_error[sizeof(row.error)] = "";
    bool note = store_unrecorded(q->store, STORE_JOBS, row.id, &noted, noted_error,
                                 sizeof(noted_error));
    if (note)
        LOG(LOG_WARN, "job %s: stored as %s, but the last run noted it %s (the disk was full)",
            row.id, job_status_name(row.status), job_status_name(noted));
    if (note && noted == JOB_QUEUED && row.status == JOB_RUNNING) {
        /* Stopped by SIGTERM and sent back to the queue, unrecorded. */
        row.status = JOB_QUEUED;
        row.started = 0;
        row.done = 0;
        if (!store_put(q->store, &row, 0, NULL, err, sizeof(err)))
            LOG(LOG_ERROR, "job %s: %s", row.id, err);
    }
    bool noted_end = note && job_status_finished(noted) && noted != JOB_DONE;
    if (row.status == JOB_QUEUED && !noted_end) {
        struct job *job = job_new();
        if (!job) {
            LOG(LOG_ERROR, "job %s: out of memory loading it; it runs on the next start", row.id);
            return;
        }
        snprintf(job->id, sizeof(job->id), "%s", row.id);
        snprintf(job->dir, sizeof(job->dir), "%s", row.dir);
        job->dir_given = row.dir_given;
        job->spec = spec;
        job->status = JOB_QUEUED;
        job->frames_total = row.total;
        job->created = row.created;
        pthread_mutex_lock(&q->lock);
        bool inserted = store_live_insert(&q->live, job);
        if (inserted)
            q->queued++;
        pthread_mutex_unlock(&q->lock);
        if (!inserted) {
            LOG(LOG_ERROR, "job %s: out of memory loading it; it runs on the next start", row.id);
            job_free(job);
        }
        return;
    }
    /* Running when the daemon died: what an interrupted write left goes. */
    record_remove_tmp_files(row.dir);
    if (!row.dir_given)
        row.spec = NULL; /* finished now: its spec.json has it */
    char why[800] = "";
    json_t *figures = NULL;
    if (noted_end) {
        row.status = noted;
        row.finished = clock_unix_s();
        snprintf(row.error, sizeof(row.error), "%.700s (stored at the next start: the disk was "
                 "full when the job ended)", noted_error);
    } else if (job_dir_done_from_result(q->store, &row, &spec, row.dir, why, sizeof(why))) {
        figures = row.figures; /* ours, not the store's */
        LOG(LOG_WARN, "job %s: stored as running, but its result.json is complete: done", row.id);
    } else if (note) {
        row.status = JOB_INTERRUPTED;
        row.finished = clock_unix_s();
        snprintf(row.error, sizeof(row.error), "interrupted: the disk was full when this job "
                 "ended %s, which could not be stored, and its result.json is %.400s; submit it "
                 "again to measure it", job_status_name(noted), why);
    } else {
        job_dir_interrupted(&row, why);
    }
    if (!store_put(q->store, &row, 0, NULL, err, sizeof(err)))
        LOG(LOG_ERROR, "job %s: %s", row.id, err);
    json_decref(figures);
}

int queue_load(struct queue *q, const struct technique_catalog *techniques, char *err, size_t errlen)
{
    q->techniques = techniques;
    int imported = store_import(q->store, STORE_JOBS, "job.json", import_job, q, err, errlen);
    if (imported < 0)
        return -1;
    if (imported > 0)
        LOG(LOG_INFO, "imported %d job(s) from their directories into %s/%s", imported,
            store_state_dir(q->store), STORE_FILE);
    if (!store_each_unfinished(q->store, STORE_JOBS, load_unfinished, q)) {
        snprintf(err, errlen, "cannot read the unfinished jobs from %s/%s",
                 store_state_dir(q->store), STORE_FILE);
        return -1;
    }
    store_unrecorded_done(q->store);
    pthread_mutex_lock(&q->lock);
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    apply_retention(q, true);
    size_t counts[JOB_STATUS_COUNT];
    if (!store_count(q->store, STORE_JOBS, counts)) {
        snprintf(err, errlen, "cannot count the jobs in %s/%s", store_state_dir(q->store),
                 STORE_FILE);
        return -1;
    }
    size_t total = 0;
    for (int k = 0; k < JOB_STATUS_COUNT; k++)
        total += counts[k];
    return (int)total;
}

void queue_set_retention(struct queue *q, int keep_jobs, double keep_days)
{
    pthread_mutex_lock(&q->lock);
    q->keep_jobs = keep_jobs;
    q->keep_days = keep_days;
    pthread_mutex_unlock(&q->lock);
}

static void apply_retention(struct queue *q, bool startup)
{
    int keep;
    double days;
    queue_retention(q, &keep, &days);
    if (!store_state_dir(q->store)[0] || (keep <= 0 && days <= 0))
        return;
    char(*ids)[RECORD_ID_LEN] = malloc(RETENTION_BATCH * RECORD_ID_LEN);
    if (!ids)
        return;
    pthread_mutex_lock(&q->retention);
    double t0 = clock_mono_s();
    for (;;) {
        int n = store_retention_victims(q->store, STORE_JOBS, keep, days, clock_unix_s(), ids,
                                        RETENTION_BATCH);
        /* A job still in memory, or one a sweep still needs, stays for now. */
        int m = 0;
        for (int i = 0; i < n; i++) {
            pthread_mutex_lock(&q->lock);
            bool live = find_locked(q, ids[i]) != NULL;
            pthread_mutex_unlock(&q->lock);
            if (!live && !needed_elsewhere(q, ids[i]))
                memmove(ids[m++], ids[i], RECORD_ID_LEN);
        }
        if (m > 0 && m <= 8)
            for (int i = 0; i < m; i++)
                LOG(LOG_INFO, "retention: removing job %s", ids[i]);
        else if (m > 8)
            LOG(LOG_INFO, "retention: removing %d jobs, %s to %s", m, ids[0], ids[m - 1]);
        store_remove(q->store, STORE_JOBS, ids, m);
        if (!startup || n < RETENTION_BATCH || m < n || clock_mono_s() - t0 > RETENTION_START_S)
            break;
    }
    pthread_mutex_unlock(&q->retention);
    free(ids);
}

void queue_set_asset_hooks(struct queue *q, const struct queue_asset_hooks *hooks)
{
    pthread_mutex_lock(&q->hooks_lock);
    q->hooks = hooks ? *hooks : (struct queue_asset_hooks){0};
    pthread_mutex_unlock(&q->hooks_lock);
}

bool queue_asset_in_use(struct queue *q, const char *name, const char *sha256,
                        char id_out[RECORD_ID_LEN])
{
    bool used = false;
    pthread_mutex_lock(&q->lock);
    for (size_t i = 0; i < q->live.count && !used; i++) {
        const struct job *j = q->live.items[i];
        if (job_status_finished(j->status) || !job_spec_names_asset(&j->spec))
            continue;
        const struct ibl_spec *env = &j->spec.look.ibl;
        bool named_env = env->enabled && env->environment == IBL_ENV_ASSET;
        used = (name && strcmp(j->spec.scene.asset, name) == 0) ||
               (sha256 && strcmp(j->spec.scene.asset_sha256, sha256) == 0) ||
               (named_env && name && strcmp(env->env_asset, name) == 0) ||
               (named_env && sha256 && strcmp(env->env_sha256, sha256) == 0);
        if (used)
            snprintf(id_out, RECORD_ID_LEN, "%s", j->id);
    }
    pthread_mutex_unlock(&q->lock);
    return used;
}
