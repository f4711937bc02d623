#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/measure.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>

#include "common/clock.h"
#include "daemon/gpu/glutil.h"
#include "daemon/jobs/deadline.h"
#include "daemon/harness/outputs.h"
#include "daemon/status/render_state.h"
#include "daemon/status/telemetry.h"

/* The pass a stopped frame was in, for the message: ", in the X pass". */
static void where(const struct harness_run *run, char *out, size_t cap)
{
    int s = gpu_timer_last_section(run->timer);
    if (s >= 0 && s < run->passes.count)
        snprintf(out, cap, ", in the %s pass", run->passes.names[s]);
    else
        out[0] = '\0';
}

/* A DELETE or a stop sets the job's cancel flag, and the job's timeout_s
 * may run out: between frames, and (through the budget) inside them. */
static bool keep_going(struct harness_run *run, int64_t k, int run_index, enum job_status *status)
{
    char in[96] = "";
    if (gpu_budget_stopped(&run->budget))
        where(run, in, sizeof(in));
    if (atomic_load(&run->job->cancel)) {
        *status = JOB_CANCELLED;
        if (k >= 1)
            snprintf(run->err, sizeof(run->err), "cancelled at frame %" PRId64 " of run %d%s", k,
                     run_index + 1, in);
        else
            snprintf(run->err, sizeof(run->err), "cancelled during warm-up frame %" PRId64
                     " of %d, run %d%s", k + run->spec->warmup_frames, run->spec->warmup_frames,
                     run_index + 1, in);
        return false;
    }
    if (job_timed_out(run->job)) {
        char detail[160];
        snprintf(detail, sizeof(detail), " at %sframe %" PRId64 "%s", k >= 1 ? "" : "warm-up ",
                 k >= 1 ? k : k + run->spec->warmup_frames, in);
        job_timeout_message(run->job, "rendering", detail, run->err, sizeof(run->err));
        return false;
    }
    return !gpu_budget_stopped(&run->budget);
}

/* A job that cannot finish within its timeout_s fails as soon as that is
 * clear, not when the time has run out: once even its fastest frame so far,
 * times the frames left in this run, would take it past the limit (a lower
 * bound: later runs, the reference and the metrics come on top). Only
 * worth it where the time saved is more than a second. */
static bool out_of_time(struct harness_run *run, int seq, double fastest_s)
{
    const struct job *job = run->job;
    int left = run->spec->warmup_frames + run->spec->frames - seq - 1;
    double more = fastest_s * left;
    if (job->spec.timeout_s <= 0 || job->started <= 0 || !isfinite(fastest_s) || more < 1.0)
        return false;
    double ran = clock_unix_s() - job->started;
    if (ran + more <= job->spec.timeout_s)
        return false;
    snprintf(run->err, sizeof(run->err),
             "timeout: the job cannot finish within its timeout_s of %g s: after %.1f s, "
             "%d frames are left and its fastest frame took %.1f ms, so at least %.1f s more; "
             "stopped at frame %d of %d in the rendering phase (fewer frames, a smaller "
             "scene, or a larger timeout_s)",
             job->spec.timeout_s, ran, left, fastest_s * 1e3, more, seq + 1,
             run->spec->warmup_frames + run->spec->frames);
    return true;
}

bool measure_run(struct harness_run *run, int run_index, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    struct gpu_budget *budget = &run->budget;
    int w0 = spec->warmup_frames, n = spec->frames;
    double wall_start = 0, frame_begin = 0, fastest_s = INFINITY;
    run->capture_s = 0;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    for (int seq = 0; seq < w0 + n; seq++) {
        int64_t k = (int64_t)seq - w0 + 1;
        if (!keep_going(run, k, run_index, status))
            return false;
        if (k == 1) {
            /* Warm-up work still queued must not be billed to the timed frames. */
            if (!gpu_budget_sync(budget))
                return keep_going(run, k, run_index, status);
            interference_sample(&run->interference[0]);
            wall_start = clock_mono_s();
        }
        /* Bound the frames in flight like a swap chain would; the wait is part
         * of the frame interval, never of the CPU submit time. */
        GLsync *fence = &run->fences[seq % RUN_FRAMES_IN_FLIGHT];
        if (*fence) {
            bool go = gpu_budget_wait(budget, *fence);
            *fence = NULL;
            if (!go)
                return keep_going(run, k, run_index, status);
        }
        double t0 = clock_mono_s();
        if (k >= 2)
            run->frame_ms[k - 2] += (t0 - frame_begin) * 1e3;
        /* From the fourth frame on, an interval includes the wait for a frame
         * in flight, so it is what a frame costs (the first ones are only
         * submissions, or shader compilation). */
        if (seq >= 3)
            fastest_s = fmin(fastest_s, t0 - frame_begin);
        frame_begin = t0;
        bool ok = run_frame(run, k, k >= 1);
        glFlush(); /* where a swap would hand the frame to the GPU */
        double t1 = clock_mono_s();
        *fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        if (!ok)
            return gpu_budget_stopped(budget) ? keep_going(run, k, run_index, status) : false;
        if (k >= 1)
            run->cpu_ms[k - 1] = (t1 - t0) * 1e3;
        if (run->capture_count && job_spec_is_capture_frame(spec, (int)k)) {
            double c0 = clock_mono_s();
            /* The readback waits for the frame: let the wait ask. */
            if (!gpu_budget_sync(budget))
                return keep_going(run, k, run_index, status);
            if (!outputs_read_capture(run, (int)k))
                return false;
            double c = clock_mono_s() - c0;
            run->capture_s += c;
            run->frame_ms[k - 1] -= c * 1e3;
        }
        if ((seq & 15) == 15 && gl_error_take("rendering", run->err, sizeof(run->err)))
            return false;
        if (out_of_time(run, seq, fastest_s))
            return false;
        queue_progress(run->queue, run->job, run_index * n + (k > 0 ? (int)k : 0));
        render_progress_at(t1); /* for /healthz: one atomic store of a time already read */
        telemetry_frames(1);
    }
    if (!gpu_budget_sync(budget))
        return keep_going(run, n, run_index, status);
    double wall_end = clock_mono_s();
    interference_sample(&run->interference[1]);
    run->frame_ms[n - 1] += (wall_end - frame_begin) * 1e3;
    run->wall_s = wall_end - wall_start;
    gpu_timer_drain(run->timer);
    if (run->tech->verify && !run->tech->verify(run->state, run->err, sizeof(run->err)))
        return false;
    return !gl_error_take("rendering", run->err, sizeof(run->err));
}
