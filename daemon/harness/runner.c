/* pthread_setname_np. */
#define _GNU_SOURCE
#include "daemon/harness/runner.h"
#include "daemon/jobs/fidelity.h"
#include "daemon/harness/fidelity_render.h"

#include <epoxy/gl.h>
#include <errno.h>
#include <malloc.h>
#include <pthread.h>
#include <time.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/clock.h"
#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/log.h"
#include "common/result_keys.h"
#include "common/stats.h"
#include "daemon/gpu/egl.h"
#include "daemon/gpu/glutil.h"
#include "daemon/gpu/targets.h"
#include "daemon/jobs/deadline.h"
#include "daemon/harness/measure.h"
#include "daemon/harness/metrics_stage.h"
#include "daemon/harness/outputs.h"
#include "daemon/harness/reference.h"
#include "daemon/status/render_state.h"
#include "daemon/harness/run.h"
#include "daemon/status/telemetry.h"
#include "daemon/harness/temporal.h"
#include "daemon/service.h"

/* After a job, a resident set this far above the idle one is given back
 * (give_back_memory); the target pool is emptied when it holds more than
 * RUNNER_KEEP_TARGETS_BYTES. */
#define RUNNER_TRIM_ABOVE_BYTES (64.0 * 1024 * 1024)
#define RUNNER_KEEP_TARGETS_BYTES (256.0 * 1024 * 1024)

struct runner {
    struct queue *queue;
    struct metrics_worker *metrics;
    struct device_spec device;
    bool gl_debug;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t ready_cond;
    int ready; /* 0 starting, 1 up, -1 failed, 2 its loop has ended */
    atomic_bool alive;
    char error[512];
    /* The render thread's own; device_json is immutable once ready. */
    struct harness_gl gl;
    double idle_rss; /* the resident set once the context was up */
};

/* The fidelity worker (daemon/jobs/fidelity.h), set once before
 * runner_create; NULL: fidelity jobs fail saying so. */
static struct fidelity *fidelity_worker;

void runner_use_fidelity(struct fidelity *f)
{
    fidelity_worker = f;
}

static const char *gl_str(GLenum name)
{
    const char *s = (const char *)glGetString(name);
    return s ? s : "";
}

static json_t *collect_device(struct egl_context *egl, const struct gpu_caps *caps)
{
    json_t *d = json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:i, s:i}",
                          "egl_platform", egl_context_platform(egl), "egl_device",
                          egl_context_device(egl), "egl_vendor", egl_context_egl_vendor(egl),
                          "egl_version", egl_context_egl_version(egl), "gl_vendor",
                          gl_str(GL_VENDOR), "gl_renderer", gl_str(GL_RENDERER), "gl_version",
                          gl_str(GL_VERSION), "glsl_version", gl_str(GL_SHADING_LANGUAGE_VERSION),
                          "max_texture_size", caps->max_texture_size, "max_renderbuffer_size",
                          caps->max_renderbuffer_size);
    json_object_set_new(d, "caps", gpu_caps_json(caps));
    egl_context_describe(egl, d);
    struct gpu_memory_sample memory;
    gpu_memory_sample_gl(&memory);
    json_object_set_new(d, "gpu_memory_at_start",
                        gpu_memory_sample_json(&memory, json_is_true(json_object_get(d, "software"))));
    return d;
}

