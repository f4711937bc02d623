#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/queue.h"

#include "common/fsutil.h"
#include "common/clock.h"
#include "common/log.h"

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
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct job **jobs;
    size_t count, cap;
    int queued, max_queued;
    unsigned serial;
    bool stopping;
    int keep_jobs;
    double keep_days;
    char state_dir[PATH_MAX];
    void (*listener)(void *ctx);
    void *listener_ctx;
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

static json_t *job_json_locked(const struct job *job, bool full);
static void persist_locked(const struct job *job);
static void apply_retention(struct queue *q);

struct queue *queue_create(const char *state_dir, int max_queued)
{
    struct queue *q = calloc(1, sizeof(*q));
    if (!q)
        return NULL;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->changed, NULL);
    q->max_queued = max_queued;
    if (state_dir)
        snprintf(q->state_dir, sizeof(q->state_dir), "%s", state_dir);
    return q;
}

void queue_destroy(struct queue *q)
{
    if (!q)
        return;
    for (size_t i = 0; i < q->count; i++) {
        json_decref(q->jobs[i]->result);
        free(q->jobs[i]);
    }
    free(q->jobs);
    pthread_cond_destroy(&q->changed);
    pthread_mutex_destroy(&q->lock);
    free(q);
}

int queue_max_queued(const struct queue *q) { return q->max_queued; }

static struct job *find_locked(struct queue *q, const char *id)
{
    for (size_t i = 0; i < q->count; i++)
        if (strcmp(q->jobs[i]->id, id) == 0)
            return q->jobs[i];
    return NULL;
}

enum queue_submit_result queue_submit(struct queue *q, const struct job_spec *spec,
                                      const char *dir_override, char id_out[24])
{
    enum queue_submit_result res = QUEUE_OK;
    pthread_mutex_lock(&q->lock);
    if (q->stopping) {
        res = QUEUE_STOPPING;
        goto out;
    }
    if (q->queued >= q->max_queued) {
        res = QUEUE_FULL;
        goto out;
    }
    if (q->count == q->cap) {
        size_t cap = q->cap ? q->cap * 2 : 64;
        struct job **jobs = realloc(q->jobs, cap * sizeof(*jobs));
        if (!jobs) {
            res = QUEUE_IO_ERROR;
            goto out;
        }
        q->jobs = jobs;
        q->cap = cap;
    }
    struct job *job = calloc(1, sizeof(*job));
    if (!job) {
        res = QUEUE_IO_ERROR;
        goto out;
    }
    /* Time-ordered ids: they sort by submission and stay unique across restarts. */
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    char stamp[16];
    strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &tm);
    /* A fresh directory per job: an id that is taken (after a restart in the
     * same second) just moves on to the next serial number. */
    bool made = false;
    for (int attempt = 0; attempt < 10000 && !made; attempt++) {
        snprintf(job->id, sizeof(job->id), "%.15s-%04u", stamp, ++q->serial % 10000u);
        if (dir_override) {
            snprintf(job->dir, sizeof(job->dir), "%s", dir_override);
            made = fs_mkdir_p(job->dir);
            break;
        }
        snprintf(job->dir, sizeof(job->dir), "%.*s/jobs/%s",
                 (int)(sizeof(job->dir) - sizeof(job->id) - 8), q->state_dir, job->id);
        char parent[PATH_MAX];
        snprintf(parent, sizeof(parent), "%.*s/jobs", (int)(sizeof(parent) - 8), q->state_dir);
        if (!fs_mkdir_p(parent))
            break;
        made = mkdir(job->dir, 0755) == 0;
        if (!made && errno != EEXIST)
            break;
    }
    if (!made) {
        free(job);
        res = QUEUE_IO_ERROR;
        goto out;
    }
    job->spec = *spec;
    job->status = JOB_QUEUED;
    job->frames_total = spec->frames * job_spec_runs(spec);
    job->created = clock_unix_s();
    atomic_init(&job->cancel, false);
    q->jobs[q->count++] = job;
    q->queued++;
    persist_locked(job);
    snprintf(id_out, 24, "%s", job->id);
    pthread_cond_broadcast(&q->changed);
out:
    pthread_mutex_unlock(&q->lock);
    return res;
}

struct job *queue_next(struct queue *q)
{
    struct job *job = NULL;
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
        persist_locked(job);
        pthread_cond_broadcast(&q->changed);
    }
    pthread_mutex_unlock(&q->lock);
    return job;
}

void queue_progress(struct queue *q, struct job *job, int frames_done)
{
    pthread_mutex_lock(&q->lock);
    job->frames_done = frames_done;
    pthread_mutex_unlock(&q->lock);
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
    pthread_mutex_lock(&q->lock);
    job->status = status;
    job->finished = clock_unix_s();
    if (error)
        snprintf(job->error, sizeof(job->error), "%s", error);
    json_decref(job->result);
    job->result = result;
    persist_locked(job);
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
    apply_retention(q);
}

