/* Temporal anti-aliasing: the harness jitters the projection along TAA's
 * Halton (2, 3) sequence and draws the motion vectors (both asked for
 * through taa_info's needs); each frame the resolve pass blends this
 * frame's pixel into the history, reprojected and kept to the pixel's
 * neighbourhood (taa.frag), writes the result into one of two history
 * planes (read back the next frame) and copies it to the chain's plane. A
 * frame that restarts the history (the first an instance draws, and the
 * one taa.history frames before each captured frame) passes the frame
 * through as it is, so that frame k is a pure function of k. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>

#include "daemon/effects/effect.h"
#include "daemon/effects/taa/taa_info.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

struct taa {
    struct taa_options o;
    GLuint prog;
    GLuint history[2], history_fbo[2];
    int write; /* the plane this frame writes; the other holds the history */
    int pass;
};

static void taa_destroy(void *state)
{
    struct taa *t = state;
    if (!t)
        return;
    glDeleteProgram(t->prog);
    free(t);
}

static bool taa_create(const struct effect_env *env, const void *opts, void **state, char *err,
                       size_t errlen)
{
    static const char *const clamp_defines[] = {
        "", "#define TAA_CLAMP_AABB 1\n", "#define TAA_CLAMP_CLIP 1\n",
        "#define TAA_CLAMP_VARIANCE 1\n"};
    struct taa *t = calloc(1, sizeof(*t));
    if (!t) {
        snprintf(err, errlen, "taa: out of memory");
        return false;
    }
    t->o = *(const struct taa_options *)opts;
    if (!env->motion_tex) {
        snprintf(err, errlen, "taa: the harness drew no motion vectors");
        goto fail;
    }
    /* The history in the look's HDR format: the resolve's running mean is
     * HDR colour, like the frame it blends. */
    if (!effect_plane(env, "history.a", env->hdr_format, env->width, env->height,
                      &t->history[0], &t->history_fbo[0], err, errlen) ||
        !effect_plane(env, "history.b", env->hdr_format, env->width, env->height,
                      &t->history[1], &t->history_fbo[1], err, errlen))
        goto fail;
    char defines[160];
    snprintf(defines, sizeof(defines), "%s%s", clamp_defines[t->o.clamp],
             t->o.filter == TAA_FILTER_CATMULL_ROM ? "#define TAA_CATMULL_ROM 1\n" : "");
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"taa.frag"}},
    };
    if (!(t->prog = gl_program_build("taa.resolve", stages, 2, defines, err, errlen)))
        goto fail;
    t->pass = env->first_pass;
    *state = t;
    return true;
fail:
    taa_destroy(t);
    return false;
}

static bool taa_run(void *state, const struct effect_env *env, const struct gpu_frame_time *time,
                    GLuint src, GLuint dst_fbo, char *err, size_t errlen)
{
    (void)err, (void)errlen;
    struct taa *t = state;
    int w = t->write, r = 1 - w;
    gpu_pass_begin(env->passes, t->pass, t->history_fbo[w], env->width, env->height);
    glProgramUniform4f(t->prog, SB_LOC_POST_PARAMS, (float)t->o.blend, (float)t->o.gamma,
                       time->restart ? 1.0f : 0.0f, 0.0f);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_SRC);
    glBindTexture(GL_TEXTURE_2D, src);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_DEPTH);
    glBindTexture(GL_TEXTURE_2D, env->depth_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_MOTION);
    glBindTexture(GL_TEXTURE_2D, env->motion_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_AUX);
    glBindTexture(GL_TEXTURE_2D, t->history[r]);
    glBindSampler(SB_TEX_POST_AUX, env->linear_sampler);
    effect_draw_fullscreen(env, t->prog);
    glBindSampler(SB_TEX_POST_AUX, 0);
    /* The chain's plane gets the same image: the next effect, or the
     * resolve, reads it there. */
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->history_fbo[w]);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, dst_fbo);
    glBlitFramebuffer(0, 0, env->width, env->height, 0, 0, env->width, env->height,
                      GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    gpu_pass_end(env->passes);
    t->write = r;
    return true;
}

const struct effect effect_taa = {
    .info = &taa_info,
    .create = taa_create,
    .run = taa_run,
    .destroy = taa_destroy,
};