/* One measured run: set up, then the timed loop. */
static bool prepare_and_measure(struct harness_run *run, bool capture, int run_index,
                                enum job_status *status)
{
    render_state_phase("setup");
    /* The costs beside the frame times (glutil.h, gpu_memory.h): the
     * programs built in the set-up and warm-up, and GPU memory around them. */
    gpu_memory_sample_gl(&run->gpu_memory[0]);
    gl_build_log_begin(&run->builds);
    bool prepared = run_prepare(run, capture), measured = false;
    if (prepared) {
        gpu_memory_sample_gl(&run->gpu_memory[1]);
        render_state_phase("rendering");
        measured = measure_run(run, run_index, status);
        gpu_memory_sample_gl(&run->gpu_memory[2]);
    }
    gl_build_timed_region(false);
    gl_build_log_end();
    if (prepared)
        return measured;
    /* Told to stop while the look's set-up (image-based lighting's probes)
     * ran: say why, as the timed loop would. */
    bool cancelled = atomic_load(&run->job->cancel);
    if (cancelled || job_timed_out(run->job)) {
        char what[512];
        snprintf(what, sizeof(what), "%.500s", run->err);
        if (cancelled) {
            *status = JOB_CANCELLED;
            snprintf(run->err, sizeof(run->err), "cancelled during the set-up of run %d (%s)",
                     run_index + 1, what);
        } else {
            char detail[540];
            snprintf(detail, sizeof(detail), " (%s)", what);
            job_timeout_message(run->job, "set-up", detail, run->err, sizeof(run->err));
        }
    }
    return false;
}

static json_t *run_summary(int index, double wall_s, json_t *frame, json_t *gpu, json_t *cpu)
{
    return json_pack("{s:i, s:f, s:o, s:o, s:o}", "run", index, RK_WALL_S, wall_s, RK_FRAME_MS,
                     frame, RK_GPU_MS, gpu, RK_CPU_MS, cpu);
}

static json_t *across_runs(const double *medians, size_t n)
{
    struct stats s;
    stats_compute(medians, n, &s);
    double lo, hi;
    json_t *ci = stats_mean_ci95(medians, n, &lo, &hi) ? json_pack("[f, f]", lo, hi) : json_null();
    return json_pack("{s:f, s:f, s:f, s:f, s:f, s:o}", RK_MEAN, s.mean, RK_MEDIAN, s.median,
                     RK_STDDEV, s.stddev, RK_MIN, s.min, RK_MAX, s.max, RK_CI95, ci);
}

/* Runs 2..N of a repeated job, each with the scene rebuilt; with automatic
 * repeats, stops as soon as the frame-time interval has tightened. Adds
 * result.runs and result.repeat, and rewrites result.json. */
