/* Toon shading (seeds 001 and 003): a luminance ramp of a few levels and
 * black outlines on depth (and normal) edges, in one pass. Its normals are
 * always rebuilt from depth, never read from a g-buffer: smooth g-buffer
 * normals put outlines inside small spheres that depth-rebuilt ones do not
 * (deferred against forward fell to SSIM 0.71 at 160x120), and outlines
 * must not depend on the technique. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>

#include "daemon/effects/effect.h"
#include "daemon/effects/toon/toon_info.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

struct toon {
    GLuint prog;
    int pass;
};

static void toon_destroy(void *state)
{
    struct toon *t = state;
    if (!t)
        return;
    glDeleteProgram(t->prog);
    free(t);
}

static bool toon_create(const struct effect_env *env, const void *opts, void **state, char *err,
                        size_t errlen)
{
    const struct toon_options *o = opts;
    struct toon *t = calloc(1, sizeof(*t));
    if (!t) {
        snprintf(err, errlen, "toon: out of memory");
        return false;
    }
    static const char *const edges[] = {"#define EDGES_SOBEL 1\n", "#define EDGES_DEPTH_DIFF 1\n",
                                        ""};
    char defines[320];
    snprintf(defines, sizeof(defines), "#define LEVELS %d\n#define THICKNESS %d\n%s", o->levels,
             o->thickness, edges[o->edges]);
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"toon.frag"}},
    };
    t->prog = gl_program_build("toon", stages, 2, defines, err, errlen);
    if (!t->prog) {
        toon_destroy(t);
        return false;
    }
    glProgramUniform4f(t->prog, SB_LOC_POST_PARAMS, (float)o->threshold,
                       (float)o->normal_threshold, 0, 0);
    t->pass = env->first_pass;
    *state = t;
    return true;
}

static bool toon_run(void *state, const struct effect_env *env,
                     const struct gpu_frame_time *time, GLuint src, GLuint dst_fbo, char *err,
                     size_t errlen)
{
    (void)time, (void)err, (void)errlen;
    struct toon *t = state;
    gpu_pass_begin(env->passes, t->pass, dst_fbo, env->width, env->height);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_SRC);
    glBindTexture(GL_TEXTURE_2D, src);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_DEPTH);
    glBindTexture(GL_TEXTURE_2D, env->depth_tex);
    effect_draw_fullscreen(env, t->prog);
    gpu_pass_end(env->passes);
    return true;
}

const struct effect effect_toon = {
    .info = &toon_info,
    .create = toon_create,
    .run = toon_run,
    .destroy = toon_destroy,
};
