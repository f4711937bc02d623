/* Screen-space ambient occlusion (seed 002's "blurry SSAO"): hemisphere
 * samples around each pixel's normal tested against the depth texture,
 * then blurred over the 4x4 rotation tile and multiplied into the colour.
 * Normals come from the technique's g-buffer when it publishes one, else
 * they are rebuilt from depth (post_common.glsl). The kernel and the
 * rotations come from a fixed seed: the same every frame and every run. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>

#include "daemon/effects/effect.h"
#include "daemon/effects/ssao/ssao_info.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

struct ssao {
    GLuint ao_prog, apply_prog;
    GLuint ao, ao_fbo;
    int pass_ao, pass_apply;
};

static void ssao_destroy(void *state)
{
    struct ssao *s = state;
    if (!s)
        return;
    glDeleteProgram(s->ao_prog);
    glDeleteProgram(s->apply_prog);
    free(s);
}

static bool ssao_create(const struct effect_env *env, const void *opts, void **state, char *err,
                        size_t errlen)
{
    const struct ssao_options *o = opts;
    struct ssao *s = calloc(1, sizeof(*s));
    if (!s) {
        snprintf(err, errlen, "ssao: out of memory");
        return false;
    }
    /* Occlusion is a fraction: 16 bits keep the blur free of banding. */
    if (!effect_plane(env, "ao", GL_R16F, env->width, env->height, &s->ao, &s->ao_fbo,
                      err, errlen))
        goto fail;
    char defines[256];
    snprintf(defines, sizeof(defines), "#define SAMPLES %d\n%s", o->samples, env->normal_defines);
    const struct gl_stage ao_stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"ssao.frag"}},
    };
    const struct gl_stage apply_stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"ssao_apply.frag"}},
    };
    if (!(s->ao_prog = gl_program_build("ssao.ao", ao_stages, 2, defines, err, errlen)) ||
        !(s->apply_prog = gl_program_build("ssao.apply", apply_stages, 2,
                                           o->blur ? "#define BLUR 1\n" : NULL, err, errlen)))
        goto fail;

    float kernel[SSAO_MAX_SAMPLES][4], noise[SSAO_NOISE_SIZE * SSAO_NOISE_SIZE];
    ssao_kernel(o->samples, SSAO_SEED, kernel);
    ssao_noise(SSAO_SEED, noise);
    glProgramUniform4fv(s->ao_prog, SB_LOC_SSAO_KERNEL, o->samples, &kernel[0][0]);
    glProgramUniform1fv(s->ao_prog, SB_LOC_SSAO_NOISE, SSAO_NOISE_SIZE * SSAO_NOISE_SIZE, noise);
    glProgramUniform4f(s->ao_prog, SB_LOC_POST_PARAMS, (float)o->radius, (float)o->bias, 0, 0);
    glProgramUniform4f(s->apply_prog, SB_LOC_POST_PARAMS, (float)o->intensity, 0, 0, 0);
    s->pass_ao = env->first_pass;
    s->pass_apply = env->first_pass + 1;
    *state = s;
    return true;
fail:
    ssao_destroy(s);
    return false;
}

static bool ssao_run(void *state, const struct effect_env *env,
                     const struct gpu_frame_time *time, GLuint src, GLuint dst_fbo, char *err,
                     size_t errlen)
{
    (void)time, (void)err, (void)errlen;
    struct ssao *s = state;
    gpu_pass_begin(env->passes, s->pass_ao, s->ao_fbo, env->width, env->height);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_DEPTH);
    glBindTexture(GL_TEXTURE_2D, env->depth_tex);
    if (env->normal_tex) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_NORMAL);
        glBindTexture(GL_TEXTURE_2D, env->normal_tex);
    }
    effect_draw_fullscreen(env, s->ao_prog);
    gpu_pass_end(env->passes);

    gpu_pass_begin(env->passes, s->pass_apply, dst_fbo, env->width, env->height);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_SRC);
    glBindTexture(GL_TEXTURE_2D, src);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_AUX);
    glBindTexture(GL_TEXTURE_2D, s->ao);
    effect_draw_fullscreen(env, s->apply_prog);
    gpu_pass_end(env->passes);
    return true;
}

const struct effect effect_ssao = {
    .info = &ssao_info,
    .create = ssao_create,
    .run = ssao_run,
    .destroy = ssao_destroy,
};
