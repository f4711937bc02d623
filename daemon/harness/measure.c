#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/measure.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

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
        if (run->measuring)
            snprintf(run->err, sizeof(run->err), "cancelled while the first frame of run %d was "
                     "measured, before timing%s", run_index + 1, in);
        else if (k >= 1)
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
        if (run->measuring)
            snprintf(detail, sizeof(detail), " while its first frame was measured, before "
                     "timing%s", in);
        else
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

/* The pass a measure named, for messages. */
static void pass_name(const struct harness_run *run, int pass, char *out, size_t cap)
{
    snprintf(out, cap, "%s", pass >= 0 && pass < run->passes.count ? run->passes.names[pass]
                                                                     : "unnamed");
}

/* One of the harness's own frames before the warm-up (the content of the
 * first warm-up frame, k = 1 - max(warmup_frames, 1), never timed nor
 * counted): drawn after every earlier submission has finished and waited
 * for, so that *took is what it held the render thread. */
static bool harness_frame(struct harness_run *run, int64_t k, int run_index, double *took,
                          enum job_status *status)
{
    struct gpu_budget *b = &run->budget;
    if (!gpu_budget_sync(b))
        return keep_going(run, k, run_index, status);
    double t0 = clock_mono_s();
    bool ok = run_frame(run, k, false);
    if (!ok && !gpu_budget_stopped(b))
        return false;
    if (ok && !gpu_budget_sync(b))
        ok = false;
    if (!ok) {
        if (b->over)
            return false; /* the caller says why */
        return keep_going(run, k, run_index, status);
    }
    *took = clock_mono_s() - t0;
    render_progress();
    return !gl_error_take("measuring", run->err, sizeof(run->err));
}

/* A frame measured in slices: what it would take drawn whole, from what it
 * took less the time its measured pieces spent in their tiles plus what
 * their measures say they cost whole (the probe's fixed cost once, not once
 * a tile). */
static double whole_estimate(const struct gpu_budget *b, double took)
{
    double e = took - b->frame.measured_s + b->frame.whole_s;
    return e > b->frame.whole_s ? e : b->frame.whole_s;
}

static void note_largest(struct harness_run *run)
{
    const struct gpu_budget *b = &run->budget;
    struct run_timing_rule *rule = run->rule;
    if (b->frame.largest_s > rule->largest_s) {
        rule->largest_s = b->frame.largest_s;
        pass_name(run, b->frame.largest_pass, rule->largest, sizeof(rule->largest));
    }
}

/* The job's frames cannot be drawn whole within the bound, and it did not
 * accept sliced timing: it fails before any frame is timed, with the
 * figures that decided it and what to change. */
static bool refuse_whole(struct harness_run *run, bool gave_up)
{
    const struct run_timing_rule *rule = run->rule;
    char measured[384];
    if (rule->whole_frame_s >= 0)
        snprintf(measured, sizeof(measured), "a whole frame took %.2f s", rule->whole_frame_s);
    else if (gave_up && rule->settling_frame_s >= 0)
        snprintf(measured, sizeof(measured), "its first frame, measured in slices, came to more "
                 "than %.2f s drawn whole before it was done (the measure stops at 4 times the "
                 "bound), and did again once the frame had been drawn through (%.2f s in slices)",
                 4 * rule->limit_s, rule->settling_frame_s);
    else if (rule->settling_frame_s >= 0)
        snprintf(measured, sizeof(measured), "its first frame, measured in slices, came to more "
                 "than %.2f s drawn whole before it was done (the measure stops at 4 times the "
                 "bound); drawn through (%.2f s in slices) and measured again, it would take "
                 "%.2f s drawn whole", 4 * rule->limit_s, rule->settling_frame_s,
                 rule->estimate_s[1]);
    else if (gave_up)
        snprintf(measured, sizeof(measured), "its first frame, measured in slices, already came "
                 "to more than %.2f s drawn whole before it was done (the measure stops at 4 "
                 "times the bound)", 4 * rule->limit_s);
    else if (rule->estimate_s[1] >= 0)
        snprintf(measured, sizeof(measured), "its first frame, measured twice in slices, would "
                 "take %.2f s and %.2f s drawn whole", rule->estimate_s[0], rule->estimate_s[1]);
    else
        snprintf(measured, sizeof(measured), "its first frame, measured in slices, would take "
                 "%.2f s drawn whole", rule->estimate_s[0]);
    snprintf(run->err, sizeof(run->err),
             "failed before timing: %s (the dearest piece: the %s pass, %s%.2f s), more than "
             "the %g s one frame may hold the render thread (--max-frame-seconds %g; /v1/info: "
             "limits.max_frame_seconds), so its frames cannot be timed whole; run it with fewer "
             "pixels (scene.width, scene.height) or fewer lights (scene.lights), or set "
             "\"accept_sliced_timing\": true to time it in slices (every figure is then marked "
             "sliced)",
             measured, rule->largest[0] ? rule->largest : "unnamed", gave_up ? "at least " : "about ",
             rule->largest_s,
             rule->limit_s, rule->limit_s);
    return false;
}