static bool repeat_runs(struct runner *r, struct harness_run *first, json_t *result,
                        enum job_status *status)
{
    const struct job_spec *spec = first->spec;
    int planned = spec->repeat, n = spec->frames, w0 = spec->warmup_frames;
    double *med = calloc((size_t)planned * 3, sizeof(double)); /* frame, gpu, cpu */
    double *gpu = malloc((size_t)n * sizeof(double));
    json_t *runs = json_array();
    static const char *const series[3] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    bool ok = med && gpu;
    if (!ok)
        snprintf(first->err, sizeof(first->err), "out of memory for repeats");
    for (int k = 0; ok && k < 3; k++)
        med[k * planned] = json_real_value(json_object_get(json_object_get(result, series[k]), RK_MEDIAN));
    if (ok)
        json_array_append_new(runs, run_summary(1, json_real_value(json_object_get(result, RK_WALL_S)),
                                                json_deep_copy(json_object_get(result, RK_FRAME_MS)),
                                                json_deep_copy(json_object_get(result, RK_GPU_MS)),
                                                json_deep_copy(json_object_get(result, RK_CPU_MS))));
    if (ok)
        json_object_set_new(json_array_get(runs, 0), RK_INTERFERENCE,
                            json_deep_copy(json_object_get(result, RK_INTERFERENCE)));
    if (ok)
        json_object_set_new(json_array_get(runs, 0), "compile_ms",
                            json_real(first->builds.compile_ms + first->builds.link_ms));
    int done = 1;
    while (ok && done < planned && !(spec->repeat_auto && stats_is_stable(med, (size_t)done, 0.025))) {
        struct harness_run extra = {.gl = &r->gl, .queue = r->queue, .job = first->job, .spec = spec,
                            .tech = first->tech, .rule = first->rule};
        ok = prepare_and_measure(&extra, false, done, status);
        if (ok) {
            for (int i = 0; i < n; i++)
                gpu[i] = gpu_timer_ms(extra.timer, w0 + i, -1);
            json_t *f = outputs_stats_json(extra.frame_ms, (size_t)n),
                   *g = outputs_stats_json(gpu, (size_t)n),
                   *c = outputs_stats_json(extra.cpu_ms, (size_t)n);
            med[done] = json_real_value(json_object_get(f, RK_MEDIAN));
            med[planned + done] = json_real_value(json_object_get(g, RK_MEDIAN));
            med[2 * planned + done] = json_real_value(json_object_get(c, RK_MEDIAN));
            json_array_append_new(runs, run_summary(done + 1, extra.wall_s, f, g, c));
            json_object_set_new(json_array_get(runs, done), RK_INTERFERENCE,
                                interference_json(&extra.interference[0], &extra.interference[1]));
            json_object_set_new(json_array_get(runs, done), "compile_ms",
                                json_real(extra.builds.compile_ms + extra.builds.link_ms));
            done++;
        } else {
            char why[900];
            snprintf(why, sizeof(why), "%.890s", extra.err);
            snprintf(first->err, sizeof(first->err), "run %d: %s", done + 1, why);
        }
        run_finish(&extra);
    }
    if (ok) {
        bool stable = stats_is_stable(med, (size_t)done, 0.025);
        json_t *rep = json_pack("{s:i, s:i, s:b, s:b, s:s, s:s}", RK_RUNS, done, "planned", planned,
                                "auto", spec->repeat_auto, RK_STABLE, stable, "rule_series",
                                RK_FRAME_MS, "rule",
                                "stable when the 95% confidence interval (Student's t) of the mean "
                                "of per-run median frame_ms is within 2.5% of it, from 3 runs");
        for (int k = 0; k < 3; k++)
            json_object_set_new(rep, series[k], across_runs(med + k * planned, (size_t)done));
        json_object_set_new(result, RK_REPEAT, rep);
        json_object_set_new(result, RK_RUNS, runs);
        runs = NULL;
        if (first->rule->mode == GPU_BUDGET_SLICED)
            outputs_mark_sliced(result);
        queue_progress(r->queue, first->job, planned * n);
        char path[PATH_MAX + 16];
        job_file_path(first->job->dir, JOB_FILE_RESULT, path, sizeof(path));
        if (!fs_write_json_atomic(path, result)) {
            snprintf(first->err, sizeof(first->err), "cannot write %.900s: %s", path, strerror(errno));
            ok = false;
        }
    }
    json_decref(runs);
    free(med);
    free(gpu);
    return ok;
}

/* A job that ended early (cancelled, stopped, failed) may leave work on
 * the GPU: the frames in flight of a whole frame, a tile of a sliced one.
 * It finishes here, before the job's objects go and the next job starts;
 * /healthz shows the thread draining that job, not rendering it, and the
 * wait is bounded by the frame bound (measure.c), well within the stall
 * bound. */
static void drain(const char *id, enum job_status status)
{
    render_state_phase(status == JOB_CANCELLED ? RENDER_PHASE_DRAINING_CANCELLED
                                               : RENDER_PHASE_DRAINING_FAILED);
    double t0 = clock_mono_s();
    GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    glClientWaitSync(fence, GL_SYNC_FLUSH_COMMANDS_BIT, UINT64_MAX);
    glDeleteSync(fence);
    double took = clock_mono_s() - t0;
    LOG(took > 0.5 ? LOG_INFO : LOG_DEBUG, "job %s: the GPU finished its last work %.2f s after "
        "it ended", id, took);
}

