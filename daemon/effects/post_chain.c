#define _POSIX_C_SOURCE 200809L
#include "daemon/effects/post_chain.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/effects/effect.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

struct post_chain {
    struct post_frame frame;
    const struct post_spec *post;
    const struct gpu_passes *passes;
    int first_pass;
    bool built;
    int count;
    struct {
        const struct effect *ops;
        struct effect_env env;
        void *state;
        char label[24];
    } fx[POST_MAX_EFFECTS];
    char names[POST_MAX_PASSES][POST_PASS_NAME_BYTES];
    char normal_defines[160];
    GLuint plane[2], plane_fbo[2]; /* ping-pong colour between effects */
    GLuint empty_vao, linear_sampler;
    GLuint count_prog, count_ssbo;
};

void effect_draw_fullscreen(const struct effect_env *env, GLuint prog)
{
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(prog);
    glBindVertexArray(env->empty_vao);
    GLint vp[4];
    glGetIntegerv(GL_VIEWPORT, vp); /* the effect drew its plane's size: tile that */
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, vp[2], vp[3], &t); gpu_tiles_next(env->budget, &t);)
        glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
}

bool effect_plane(const struct effect_env *env, const char *suffix, GLenum format, int w, int h,
                  GLuint *tex, GLuint *fbo, char *err, size_t errlen)
{
    char name[32];
    snprintf(name, sizeof(name), "%.15s.%.15s", env->label, suffix);
    *tex = gpu_targets_texture(env->targets, name, format, w, h, err, errlen);
    *fbo = *tex ? gpu_targets_fbo(env->targets, name, tex, 1, 0, err, errlen) : 0;
    return *fbo != 0;
}

static bool build_counter(struct post_chain *c, char *err, size_t errlen)
{
    const struct gl_stage stage = {GL_COMPUTE_SHADER, {"nonfinite.comp"}};
    c->count_prog = gl_program_build("nonfinite", &stage, 1,
                                     c->frame.hdr_format == GL_RGBA16F ? "#define HALF_TARGET 1\n"
                                                                       : NULL,
                                     err, errlen);
    if (!c->count_prog)
        return false;
    glGenBuffers(1, &c->count_ssbo);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->count_ssbo);
    glBufferData(GL_SHADER_STORAGE_BUFFER, 3 * sizeof(uint32_t), NULL, GL_DYNAMIC_READ);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    return true;
}

struct post_chain *post_chain_create(const struct post_frame *frame, const struct post_spec *post,
                                     struct gpu_passes *passes, char *err, size_t errlen)
{
    struct post_chain *c = calloc(1, sizeof(*c));
    if (!c) {
        snprintf(err, errlen, "post chain: out of memory");
        return NULL;
    }
    c->frame = *frame;
    c->post = post;
    c->first_pass = passes->count;
    c->passes = passes;
    if (!build_counter(c, err, errlen))
        goto fail;
    if (!post->count)
        return c;

    int npasses = post_spec_pass_names(post, c->names, POST_MAX_PASSES);
    if (npasses > POST_MAX_PASSES) {
        snprintf(err, errlen, "look.post needs %d passes; at most %d", npasses, POST_MAX_PASSES);
        goto fail;
    }
    for (int i = 0; i < npasses; i++)
        if (gpu_passes_add(passes, c->names[i]) < 0) {
            snprintf(err, errlen, "look.post: the harness times at most %d passes a frame",
                     GPU_MAX_PASSES);
            goto fail;
        }
    return c;
fail:
    post_chain_destroy(c);
    return NULL;
}