/* A run's first frames, which decide how its timed frames are drawn: its
 * first warm-up frame drawn in slices (every piece measured, so that
 * nothing in it, OSL's first shading or a frame of many lights included,
 * holds the render thread past about a slice), and, in the job's first run,
 * its second warm-up frame drawn whole, exactly as the timed frames will
 * be, and timed alone, when the measure says it fits the bound. A job with
 * fewer warm-up frames gets that many more frames of the harness's own
 * before its timed frames (of the first warm-up frame's content, or of
 * frame 0). The timed frames are drawn whole when that whole frame took no
 * more than the bound; else, if the job accepts it, in the tiles the
 * measure gives, and otherwise the job fails here. A measure over the bound
 * is taken again once, however far over it (a slow first frame, a moment
 * of load, must not decide). A measure far over it (4 times) ends at once,
 * the technique made anew after it (the frame was abandoned); the frame is
 * then drawn through once in slices, unjudged, before it is measured again:
 * work a technique does once (OSL shading every atlas on its first frame)
 * can pass 4 times the bound on a loaded machine, and measured again from
 * a new instance it would only pass it again, failing a job whose frames
 * fit. Later runs borrow the first run's measures and follow its rule.
 * *consumed gets the job's warm-up frames these frames were (0 to 2). */
static bool decide(struct harness_run *run, int run_index, int *consumed,
                   enum job_status *status)
{
    struct gpu_budget *b = &run->budget;
    struct run_timing_rule *rule = run->rule;
    int w0 = run->spec->warmup_frames;
    int64_t k = 1 - (w0 > 1 ? w0 : 1);
    double took;
    *consumed = 0;
    if (rule->decided) {
        memcpy(b->piece, rule->pieces, sizeof(b->piece));
        *consumed = w0 >= 1;
        return harness_frame(run, k, run_index, &took, status);
    }
    double limit = rule->limit_s = job_spec_max_frame_seconds();
    rule->estimate_s[0] = rule->estimate_s[1] = rule->whole_frame_s = rule->settling_frame_s = -1;
    double give_up = limit > 0 && !run->spec->accept_sliced_timing ? 4 * limit : 0;
    bool whole = false, gave_up = false;
    /* Two measures; after a give-up (at the first or the second), the next
     * frame draws the frame through and one more measures it. e: the next
     * of the two estimate slots (a third measure overwrites the second). */
    int settle_at = -1;
    for (int m = 0, e = 0; m < (settle_at >= 0 ? settle_at + 2 : 2) && !whole; m++) {
        bool settling = m == settle_at;
        /* The settling frame keeps what the given-up one measured (its
         * pieces drawn in tiles of a slice); a measure starts afresh. */
        if (m >= 1 && !settling)
            gpu_budget_forget(b);
        b->give_up_s = settling ? 0 : give_up;
        bool ok = harness_frame(run, k, run_index, &took, status);
        rule->measuring_frames = m + 1;
        if (!settling)
            note_largest(run);
        if (!ok && !b->over)
            return false;
        if (!ok) {
            /* Given up at 4 times the bound: over it, unless that was the
             * moment's load or work done once, which the next measure tells. */
            if (gave_up)
                return refuse_whole(run, true);
            rule->estimate_s[e < 2 ? e : 1] = b->frame.whole_s;
            e++;
            b->stopped = b->over = false;
            gave_up = true;
            settle_at = m + 1;
            /* The frame was abandoned: what it left half-done (OSL's first
             * shading) must not pass for done in the next. */
            if (!gpu_budget_sync(b))
                return keep_going(run, k, run_index, status);
            if (!run_recreate_technique(run))
                return false;
            continue;
        }
        /* The first is the job's first warm-up frame, if it has one. */
        *consumed = w0 >= 1;
        if (settling) {
            rule->settling_frame_s = took;
            continue;
        }
        double estimate = rule->estimate_s[e < 2 ? e : 1] = whole_estimate(b, took);
        e++;
        /* The pixels' work: the measured pieces' cost above what every tile
         * pays; the rest of the frame (submission, geometry, loops of draws,
         * the waits between) does not grow with the pixels. */
        rule->pixel_share =
            estimate > 0 ? (b->frame.whole_s - b->frame.fixed_s) / estimate : 1.0;
        whole = limit <= 0 || estimate <= limit;
    }
    b->give_up_s = 0;
    if (whole) {
        /* The deciding frame, drawn exactly as the timed frames will be:
         * the second warm-up frame, or one more of the first's. */
        b->mode = GPU_BUDGET_WHOLE;
        if (!harness_frame(run, w0 >= 2 ? k + 1 : k, run_index, &took, status))
            return false;
        if (w0 >= 2)
            *consumed = 2;
        rule->whole_frame_s = took;
        whole = limit <= 0 || took <= limit;
    }
    if (!whole && !run->spec->accept_sliced_timing)
        return refuse_whole(run, false);
    rule->mode = whole ? GPU_BUDGET_WHOLE : GPU_BUDGET_SLICED;
    rule->decided = true;
    memcpy(rule->pieces, b->piece, sizeof(rule->pieces));
    return true;
}