static void run_job(struct runner *r, struct job *job)
{
    /* Decided in the first run, followed by the others (measure.c). */
    struct run_timing_rule rule = {0};
    struct harness_run run = {.gl = &r->gl, .queue = r->queue, .job = job, .spec = &job->spec,
                              .rule = &rule};
    const struct job_spec *spec = &job->spec;
    enum job_status status = JOB_FAILED;
    json_t *result = NULL, *fidelity_view = NULL;

    LOG(LOG_INFO, "job %s: %s, %d+%d frames at %dx%d, %d run(s)", job->id, spec->technique,
        spec->warmup_frames, spec->frames, spec->scene.width, spec->scene.height,
        job_spec_runs(spec));
    service_status("running job %s (%s, %d frames at %dx%d)", job->id, spec->technique,
                   spec->frames, spec->scene.width, spec->scene.height);
    gl_error_take("previous job", run.err, sizeof(run.err));
    run.err[0] = '\0';
    run.tech = technique_find(spec->technique);
    if (!run.tech) {
        snprintf(run.err, sizeof(run.err), "technique %s is not available", spec->technique);
        goto done;
    }
    if (!prepare_and_measure(&run, true, 0, &status))
        goto done;
    render_state_phase("writing results");
    result = outputs_write(&run);
    /* The first run's technique is done with: free it before more runs or the
     * reference claim the device's memory. */
    run.tech->destroy(run.state);
    run.state = NULL;
    if (result && spec->repeat > 1 && !repeat_runs(r, &run, result, &status)) {
        json_decref(result);
        result = NULL;
    }
    if (result && spec->reference[0]) {
        queue_set_phase(r->queue, job, "reference");
        render_state_phase("reference");
        if (!reference_render(&run, &status)) {
            json_decref(result);
            result = NULL;
        }
    }
    if (result && spec->temporal_frames) {
        queue_set_phase(r->queue, job, "temporal");
        render_state_phase("temporal");
        if (!temporal_measure(&run, result, &status)) {
            json_decref(result);
            result = NULL;
        }
    }
    if (result && spec->fidelity.enabled) {
        queue_set_phase(r->queue, job, "fidelity");
        render_state_phase("fidelity");
        if (!(fidelity_view = fidelity_render(&run, &status))) {
            json_decref(result);
            result = NULL;
        }
    }
    if (result)
        status = JOB_DONE;
done:;
    char id[RECORD_ID_LEN];
    snprintf(id, sizeof(id), "%s", job->id);
    if (status != JOB_DONE) {
        /* The job ends now; what the GPU still has of it (a tile or two of
         * an abandoned frame) drains in the tear-down below, before the
         * next job starts. */
        LOG(LOG_WARN, "job %s %s: %s", id, job_status_name(status), run.err);
        queue_finish(r->queue, job, status, run.err, result);
        drain(id, status);
        run_finish(&run);
    } else {
        LOG(LOG_INFO, "job %s rendered", id);
        run_finish(&run);
        if (spec->fidelity.enabled && !fidelity_worker) {
            json_decref(result);
            json_decref(fidelity_view);
            queue_finish(r->queue, job, JOB_FAILED, "fidelity: this daemon runs no fidelity "
                         "worker (shadebenchd --once compares nothing)", NULL);
        } else if (spec->fidelity.enabled) {
            /* The Khronos reference and the comparisons, on the fidelity
             * worker; the render thread waits for it before the next job. */
            render_state_phase("fidelity");
            fidelity_submit(fidelity_worker, job, result, fidelity_view);
        } else if (spec->reference[0]) {
            queue_set_phase(r->queue, job, "metrics");
            /* Still this job's until the metrics thread is done with it: the
             * render thread waits for that before the next job. */
            render_state_phase("metrics");
            metrics_worker_submit(r->metrics, job, result);
        } else {
            queue_finish(r->queue, job, status, NULL, result);
        }
    }
    service_status("idle; last job %s %s", id, job_status_name(status));
}