void queue_stop(struct queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->stopping = true;
    /* A running job stops at its next frame rather than holding up the exit. */
    for (size_t i = 0; i < q->count; i++)
        if (q->jobs[i]->status == JOB_RUNNING)
            atomic_store(&q->jobs[i]->cancel, true);
    pthread_cond_broadcast(&q->changed);
    NOTIFY_LISTENER(q);
    pthread_mutex_unlock(&q->lock);
}

enum queue_cancel_result queue_cancel(struct queue *q, const char *id)
{
    enum queue_cancel_result res = CANCEL_NOT_FOUND;
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
        persist_locked(job);
        res = CANCEL_DONE;
        pthread_cond_broadcast(&q->changed);
        NOTIFY_LISTENER(q);
        break;
    case JOB_RUNNING:
        atomic_store(&job->cancel, true);
        res = CANCEL_REQUESTED;
        break;
    default:
        res = CANCEL_FINISHED;
    }
out:
    pthread_mutex_unlock(&q->lock);
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

static json_t *job_json_locked(const struct job *job, bool full)
{
    char url[64];
    snprintf(url, sizeof(url), "/v1/jobs/%s", job->id);
    json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:{s:i, s:i}, s:o, s:o, s:o}",
                          "id", job->id, "url", url, "status", job_status_name(job->status),
                          "technique", job->spec.technique, "progress", "frames_done",
                          job->frames_done, "frames_total", job->frames_total, "created",
                          iso_time(job->created), "started", iso_time(job->started),
                          "finished", iso_time(job->finished));
    if (job->status == JOB_RUNNING && job->phase)
        json_object_set_new(o, "phase", json_string(job->phase));
    if (job->error[0])
        json_object_set_new(o, "error", json_string(job->error));
    if (full) {
        json_object_set_new(o, "spec", job_spec_to_json(&job->spec));
        if (job->result)
            json_object_set_new(o, "result", json_deep_copy(job->result));
    }
    return o;
}

static bool finished(const struct job *job)
{
    return job->status != JOB_QUEUED && job->status != JOB_RUNNING;
}

/* job.json: the job's state, written whenever it changes (the result lives
 * in result.json beside it, written before the job is marked done). */
static void persist_locked(const struct job *job)
{
    json_t *o = job_json_locked(job, false);
    json_object_set_new(o, "spec", job_spec_to_json(&job->spec));
    json_object_set_new(o, "times_unix",
                        json_pack("[f, f, f]", job->created, job->started, job->finished));
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/job.json", job->dir);
    if (!fs_write_json_atomic(path, o))
        LOG(LOG_ERROR, "job %s: cannot write %s", job->id, path);
    json_decref(o);
}

static enum job_status status_from_name(const char *name)
{
    for (int s = JOB_QUEUED; s <= JOB_INTERRUPTED; s++)
        if (name && strcmp(name, job_status_name((enum job_status)s)) == 0)
            return (enum job_status)s;
    return JOB_INTERRUPTED;
}

static int by_id(const void *a, const void *b)
{
    return strcmp((*(struct job *const *)a)->id, (*(struct job *const *)b)->id);
}

static bool load_job(struct queue *q, const char *id, const char *const *techniques)
{
    char dir[PATH_MAX], path[PATH_MAX + 16];
    if (strlen(id) >= sizeof(((struct job *)0)->id))
        return false;
    snprintf(dir, sizeof(dir), "%.*s/jobs/%.23s", (int)(sizeof(dir) - 40), q->state_dir, id);
    snprintf(path, sizeof(path), "%s/job.json", dir);
    json_error_t jerr;
    json_t *o = json_load_file(path, 0, &jerr);
    if (!o)
        return false;
    struct job_spec spec;
    struct job_error err;
    struct job *job = NULL;
    const char *jid = json_string_value(json_object_get(o, "id"));
    if (!jid || strcmp(jid, id) != 0 || strlen(id) >= sizeof(job->id) ||
        !job_spec_parse(json_object_get(o, "spec"), techniques, &spec, &err)) {
        LOG(LOG_WARN, "skipping %s: not a job this daemon can read (%s %s)", path, err.field,
            err.message);
        json_decref(o);
        return false;
    }
    if (q->count == q->cap) {
        size_t cap = q->cap ? q->cap * 2 : 64;
        struct job **jobs = realloc(q->jobs, cap * sizeof(*jobs));
        if (!jobs) {
            json_decref(o);
            return false;
        }
        q->jobs = jobs;
        q->cap = cap;
    }
    job = calloc(1, sizeof(*job));
    if (!job) {
        json_decref(o);
        return false;
    }
    snprintf(job->id, sizeof(job->id), "%s", id);
    snprintf(job->dir, sizeof(job->dir), "%s", dir);
    job->spec = spec;
    job->status = status_from_name(json_string_value(json_object_get(o, "status")));
    json_t *progress = json_object_get(o, "progress");
    job->frames_total = spec.frames * job_spec_runs(&spec);
    job->frames_done = (int)json_integer_value(json_object_get(progress, "frames_done"));
    json_t *times = json_object_get(o, "times_unix");
    job->created = json_real_value(json_array_get(times, 0));
    job->started = json_real_value(json_array_get(times, 1));
    job->finished = json_real_value(json_array_get(times, 2));
    const char *error = json_string_value(json_object_get(o, "error"));
    if (error)
        snprintf(job->error, sizeof(job->error), "%s", error);
    atomic_init(&job->cancel, false);
    json_decref(o);

    bool changed = false;
    if (job->status == JOB_RUNNING) {
        job->status = JOB_INTERRUPTED;
        job->finished = clock_unix_s();
        snprintf(job->error, sizeof(job->error),
                 "interrupted: the daemon stopped (killed or crashed) while this job ran; "
                 "its files may be incomplete, submit it again to measure it");
        changed = true;
    } else if (job->status == JOB_DONE) {
        snprintf(path, sizeof(path), "%s/result.json", dir);
        job->result = json_load_file(path, 0, &jerr);
        if (!job->result) {
            job->status = JOB_FAILED;
            snprintf(job->error, sizeof(job->error), "result.json is missing or damaged: %s",
                     jerr.text);
            changed = true;
        }
    } else if (job->status == JOB_QUEUED) {
        q->queued++;
    }
    if (changed)
        persist_locked(job);
    q->jobs[q->count++] = job;
    return true;
}

