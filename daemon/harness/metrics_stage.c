/* pthread_setname_np. */
#define _GNU_SOURCE
#include "daemon/harness/metrics_stage.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/clock.h"
#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/log.h"
#include "daemon/quality/metrics.h"
#include "common/png_io.h"
#include "daemon/jobs/deadline.h"
#include "daemon/status/render_state.h"
#include "daemon/status/telemetry.h"
#include "common/result_keys.h"

struct task {
    struct job *job;
    json_t *result;
    struct task *next;
};

struct metrics_worker {
    struct queue *queue;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    pthread_cond_t idle; /* signalled when a task has ended */
    struct task *head, *tail;
    bool busy; /* a task is running: out of the list, not yet finished */
    bool stopping;
};

/* The metric loops ask between tiles: a DELETE (or SIGTERM) sets the job's
 * cancel flag, and the job's timeout_s may run out. */
static bool cancel_requested(void *ctx)
{
    const struct job *job = ctx;
    render_progress(); /* a tile scored: the render thread waits on this (/healthz) */
    return atomic_load(&job->cancel) || job_timed_out(job);
}

/* Fills capture's metrics and the names of its reference and maps; updates the job-wide summary. */
static bool score_capture(struct job *job, json_t *capture, json_t *summary, char *err,
                          size_t errlen)
{
    const struct metrics_stop stop = {cancel_requested, job};
    int frame = (int)json_integer_value(json_object_get(capture, "frame"));
    char test_path[PATH_MAX + JOB_IMAGE_NAME_MAX], ref_path[PATH_MAX + JOB_IMAGE_NAME_MAX],
        ssim_path[PATH_MAX + JOB_IMAGE_NAME_MAX], flip_path[PATH_MAX + JOB_IMAGE_NAME_MAX];
    job_image_path(job->dir, JOB_IMAGE_FRAME, frame, test_path, sizeof(test_path));
    job_image_path(job->dir, JOB_IMAGE_REFERENCE, frame, ref_path, sizeof(ref_path));
    job_image_path(job->dir, JOB_IMAGE_SSIM, frame, ssim_path, sizeof(ssim_path));
    job_image_path(job->dir, JOB_IMAGE_FLIP, frame, flip_path, sizeof(flip_path));
    struct image ref = {0}, test = {0};
    bool ok = png_read_rgb(ref_path, &ref, err, errlen) &&
              png_read_rgb(test_path, &test, err, errlen);
    const struct metrics_options *o = &job->spec.metrics;
    json_t *m = ok ? metrics_compare(&ref, &test, o, (o->which & METRIC_SSIM) ? ssim_path : NULL,
                                     (o->which & METRIC_FLIP) ? flip_path : NULL, &stop, err,
                                     errlen)
                   : NULL;
    image_finish(&ref);
    image_finish(&test);
    if (!m)
        return false;
    json_object_set_new(capture, "metrics", m);
    /* File names only: the API layer turns them into URLs (api/links.c). */
    json_object_set_new(capture, job_image_kind(JOB_IMAGE_REFERENCE)->file_key,
                        json_string(strrchr(ref_path, '/') + 1));
    if (o->which & METRIC_SSIM)
        json_object_set_new(capture, job_image_kind(JOB_IMAGE_SSIM)->file_key,
                            json_string(strrchr(ssim_path, '/') + 1));
    if (o->which & METRIC_FLIP)
        json_object_set_new(capture, job_image_kind(JOB_IMAGE_FLIP)->file_key,
                            json_string(strrchr(flip_path, '/') + 1));

    /* Worst cases over the captures, and which frame they came from. */
    json_t *ssim = json_object_get(m, "ssim");
    json_t *worst = json_object_get(summary, RK_WORST_SSIM);
    if (ssim && (!worst || json_real_value(ssim) < json_real_value(json_object_get(worst, "value"))))
        json_object_set_new(summary, RK_WORST_SSIM,
                            json_pack("{s:f, s:i}", "value", json_real_value(ssim), "frame", frame));
    json_t *smin = json_object_get(m, "ssim_min");
    worst = json_object_get(summary, RK_WORST_SSIM_MIN);
    if (smin && (!worst || json_real_value(json_object_get(smin, "value")) <
                               json_real_value(json_object_get(worst, "value")))) {
        json_t *w = json_deep_copy(smin);
        json_object_set_new(w, "frame", json_integer(frame));
        json_object_set_new(summary, RK_WORST_SSIM_MIN, w);
    }
    json_t *flip = json_object_get(m, "flip");
    worst = json_object_get(summary, RK_WORST_FLIP);
    double fmean = flip ? json_real_value(json_object_get(flip, "mean")) : 0;
    if (flip && (!worst || fmean > json_real_value(json_object_get(worst, "mean"))))
        json_object_set_new(summary, RK_WORST_FLIP,
                            json_pack("{s:f, s:f, s:i}", "mean", fmean, "max",
                                      json_real_value(json_object_get(flip, "max")), "frame", frame));
    json_t *pdiff = json_object_get(m, "pdiff");
    if (pdiff && !json_is_true(json_object_get(pdiff, "pass")))
        json_array_append_new(json_object_get(summary, RK_PDIFF_FAILED_FRAMES), json_integer(frame));
    /* temporal.frames: the capture's run of frames, measured on the render
     * thread (temporal.c); the worst run is the sweeps' flicker_max. */
    json_t *flicker = json_object_get(json_object_get(capture, RK_TEMPORAL), "flicker");
    worst = json_object_get(summary, RK_WORST_FLICKER);
    if (json_is_number(flicker) &&
        (!worst || json_number_value(flicker) > json_number_value(json_object_get(worst, "value"))))
        json_object_set_new(summary, RK_WORST_FLICKER,
                            json_pack("{s:f, s:i}", "value", json_number_value(flicker), "frame",
                                      frame));
    json_t *psnr = json_object_get(m, "psnr");
    json_t *overall = psnr ? json_object_get(psnr, "overall") : NULL;
    worst = json_object_get(summary, "worst_psnr");
    if (overall && json_is_real(overall) &&
        (!worst || json_is_null(json_object_get(worst, "value")) ||
         json_real_value(overall) < json_real_value(json_object_get(worst, "value"))))
        json_object_set_new(summary, "worst_psnr",
                            json_pack("{s:f, s:i}", "value", json_real_value(overall), "frame", frame));
    return true;
}