bool post_chain_build(struct post_chain *c, GLuint normal_tex, bool normal_octahedral, char *err,
                      size_t errlen)
{
    if (c->built)
        return true;
    c->built = true;
    const struct post_frame *frame = &c->frame;
    const struct post_spec *post = c->post;
    int first = c->first_pass;
    if (!post->count)
        return true;

    if (normal_tex)
        snprintf(c->normal_defines, sizeof(c->normal_defines), "#define HAVE_NORMAL_TEX 1\n%s",
                 normal_octahedral ? "#define NORMAL_OCTAHEDRAL 1\n" : "");
    glGenVertexArrays(1, &c->empty_vao);
    glGenSamplers(1, &c->linear_sampler);
    glSamplerParameteri(c->linear_sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glSamplerParameteri(c->linear_sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glSamplerParameteri(c->linear_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(c->linear_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

    for (int k = 0; k < 2; k++) {
        char name[16];
        snprintf(name, sizeof(name), "post.%c", 'a' + k);
        c->plane[k] = gpu_targets_texture(frame->targets, name, frame->hdr_format, frame->width,
                                          frame->height, err, errlen);
        c->plane_fbo[k] = c->plane[k] ? gpu_targets_fbo(frame->targets, name, &c->plane[k], 1, 0,
                                                        err, errlen)
                                      : 0;
        if (!c->plane_fbo[k])
            return false;
    }

    for (int i = 0; i < post->count; i++) {
        const struct effect *ops = effect_registry[post->effects[i].effect];
        const char *active[EFFECT_MAX_PASSES];
        post_effect_label(post, i, c->fx[i].label, sizeof(c->fx[i].label));
        c->fx[i].ops = ops;
        c->fx[i].env = (struct effect_env){
            .width = frame->width,
            .height = frame->height,
            .depth_tex = frame->depth,
            .normal_tex = normal_tex,
            .targets = frame->targets,
            .passes = c->passes,
            .first_pass = first,
            .label = c->fx[i].label,
            .hdr_format = frame->hdr_format,
            .budget = frame->budget,
            .empty_vao = c->empty_vao,
            .linear_sampler = c->linear_sampler,
            .normal_defines = c->normal_defines,
            .motion_tex = frame->motion,
        };
        first += ops->info->active_passes(post_effect_options(post, i), active);
        c->count = i + 1;
        if (!ops->create(&c->fx[i].env, post_effect_options(post, i), &c->fx[i].state, err,
                         errlen)) {
            c->count = i; /* destroy frees the effects made so far */
            return false;
        }
    }
    return true;
}

void post_chain_destroy(struct post_chain *c)
{
    if (!c)
        return;
    for (int i = 0; i < c->count; i++)
        c->fx[i].ops->destroy(c->fx[i].state);
    glDeleteProgram(c->count_prog);
    if (c->count_ssbo)
        glDeleteBuffers(1, &c->count_ssbo);
    if (c->empty_vao)
        glDeleteVertexArrays(1, &c->empty_vao);
    if (c->linear_sampler)
        glDeleteSamplers(1, &c->linear_sampler);
    free(c);
}

bool post_chain_run(struct post_chain *c, const struct gpu_frame_time *time, GLuint *out,
                    char *err, size_t errlen)
{
    GLuint cur = c->frame.color;
    for (int i = 0; i < c->count; i++) {
        char why[512] = "";
        if (!c->fx[i].ops->run(c->fx[i].state, &c->fx[i].env, time, cur, c->plane_fbo[i & 1],
                               why, sizeof(why))) {
            snprintf(err, errlen, "look.post %s at frame %lld: %s", c->fx[i].label,
                     (long long)time->frame, why[0] ? why : "failed");
            *out = cur;
            return false;
        }
        cur = c->plane[i & 1];
    }
    *out = cur;
    return true;
}

bool post_chain_count_nonfinite(struct post_chain *c, GLuint tex, struct post_nonfinite *out,
                                char *err, size_t errlen)
{
    static const uint32_t zero[3] = {0, 0, 0};
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->count_ssbo);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(zero), zero);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_NONFINITE, c->count_ssbo);
    glUseProgram(c->count_prog);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_HDR);
    glBindTexture(GL_TEXTURE_2D, tex);
    glDispatchCompute((GLuint)(c->frame.width + 7) / 8, (GLuint)(c->frame.height + 7) / 8, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    uint32_t counts[3] = {0, 0, 0};
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), counts);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    glUseProgram(0);
    out->nan_pixels = counts[0];
    out->inf_pixels = counts[1];
    out->overflow_pixels = counts[2];
    return !gl_error_take("counting non-finite pixels", err, errlen);
}
