#define _POSIX_C_SOURCE 200809L
#include "daemon/queue.h"

#include "daemon/fsutil.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct queue {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct job **jobs;
    size_t count, cap;
    int queued, max_queued;
    unsigned serial;
    bool stopping;
    char state_dir[PATH_MAX];
};

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

const char *job_status_name(enum job_status s)
{
    static const char *const names[] = {"queued", "running", "done", "failed", "cancelled"};
    return names[s];
}

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
    snprintf(job->id, sizeof(job->id), "%.15s-%04u", stamp, ++q->serial % 10000u);
    if (dir_override)
        snprintf(job->dir, sizeof(job->dir), "%s", dir_override);
    else
        snprintf(job->dir, sizeof(job->dir), "%.*s/jobs/%s",
                 (int)(sizeof(job->dir) - sizeof(job->id) - 8), q->state_dir, job->id);
    if (!fs_mkdir_p(job->dir)) {
        free(job);
        res = QUEUE_IO_ERROR;
        goto out;
    }
    job->spec = *spec;
    job->status = JOB_QUEUED;
    job->frames_total = spec->frames;
    job->created = now_s();
    atomic_init(&job->cancel, false);
    q->jobs[q->count++] = job;
    q->queued++;
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
        job->started = now_s();
        q->queued--;
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
    job->finished = now_s();
    if (error)
        snprintf(job->error, sizeof(job->error), "%s", error);
    json_decref(job->result);
    job->result = result;
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
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
        job->finished = now_s();
        snprintf(job->error, sizeof(job->error), "cancelled before it started");
        q->queued--;
        res = CANCEL_DONE;
        pthread_cond_broadcast(&q->changed);
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

json_t *queue_job_json(struct queue *q, const char *id, double wait_s)
{
    json_t *out = NULL;
    struct timespec deadline;
    clock_gettime(CLOCK_REALTIME, &deadline);
    double secs = (double)deadline.tv_sec + deadline.tv_nsec / 1e9 + wait_s;
    deadline.tv_sec = (time_t)secs;
    deadline.tv_nsec = (long)((secs - (double)deadline.tv_sec) * 1e9);
    pthread_mutex_lock(&q->lock);
    struct job *job = find_locked(q, id);
    while (job && wait_s > 0 && !finished(job) && !q->stopping)
        if (pthread_cond_timedwait(&q->changed, &q->lock, &deadline) == ETIMEDOUT)
            break;
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