/* Between jobs, outside every timed region: what a large job took goes
 * back to the system. The target pool keeps a size's framebuffers for the
 * next job at that size, so that it allocates nothing; but llvmpipe keeps
 * the framebuffers in the daemon's own memory, and it keeps the last
 * output's colour and depth alive after they are deleted (an 8192x8192 job
 * left 1.89 GB resident until a restart; a 4096x4096 one 440 MB). So once
 * the pool holds more than RUNNER_KEEP_TARGETS_BYTES, the context is made
 * anew, which frees everything the driver held; then malloc_trim returns
 * what the freed buffers left in the heap (main.c's fixed M_TRIM_THRESHOLD
 * and M_MMAP_THRESHOLD, which keep a job's timings independent of the jobs
 * before it, stay as they are). false when no context could be made again
 * (err says why): the render thread then stops. */
static bool give_back_memory(struct runner *r, struct egl_context **egl, char *err, size_t errlen)
{
    double before = telemetry_rss_bytes();
    if (before < r->idle_rss + RUNNER_TRIM_ABOVE_BYTES)
        return true;
    double renew_s = 0;
    bool renew = gpu_targets_bytes(r->gl.targets) > RUNNER_KEEP_TARGETS_BYTES;
    if (!renew) {
        /* The heap first; what it cannot give back is the driver's (an
         * asset's textures, which llvmpipe kept: 100 MiB after a job on
         * four 2048x2048 maps), and goes with the context. */
        malloc_trim(0);
        renew = telemetry_rss_bytes() >= r->idle_rss + RUNNER_TRIM_ABOVE_BYTES;
    }
    if (renew) {
        double t0 = clock_mono_s();
        harness_gl_finish(&r->gl);
        egl_context_destroy(*egl);
        *egl = egl_context_create(&r->device, r->gl_debug, err, errlen);
        if (!*egl || !harness_gl_init(&r->gl, err, errlen))
            return false;
        renew_s = clock_mono_s() - t0;
    }
    malloc_trim(0);
    double after = telemetry_rss_bytes();
    LOG(LOG_INFO, "after the job: %.0f MiB given back (%s), %.0f MiB resident (%.0f when idle)",
        (before - after) / 1048576.0, renew_s > 0 ? "a new GL context" : "the heap trimmed",
        after / 1048576.0, r->idle_rss / 1048576.0);
    if (renew_s > 0)
        LOG(LOG_DEBUG, "the new GL context took %.0f ms", renew_s * 1e3);
    return true;
}

static void *runner_main(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-render"); /* named in crash reports, top, gdb */
    struct runner *r = arg;
    char err[512] = "";
    struct egl_context *egl = egl_context_create(&r->device, r->gl_debug, err, sizeof(err));
    pthread_mutex_lock(&r->lock);
    if (egl && !harness_gl_init(&r->gl, err, sizeof(err))) {
        egl_context_destroy(egl);
        egl = NULL;
    }
    if (egl) {
        r->gl.device_json = collect_device(egl, &r->gl.caps);
        r->idle_rss = telemetry_rss_bytes();
        render_state_end(); /* idle from now */
        r->ready = 1;
        atomic_store(&r->alive, true);
    } else {
        snprintf(r->error, sizeof(r->error), "%s", err);
        r->ready = -1;
    }
    pthread_cond_broadcast(&r->ready_cond);
    pthread_mutex_unlock(&r->lock);
    if (!egl)
        return NULL;
    LOG(LOG_INFO, "GL context on %s (%s): %s, %s", egl_context_device(egl),
        egl_context_platform(egl), gl_str(GL_RENDERER), gl_str(GL_VERSION));

    for (;;) {
        /* The metrics and files of earlier jobs finish before the next job is timed. */
        metrics_worker_wait_idle(r->metrics);
        fidelity_wait_idle(fidelity_worker);
        if (!give_back_memory(r, &egl, err, sizeof(err))) {
            LOG(LOG_ERROR, "the render thread stops: no GL context after a large job: %s", err);
            break;
        }
        render_state_end();
        struct job *job = queue_next(r->queue);
        if (!job)
            break;
        render_state_begin(job->id, "setup");
        double busy_from = clock_mono_s();
        run_job(r, job);
        telemetry_render_busy(clock_mono_s() - busy_from);
    }
    atomic_store(&r->alive, false);
    if (egl)
        harness_gl_finish(&r->gl);
    egl_context_destroy(egl);
    pthread_mutex_lock(&r->lock);
    r->ready = 2;
    pthread_cond_broadcast(&r->ready_cond);
    pthread_mutex_unlock(&r->lock);
    return NULL;
}