static void run_task(struct metrics_worker *w, struct task *t)
{
    struct job *job = t->job;
    char err[512] = "";
    double t0 = clock_mono_s();
    json_t *summary = json_pack("{s:s, s:i, s:i, s:[]}", "reference", job->spec.reference,
                                "reference_supersample", job->spec.reference_supersample,
                                "captures_compared", 0, RK_PDIFF_FAILED_FRAMES);
    json_t *captures = json_object_get(t->result, RK_CAPTURES);
    size_t i;
    json_t *capture;
    bool ok = true, cancelled = false, timed_out = false;
    json_array_foreach(captures, i, capture) {
        if (cancel_requested(job) || !(ok = score_capture(job, capture, summary, err, sizeof(err)))) {
            cancelled = atomic_load(&job->cancel);
            timed_out = !cancelled && job_timed_out(job);
            ok = false;
            break;
        }
        json_object_set_new(summary, "captures_compared", json_integer((json_int_t)i + 1));
    }
    double t1 = clock_mono_s();
    telemetry_metrics(t1 - t0,
                      (unsigned)json_integer_value(json_object_get(summary, "captures_compared")));
    if (ok) {
        json_t *failed = json_object_get(summary, RK_PDIFF_FAILED_FRAMES);
        json_object_set_new(summary, RK_PDIFF_FAILED_CAPTURES,
                            json_integer((json_int_t)json_array_size(failed)));
        json_object_set_new(summary, "metrics_s", json_real(t1 - t0));
        json_object_set_new(t->result, RK_QUALITY, summary);
        summary = NULL;
        char path[PATH_MAX + 16];
        job_file_path(job->dir, JOB_FILE_RESULT, path, sizeof(path));
        if (!fs_write_json_atomic(path, t->result)) {
            ok = false;
            snprintf(err, sizeof(err), "cannot write %.400s: %s", path, strerror(errno));
        }
    }
    json_decref(summary);
    if (ok) {
        LOG(LOG_INFO, "job %s done: metrics for %zu captures", job->id, json_array_size(captures));
        queue_finish(w->queue, job, JOB_DONE, NULL, t->result);
    } else if (timed_out) {
        char msg[200];
        job_timeout_message(job, "metrics", "", msg, sizeof(msg));
        LOG(LOG_WARN, "job %s failed: %s", job->id, msg);
        queue_finish(w->queue, job, JOB_FAILED, msg, NULL);
        json_decref(t->result);
    } else if (cancelled) {
        LOG(LOG_INFO, "job %s cancelled in the metrics phase (%zu of %zu captures scored)", job->id,
            i, json_array_size(captures));
        char msg[160];
        snprintf(msg, sizeof(msg), "cancelled in the metrics phase, after %zu of %zu captures",
                 i, json_array_size(captures));
        queue_finish(w->queue, job, JOB_CANCELLED, msg, NULL);
        json_decref(t->result);
    } else {
        LOG(LOG_WARN, "job %s failed in metrics: %s", job->id, err);
        char msg[600];
        snprintf(msg, sizeof(msg), "metrics: %s", err);
        queue_finish(w->queue, job, JOB_FAILED, msg, NULL);
        json_decref(t->result);
    }
}

