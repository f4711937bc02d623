/* MSAA as a harness option (issue 22): at msaa > 1 a technique draws into
 * a multisampled HDR colour and depth-stencil from the target pool, and the
 * harness resolves them, in a timed pass of its own after the technique's
 * passes and the sky, into the single-sample output that the post chain,
 * the captures and the HDR statistics read as at msaa 1. Render thread. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>

#include "daemon/harness/run.h"

bool run_msaa_targets(struct harness_run *run, GLenum hdr_format, int w, int h, int *samples_io,
                      GLuint *out, GLuint *color, GLuint *depth)
{
    int samples = *samples_io;
    const struct gpu_caps *caps = &run->gl->caps;
    struct gpu_targets *pool = run->gl->targets;
    /* Submission checks the same limit once the daemon knows it; a job queued
     * before a restart on another device meets it here. */
    if (samples > caps->max_msaa) {
        snprintf(run->err, sizeof(run->err),
                 "msaa: %d samples exceed this device's limit of %d (GL_MAX_SAMPLES %d, "
                 "GL_MAX_COLOR_TEXTURE_SAMPLES %d, GL_MAX_DEPTH_TEXTURE_SAMPLES %d)",
                 samples, caps->max_msaa, caps->max_samples, caps->max_color_texture_samples,
                 caps->max_depth_texture_samples);
        return false;
    }
    GLuint c = gpu_targets_texture_ms(pool, "output.hdr.ms", hdr_format, w, h, samples, run->err,
                                      sizeof(run->err));
    GLuint d = c ? gpu_targets_texture_ms(pool, "output.depth.ms", GL_DEPTH24_STENCIL8, w, h,
                                          samples, run->err, sizeof(run->err))
                 : 0;
    GLuint fbo = d ? gpu_targets_fbo(pool, "output.ms", &c, 1, d, run->err, sizeof(run->err)) : 0;
    if (!fbo)
        return false;
    /* Every program loops over the samples the driver gave (llvmpipe gives
     * 4 for 2), or an edge in the samples past the asked-for count would
     * go unseen. */
    int given = gpu_targets_samples(pool, c);
    if (gpu_targets_samples(pool, d) != given) {
        snprintf(run->err, sizeof(run->err),
                 "msaa: the driver gave the colour %d samples and the depth %d for %d asked",
                 given, gpu_targets_samples(pool, d), samples);
        return false;
    }
    *samples_io = given;
    *out = fbo, *color = c, *depth = d;
    return true;
}

void run_msaa_resolve(struct harness_run *run)
{
    int w = run->env.width, h = run->env.height;
    gpu_pass_begin(&run->passes, run->msaa_pass, run->hdr_fbo, w, h);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, run->env.output_fbo);
    /* Colour: the box filter of its samples. Depth and stencil: the value
     * of one sample (glBlitFramebuffer picks it; Mesa and the GPU drivers
     * take sample 0): a depth no surface has, such as the mean of a
     * silhouette's samples, would put SSAO's or toon's edges in mid-air. */
    glBlitFramebuffer(0, 0, w, h, 0, 0, w, h,
                      GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT,
                      GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    gpu_pass_end(&run->passes);
}

json_t *run_msaa_json(const struct harness_run *run)
{
    const struct gpu_caps *caps = &run->gl->caps;
    int samples = run->spec->msaa > 1 ? run->spec->msaa : 1;
    int given = run->env.samples > 1 ? run->env.samples : 1;
    return json_pack("{s:i, s:i, s:i, s:i, s:f, s:s}", "samples", samples, "device_samples", given,
                     "reference_samples", run->spec->reference[0] ? samples : 0, "device_max",
                     caps->max_msaa,
                     "targets_bytes_in_use", gpu_targets_bytes_in_use(run->gl->targets),
                     "resolve",
                     samples > 1 ? "after the technique's passes and the sky, before the post "
                                   "chain and the captures: colour averaged over the samples "
                                   "(a box filter, before the tone map), depth and stencil "
                                   "from one sample (msaa_resolve pass)"
                                 : "none (one sample a pixel)");
}