struct runner *runner_create(struct queue *q, const struct device_spec *device, bool gl_debug,
                             char *err, size_t errlen)
{
    struct runner *r = calloc(1, sizeof(*r));
    if (!r) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    r->queue = q;
    r->metrics = metrics_worker_create(q);
    if (!r->metrics) {
        snprintf(err, errlen, "cannot start the metrics thread");
        free(r);
        return NULL;
    }
    r->device = *device;
    r->gl_debug = gl_debug;
    /* Tests cut every piece that is drawn in tiles into tiles of a tiny
     * slice, at least four, however cheap (with a job that accepts sliced
     * timing, every piece of its timed frames): the pixels must not change. */
    const char *slice_ms = getenv("SHADEBENCH_SLICE_MS");
    if (slice_ms && atof(slice_ms) > 0)
        gpu_budget_configure(atof(slice_ms) / 1e3, 0.25);
    const char *stall_ms = getenv("SHADEBENCH_DEBUG_STALL_FIRST_FRAME_MS");
    if (stall_ms && atof(stall_ms) > 0)
        gpu_budget_debug_stall(atof(stall_ms) / 1e3);
    atomic_init(&r->alive, false);
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->ready_cond, NULL);
    if (pthread_create(&r->thread, NULL, runner_main, r) != 0) {
        snprintf(err, errlen, "cannot start the render thread");
        metrics_worker_destroy(r->metrics);
        free(r);
        return NULL;
    }
    pthread_mutex_lock(&r->lock);
    while (r->ready == 0)
        pthread_cond_wait(&r->ready_cond, &r->lock);
    pthread_mutex_unlock(&r->lock);
    if (r->ready < 0) {
        snprintf(err, errlen, "%s", r->error);
        pthread_join(r->thread, NULL);
        metrics_worker_destroy(r->metrics);
        free(r);
        return NULL;
    }
    return r;
}

bool runner_stop(struct runner *r, double wait_s)
{
    queue_stop(r->queue);
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_sec += (time_t)wait_s;
    until.tv_nsec += (long)((wait_s - (double)(time_t)wait_s) * 1e9);
    if (until.tv_nsec >= 1000000000L)
        until.tv_sec++, until.tv_nsec -= 1000000000L;
    pthread_mutex_lock(&r->lock);
    while (r->ready != 2 &&
           pthread_cond_timedwait(&r->ready_cond, &r->lock, &until) == 0)
        ;
    bool ended = r->ready == 2;
    pthread_mutex_unlock(&r->lock);
    return ended;
}

void runner_destroy(struct runner *r)
{
    if (!r)
        return;
    queue_stop(r->queue);
    pthread_join(r->thread, NULL);
    /* After the render thread: it is the only one that hands work over. */
    metrics_worker_destroy(r->metrics);
    json_decref(r->gl.device_json);
    pthread_cond_destroy(&r->ready_cond);
    pthread_mutex_destroy(&r->lock);
    free(r);
}

bool runner_alive(struct runner *r) { return atomic_load(&r->alive); }

void runner_state(struct runner *r, struct render_state *out)
{
    render_state_read(out);
    out->alive = runner_alive(r);
}

json_t *runner_device_json(struct runner *r) { return json_incref(r->gl.device_json); }
