/* Bloom (seed 001, GPU Gems ch. 21): a bright pass keeps the light above a
 * luminance threshold, a Gaussian blur spreads it (one 2D pass or two 1D
 * passes), and the composite adds it back to the colour. With downsample n
 * the bright pass writes half size and a mip chain of n levels is blurred
 * and added back up level by level: a wider glow for the same taps. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/effects/effect.h"
#include "daemon/effects/bloom/bloom_info.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

#define BLOOM_MAX_LEVELS 6

struct level {
    int w, h;
    GLuint a, a_fbo; /* the bright light, then (separable) the blurred light */
    GLuint b, b_fbo; /* the row-blurred light, or (2d) the blurred light */
};

struct bloom {
    struct bloom_options o;
    int nlevels;
    struct level level[BLOOM_MAX_LEVELS];
    GLuint bright_prog, down_prog, blur_prog[2], up_prog, composite_prog;
    int pass_bright, pass_down, pass_blur, pass_up, pass_composite;
};

static void bloom_destroy(void *state)
{
    struct bloom *b = state;
    if (!b)
        return;
    GLuint progs[] = {b->bright_prog, b->down_prog, b->blur_prog[0], b->blur_prog[1], b->up_prog,
                      b->composite_prog};
    for (size_t i = 0; i < sizeof(progs) / sizeof(progs[0]); i++)
        glDeleteProgram(progs[i]);
    free(b);
}

static GLuint build(const char *label, const char *frag, const char *defines, char *err,
                    size_t errlen)
{
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {frag}},
    };
    return gl_program_build(label, stages, 2, defines, err, errlen);
}

static bool bloom_create(const struct effect_env *env, const void *opts, void **state, char *err,
                         size_t errlen)
{
    struct bloom *b = calloc(1, sizeof(*b));
    if (!b) {
        snprintf(err, errlen, "bloom: out of memory");
        return false;
    }
    b->o = *(const struct bloom_options *)opts;
    int w = env->width, h = env->height, n = b->o.downsample;
    b->nlevels = n > 0 ? n : 1;
    for (int i = 0; i < b->nlevels; i++) {
        int shift = n > 0 ? i + 1 : 0;
        struct level *l = &b->level[i];
        l->w = w >> shift > 0 ? w >> shift : 1;
        l->h = h >> shift > 0 ? h >> shift : 1;
        char a[16], bb[16];
        snprintf(a, sizeof(a), "l%d", i);
        snprintf(bb, sizeof(bb), "t%d", i);
        if (!effect_plane(env, a, env->hdr_format, l->w, l->h, &l->a, &l->a_fbo, err, errlen) ||
            !effect_plane(env, bb, env->hdr_format, l->w, l->h, &l->b, &l->b_fbo, err, errlen))
            goto fail;
    }

    char defines[160];
    bool sep = b->o.kernel == BLOOM_SEPARABLE;
    snprintf(defines, sizeof(defines), "#define BRIGHT 1\n%s", n > 0 ? "#define HALVE 1\n" : "");
    if (!(b->bright_prog = build("bloom.bright", "bloom_sample.frag", defines, err, errlen)) ||
        (n > 1 && !(b->down_prog = build("bloom.down", "bloom_sample.frag", "#define HALVE 1\n",
                                         err, errlen))))
        goto fail;
    for (int k = 0; k < (sep ? 2 : 1); k++) {
        snprintf(defines, sizeof(defines), "#define RADIUS %d\n%s", b->o.radius,
                 !sep ? "#define BLUR_2D 1\n" : k == 0 ? "#define DIR_X 1\n" : "");
        if (!(b->blur_prog[k] = build("bloom.blur", "bloom_blur.frag", defines, err, errlen)))
            goto fail;
    }
    if ((n > 1 && !(b->up_prog = build("bloom.up", "bloom_up.frag", NULL, err, errlen))) ||
        !(b->composite_prog = build("bloom.composite", "bloom_up.frag", "#define COMPOSITE 1\n",
                                    err, errlen)))
        goto fail;

    /* Every uniform is set here, once: the timed run sets none. */
    float weights[BLOOM_MAX_RADIUS + 1] = {0};
    gauss_weights(b->o.radius, weights);
    for (int k = 0; k < (sep ? 2 : 1); k++)
        glProgramUniform1fv(b->blur_prog[k], SB_LOC_POST_WEIGHTS, BLOOM_MAX_RADIUS + 1, weights);
    glProgramUniform4f(b->bright_prog, SB_LOC_POST_PARAMS, (float)b->o.threshold, 0, 0, 0);
    /* Each level carries the bloom once: average them, so that intensity
     * means the same with or without a mip chain. */
    glProgramUniform4f(b->composite_prog, SB_LOC_POST_PARAMS,
                       (float)(b->o.intensity / b->nlevels), 0, 0, 0);

    int p = env->first_pass;
    b->pass_bright = p++;
    b->pass_down = n > 1 ? p++ : -1;
    b->pass_blur = p;
    p += sep ? 2 : 1;
    b->pass_up = n > 1 ? p++ : -1;
    b->pass_composite = p;
    *state = b;
    return true;
fail:
    bloom_destroy(b);
    return false;
}

