#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/reference.h"

#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>

#include "common/job_files.h"
#include "common/png_io.h"
#include "daemon/gpu/glutil.h"
#include "daemon/jobs/deadline.h"
#include "daemon/quality/flicker.h"

bool frame_source_open(struct harness_run *run, struct frame_source *src, const char *what,
                       const struct technique *tech, const void *options,
                       const struct look_spec *look, int scale)
{
    const struct job_spec *spec = run->spec;
    /* A run of its own over the same scene, look stages and targets, with
     * the look it renders with (reference_look may differ in format and
     * lighting). */
    *src = (struct frame_source){
        .rr = {.gl = run->gl, .queue = run->queue, .job = run->job, .spec = spec, .tech = tech,
               .look = look, .stages = run->stages, .shadow_pass = -1, .sky_pass = -1,
               .transparent = run->transparent, .transparent_pass = -1,
               .scale = scale},
        .what = what,
    };
    struct harness_run *rr = &src->rr;
    run_budget_init(rr);
    if (scale > 1 &&
        !(src->big = malloc((size_t)spec->scene.width * scale * (size_t)spec->scene.height * scale * 4))) {
        snprintf(run->err, sizeof(run->err), "%s %s: out of memory for its %dx frames", what,
                 tech->info->name, scale);
        return false;
    }
    if (!run_setup_targets(rr)) {
        snprintf(run->err, sizeof(run->err), "%s %s: cannot prepare it: %.900s", what,
                 tech->info->name, rr->err);
        return false;
    }
    rr->env.scene = run->env.scene;
    rr->env.gpu = run->env.gpu;
    if (!run_setup_passes(rr, options, 1)) {
        snprintf(run->err, sizeof(run->err), "%s %s: cannot prepare it: %.900s", what,
                 tech->info->name, rr->err);
        return false;
    }
    /* Its frames are untimed: the pass timer rests, so that the budget's
     * measured tiles time their GPU work with queries of their own rather
     * than the wall clock, which on a loaded machine adds a round trip's
     * wait to every tile (and cut the frames into hundreds of tiles). */
    gpu_timer_pause(rr->timer, true);
    rr->budget.timer = rr->timer;
    rr->budget.use_queries = true;
    return true;
}

static void drop_instance(struct frame_source *src)
{
    if (src->rr.state)
        src->rr.tech->destroy(src->rr.state);
    src->rr.state = NULL;
}

bool frame_source_frame(struct harness_run *run, struct frame_source *src, int64_t k, bool fresh,
                        uint8_t *pixels, enum job_status *status)
{
    struct harness_run *rr = &src->rr;
    const struct technique *tech = rr->tech;
    const char *what = src->what;
    if (atomic_load(&run->job->cancel)) {
        *status = JOB_CANCELLED;
        snprintf(run->err, sizeof(run->err), "cancelled while rendering the %s", what);
        return false;
    }
    if (job_timed_out(run->job)) {
        job_timeout_message(run->job, what, "", run->err, sizeof(run->err));
        return false;
    }
    rr->err[0] = '\0';
    bool drawn = true;
    if (fresh || !rr->state) {
        /* The post chain's effects are built anew for each instance: from
         * the normals it publishes. */
        drop_instance(src);
        if (!tech->create(&rr->env, &rr->state, rr->err, sizeof(rr->err)) ||
            !run_build_post_chain(rr)) {
            snprintf(run->err, sizeof(run->err), "%s %s cannot run: %.900s", what,
                     tech->info->name, rr->err);
            drop_instance(src);
            return false;
        }
        /* A new instance keeps no history: it draws the frames its history
         * reaches back to first (from the restart needs.history_frames
         * before frame k), as the timed run drew them before frame k. */
        rr->drawn = false;
        for (int64_t j = k - rr->needs.history_frames; drawn && j < k; j++)
            drawn = run_frame(rr, j, false);
    }
    if (drawn)
        drawn = run_frame(rr, k, false);
    if (!drawn && gpu_budget_stopped(&rr->budget)) {
        drop_instance(src);
        if (atomic_load(&run->job->cancel)) {
            *status = JOB_CANCELLED;
            snprintf(run->err, sizeof(run->err), "cancelled while rendering the %s (frame %" PRId64 ")",
                     what, k);
        } else {
            char detail[64];
            snprintf(detail, sizeof(detail), " at frame %" PRId64, k);
            job_timeout_message(run->job, what, detail, run->err, sizeof(run->err));
        }
        return false;
    }
    int w = run->spec->scene.width, h = run->spec->scene.height, n = rr->scale > 1 ? rr->scale : 1;
    if (drawn) {
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, rr->ldr_fbo);
        glReadPixels(0, 0, w * n, h * n, GL_RGBA, GL_UNSIGNED_BYTE, n > 1 ? src->big : pixels);
    }
    if (!drawn || gl_error_take("reference rendering", rr->err, sizeof(rr->err))) {
        snprintf(run->err, sizeof(run->err), "%s %s failed: %.900s", what, tech->info->name,
                 rr->err);
        return false;
    }
    /* Outside every timed region, on the CPU: the filter is a few
     * milliseconds a megapixel, and the same code the unit tests check. */
    if (n > 1)
        flicker_box_downsample(src->big, w * n, h * n, n, 4, pixels);
    return true;
}

void frame_source_close(struct frame_source *src)
{
    drop_instance(src);
    post_chain_destroy(src->rr.post);
    src->rr.post = NULL;
    motion_vectors_finish(&src->rr.motion);
    gpu_timer_destroy(src->rr.timer);
    src->rr.timer = NULL;
    free(src->big);
    src->big = NULL;
}

/* Each frame gets a fresh technique instance, since frame k is a pure
 * function of k: a stateful technique (OSL) then shows what it would at
 * frame k in a run of its own. */
bool reference_render(struct harness_run *run, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    const struct technique *ref = technique_find(spec->reference);
    int w = spec->scene.width, h = spec->scene.height;
    uint8_t *pixels = malloc((size_t)w * (size_t)h * 4);
    struct frame_source src = {0};
    bool ok = false;
    if (!ref || !pixels) {
        snprintf(run->err, sizeof(run->err), "reference %s: cannot prepare it", spec->reference);
        goto out;
    }
    if (!frame_source_open(run, &src, "reference", ref, job_spec_reference_options(spec),
                           &spec->reference_look, spec->reference_supersample))
        goto out;
    for (int k = spec->capture_interval; k <= spec->frames; k += spec->capture_interval) {
        if (!frame_source_frame(run, &src, k, true, pixels, status))
            goto out;
        char path[PATH_MAX + JOB_IMAGE_NAME_MAX];
        job_image_path(run->job->dir, JOB_IMAGE_REFERENCE, k, path, sizeof(path));
        if (!png_write_gl_rgba(path, pixels, w, h, run->err, sizeof(run->err)))
            goto out;
    }
    ok = true;
out:
    frame_source_close(&src);
    free(pixels);
    return ok;
}