static bool measure_first_frames(struct harness_run *run, int run_index, int *consumed,
                                 enum job_status *status)
{
    struct gpu_budget *b = &run->budget;
    b->timer = run->timer;
    b->mode = GPU_BUDGET_ADAPTIVE;
    /* The pass timer rests: the measured tiles time themselves. */
    gpu_timer_pause(run->timer, true);
    b->use_queries = true;
    run->measuring = true;
    bool ok = decide(run, run_index, consumed, status);
    run->measuring = false;
    b->use_queries = false;
    gpu_timer_pause(run->timer, false);
    return ok;
}

bool measure_run(struct harness_run *run, int run_index, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    struct gpu_budget *budget = &run->budget;
    int w0 = spec->warmup_frames, n = spec->frames;
    double wall_start = 0, frame_begin = 0, fastest_s = INFINITY;
    run->capture_s = 0;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    int consumed;
    if (!measure_first_frames(run, run_index, &consumed, status))
        return false;
    /* The measuring frames are not the timer's: its frame i is the warm-up
     * or timed frame drawn i-th, as ever. */
    gpu_timer_restart(run->timer, consumed);
    budget->mode = run->rule->mode;
    int64_t sliced_before = 0;
    for (int seq = consumed; seq < w0 + n; seq++) {
        int64_t k = (int64_t)seq - w0 + 1;
        if (!keep_going(run, k, run_index, status))
            return false;
        if (k == 1) {
            /* Warm-up work still queued must not be billed to the timed frames. */
            if (!gpu_budget_sync(budget))
                return keep_going(run, k, run_index, status);
            interference_sample(&run->interference[0]);
            gl_build_timed_region(true);
            wall_start = clock_mono_s();
            sliced_before = budget->pieces_sliced;
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
        if (k >= 1) {
            run->cpu_ms[k - 1] = (t1 - t0) * 1e3;
            run->drawn_whole[k - 1] = budget->frame.sliced_runs == 0;
        }
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
    gl_build_timed_region(false);
    interference_sample(&run->interference[1]);
    run->frame_ms[n - 1] += (wall_end - frame_begin) * 1e3;
    run->wall_s = wall_end - wall_start;
    run->pieces_sliced = budget->pieces_sliced - sliced_before;
    gpu_timer_drain(run->timer);
    if (run->tech->verify && !run->tech->verify(run->state, run->err, sizeof(run->err)))
        return false;
    return !gl_error_take("rendering", run->err, sizeof(run->err));
}