int queue_load(struct queue *q, const char *const *techniques, char *err, size_t errlen)
{
    char jobs_dir[PATH_MAX];
    snprintf(jobs_dir, sizeof(jobs_dir), "%.*s/jobs", (int)(sizeof(jobs_dir) - 8), q->state_dir);
    DIR *d = opendir(jobs_dir);
    if (!d) {
        if (errno == ENOENT)
            return 0;
        snprintf(err, errlen, "cannot read %s: %s", jobs_dir, strerror(errno));
        return -1;
    }
    int loaded = 0;
    pthread_mutex_lock(&q->lock);
    struct dirent *e;
    while ((e = readdir(d)))
        if (e->d_name[0] != '.' && load_job(q, e->d_name, techniques))
            loaded++;
    closedir(d);
    qsort(q->jobs, q->count, sizeof(*q->jobs), by_id);
    /* New ids continue after the loaded ones, so that ids keep sorting in
     * submission order even within the second of a restart. */
    for (size_t i = 0; i < q->count; i++) {
        const char *dash = strrchr(q->jobs[i]->id, '-');
        unsigned serial = dash ? (unsigned)strtoul(dash + 1, NULL, 10) : 0;
        if (serial > q->serial)
            q->serial = serial;
    }
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

static int by_time(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Removes a finished job's directory: the files in it, then the directory. */
static void remove_job_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *e;
        char path[PATH_MAX + 300];
        while ((e = readdir(d)))
            if (e->d_name[0] != '.') {
                snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
                unlink(path);
            }
        closedir(d);
    }
    if (rmdir(dir) != 0)
        LOG(LOG_WARN, "retention: cannot remove %s: %s", dir, strerror(errno));
}

static void apply_retention(struct queue *q)
{
    pthread_mutex_lock(&q->lock);
    if (!q->state_dir[0] || (q->keep_jobs <= 0 && q->keep_days <= 0)) {
        pthread_mutex_unlock(&q->lock);
        return;
    }
    size_t finished_count = 0;
    for (size_t i = 0; i < q->count; i++)
        finished_count += finished(q->jobs[i]);
    double cutoff = q->keep_days > 0 ? clock_unix_s() - q->keep_days * 86400.0 : -1.0;
    struct job **victims = calloc(q->count ? q->count : 1, sizeof(*victims));
    size_t nv = 0, kept = 0;
    if (!victims) {
        pthread_mutex_unlock(&q->lock);
        return;
    }
    /* Over the count limit: the jobs that finished earliest go first. The
     * finish time of the newest one to go is the count cutoff. */
    size_t excess = q->keep_jobs > 0 && finished_count > (size_t)q->keep_jobs
                        ? finished_count - (size_t)q->keep_jobs
                        : 0;
    double count_cutoff = -1.0;
    if (excess) {
        double *times = malloc(finished_count * sizeof(double));
        size_t nt = 0;
        for (size_t i = 0; times && i < q->count; i++)
            if (finished(q->jobs[i]))
                times[nt++] = q->jobs[i]->finished;
        if (times) {
            qsort(times, nt, sizeof(double), by_time);
            count_cutoff = times[excess - 1];
        }
        free(times);
    }
    for (size_t i = 0; i < q->count; i++) {
        struct job *job = q->jobs[i];
        bool old = finished(job) && ((job->finished <= count_cutoff && nv < excess) ||
                                     (cutoff > 0 && job->finished < cutoff));
        if (old)
            victims[nv++] = job;
        else
            q->jobs[kept++] = job;
    }
    q->count = kept;
    pthread_mutex_unlock(&q->lock);
    for (size_t i = 0; i < nv; i++) {
        LOG(LOG_INFO, "retention: removing job %s", victims[i]->id);
        remove_job_dir(victims[i]->dir);
        json_decref(victims[i]->result);
        free(victims[i]);
    }
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