static void target(const struct level *l, GLuint fbo)
{
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, l->w, l->h);
}

static void bind(GLuint unit, GLuint tex)
{
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_2D, tex);
}

static bool bloom_run(void *state, const struct effect_env *env,
                      const struct gpu_frame_time *time, GLuint src, GLuint dst_fbo, char *err,
                      size_t errlen)
{
    (void)time, (void)err, (void)errlen;
    struct bloom *b = state;
    const struct gpu_passes *ps = env->passes;
    int n = b->nlevels;
    bool sep = b->o.kernel == BLOOM_SEPARABLE;

    gpu_pass_begin(ps, b->pass_bright, b->level[0].a_fbo, b->level[0].w, b->level[0].h);
    bind(SB_TEX_POST_SRC, src);
    effect_draw_fullscreen(env, b->bright_prog);
    gpu_pass_end(ps);

    if (b->pass_down >= 0) {
        gpu_pass_begin(ps, b->pass_down, b->level[1].a_fbo, b->level[1].w, b->level[1].h);
        for (int i = 1; i < n; i++) {
            target(&b->level[i], b->level[i].a_fbo);
            bind(SB_TEX_POST_SRC, b->level[i - 1].a);
            effect_draw_fullscreen(env, b->down_prog);
        }
        gpu_pass_end(ps);
    }

    /* Separable: a -> b along rows, b -> a along columns; 2d: a -> b. */
    for (int k = 0; k < (sep ? 2 : 1); k++) {
        gpu_pass_begin(ps, b->pass_blur + k, b->level[0].b_fbo, b->level[0].w, b->level[0].h);
        for (int i = 0; i < n; i++) {
            const struct level *l = &b->level[i];
            target(l, k == 0 ? l->b_fbo : l->a_fbo);
            bind(SB_TEX_POST_AUX, k == 0 ? l->a : l->b);
            effect_draw_fullscreen(env, b->blur_prog[k]);
        }
        gpu_pass_end(ps);
    }

    if (b->pass_up >= 0) {
        gpu_pass_begin(ps, b->pass_up, b->level[n - 2].a_fbo, b->level[n - 2].w,
                       b->level[n - 2].h);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBindSampler(SB_TEX_POST_AUX, env->linear_sampler);
        for (int i = n - 2; i >= 0; i--) {
            const struct level *l = &b->level[i], *below = &b->level[i + 1];
            target(l, sep ? l->a_fbo : l->b_fbo);
            bind(SB_TEX_POST_AUX, sep ? below->a : below->b);
            effect_draw_fullscreen(env, b->up_prog);
        }
        glBindSampler(SB_TEX_POST_AUX, 0);
        glDisable(GL_BLEND);
        gpu_pass_end(ps);
    }

    gpu_pass_begin(ps, b->pass_composite, dst_fbo, env->width, env->height);
    bind(SB_TEX_POST_SRC, src);
    bind(SB_TEX_POST_AUX, sep ? b->level[0].a : b->level[0].b);
    if (b->o.downsample > 0)
        glBindSampler(SB_TEX_POST_AUX, env->linear_sampler);
    effect_draw_fullscreen(env, b->composite_prog);
    glBindSampler(SB_TEX_POST_AUX, 0);
    gpu_pass_end(ps);
    return true;
}

const struct effect effect_bloom = {
    .info = &bloom_info,
    .create = bloom_create,
    .run = bloom_run,
    .destroy = bloom_destroy,
};