static void *worker_main(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-metrics"); /* named in crash reports, top, gdb */
    struct metrics_worker *w = arg;
    pthread_mutex_lock(&w->lock);
    for (;;) {
        while (!w->head && !w->stopping)
            pthread_cond_wait(&w->wake, &w->lock);
        struct task *t = w->head;
        if (!t)
            break; /* stopping, and nothing left */
        w->head = t->next;
        if (!w->head)
            w->tail = NULL;
        w->busy = true;
        pthread_mutex_unlock(&w->lock);
        run_task(w, t);
        free(t);
        pthread_mutex_lock(&w->lock);
        w->busy = false;
        pthread_cond_broadcast(&w->idle);
    }
    pthread_mutex_unlock(&w->lock);
    return NULL;
}

struct metrics_worker *metrics_worker_create(struct queue *q)
{
    struct metrics_worker *w = calloc(1, sizeof(*w));
    if (!w)
        return NULL;
    w->queue = q;
    pthread_mutex_init(&w->lock, NULL);
    pthread_cond_init(&w->wake, NULL);
    pthread_cond_init(&w->idle, NULL);
    if (pthread_create(&w->thread, NULL, worker_main, w) != 0) {
        pthread_cond_destroy(&w->idle);
        pthread_cond_destroy(&w->wake);
        pthread_mutex_destroy(&w->lock);
        free(w);
        return NULL;
    }
    return w;
}

void metrics_worker_destroy(struct metrics_worker *w)
{
    if (!w)
        return;
    pthread_mutex_lock(&w->lock);
    w->stopping = true;
    pthread_cond_broadcast(&w->wake);
    pthread_mutex_unlock(&w->lock);
    pthread_join(w->thread, NULL);
    pthread_cond_destroy(&w->idle);
    pthread_cond_destroy(&w->wake);
    pthread_mutex_destroy(&w->lock);
    free(w);
}

void metrics_worker_submit(struct metrics_worker *w, struct job *job, json_t *result)
{
    struct task *t = calloc(1, sizeof(*t));
    if (!t) {
        queue_finish(w->queue, job, JOB_FAILED, "metrics: out of memory", NULL);
        json_decref(result);
        return;
    }
    t->job = job;
    t->result = result;
    pthread_mutex_lock(&w->lock);
    if (w->tail)
        w->tail->next = t;
    else
        w->head = t;
    w->tail = t;
    pthread_cond_signal(&w->wake);
    pthread_mutex_unlock(&w->lock);
}

void metrics_worker_wait_idle(struct metrics_worker *w)
{
    pthread_mutex_lock(&w->lock);
    while (w->head || w->busy)
        pthread_cond_wait(&w->idle, &w->lock);
    pthread_mutex_unlock(&w->lock);
}
