#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/reference.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>

#include "common/job_files.h"
#include "common/png_io.h"
#include "daemon/gpu/glutil.h"
#include "daemon/harness/deadline.h"

/* Each frame gets a fresh technique instance, since frame k is a pure
 * function of k: a stateful technique (OSL) then shows what it would at
 * frame k in a run of its own. */
bool reference_render(struct harness_run *run, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    const struct technique *ref = technique_find(spec->reference);
    int w = spec->scene.width, h = spec->scene.height;
    uint8_t *pixels = malloc((size_t)w * (size_t)h * 4);
    /* A run of its own over the same scene, look stages and targets, with
     * the look the reference renders with (reference_look may differ in
     * format and lighting). */
    struct harness_run rr = {.gl = run->gl, .queue = run->queue, .job = run->job, .spec = spec,
                     .tech = ref, .look = &spec->reference_look, .stages = run->stages,
                     .shadow_pass = -1, .sky_pass = -1};
    bool ok = false;
    run_budget_init(&rr);
    if (!ref || !pixels || !run_setup_targets(&rr)) {
        snprintf(run->err, sizeof(run->err), "reference %s: cannot prepare it: %.900s",
                 spec->reference, rr.err);
        goto out;
    }
    rr.env.scene = run->env.scene;
    rr.env.gpu = run->env.gpu;
    if (!run_setup_passes(&rr, job_spec_reference_options(spec), 1)) {
        snprintf(run->err, sizeof(run->err), "reference %s: cannot prepare it: %.900s",
                 spec->reference, rr.err);
        goto out;
    }
    for (int k = spec->capture_interval; k <= spec->frames; k += spec->capture_interval) {
        if (atomic_load(&run->job->cancel)) {
            *status = JOB_CANCELLED;
            snprintf(run->err, sizeof(run->err), "cancelled while rendering the reference");
            goto out;
        }
        if (job_timed_out(run->job)) {
            job_timeout_message(run->job, "reference", "", run->err, sizeof(run->err));
            goto out;
        }
        rr.err[0] = '\0';
        if (!ref->create(&rr.env, &rr.state, rr.err, sizeof(rr.err)) ||
            !run_build_post_chain(&rr)) {
            snprintf(run->err, sizeof(run->err), "reference %s cannot run: %.900s",
                     ref->info->name, rr.err);
            ref->destroy(rr.state);
            rr.state = NULL;
            goto out;
        }
        bool drawn = run_frame(&rr, k, false);
        if (!drawn && gpu_budget_stopped(&rr.budget)) {
            ref->destroy(rr.state);
            rr.state = NULL;
            if (atomic_load(&run->job->cancel)) {
                *status = JOB_CANCELLED;
                snprintf(run->err, sizeof(run->err),
                         "cancelled while rendering the reference (frame %d)", k);
            } else {
                char detail[64];
                snprintf(detail, sizeof(detail), " at frame %d", k);
                job_timeout_message(run->job, "reference", detail, run->err, sizeof(run->err));
            }
            goto out;
        }
        if (drawn) {
            glBindFramebuffer(GL_READ_FRAMEBUFFER, rr.ldr_fbo);
            glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
        }
        ref->destroy(rr.state);
        rr.state = NULL;
        if (!drawn || gl_error_take("reference rendering", rr.err, sizeof(rr.err))) {
            snprintf(run->err, sizeof(run->err), "reference %s failed: %.900s", ref->info->name,
                     rr.err);
            goto out;
        }
        char path[PATH_MAX + JOB_IMAGE_NAME_MAX];
        job_image_path(run->job->dir, JOB_IMAGE_REFERENCE, k, path, sizeof(path));
        if (!png_write_gl_rgba(path, pixels, w, h, run->err, sizeof(run->err)))
            goto out;
    }
    ok = true;
out:
    gpu_timer_destroy(rr.timer);
    post_chain_destroy(rr.post);
    free(pixels);
    return ok;
}
