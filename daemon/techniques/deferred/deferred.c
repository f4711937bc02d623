/* Deferred shading (seed 001): the g-buffer, then lighting: an ambient pass
 * over every pixel, and each light added with additive blending over the
 * pixels its bound covers (deferred.light_bounds):
 *   scissor_tight   the screen rectangle of the light sphere's silhouette;
 *   scissor_loose   the projected box of the corners of its world AABB;
 *   volume          the sphere itself rasterised (back faces, no depth test);
 *   fullscreen      every pixel.
 * Each bound is drawn as geometry in one instanced draw for all lights (a
 * rectangle is the scissor rectangle drawn rather than set per light, which
 * would cost a draw call per light): the same pixels, one call. Blending
 * adds lights in index order, as forward's loop sums them. */
#include <stdio.h>
#include <stdlib.h>

#include "daemon/gpu/glutil.h"
#include "daemon/techniques/deferred/deferred_info.h"
#include "daemon/techniques/shared/gbuffer.h"
#include "daemon/techniques/shared/heat.h"

enum { PASS_GBUFFER, PASS_EDGES, PASS_LIGHTING };
/* deferred_light.vert's sphere: 16 segments, 8 rings. */
enum { VOLUME_VERTICES = 16 * 8 * 6, RECT_VERTICES = 6 };

static const char *const bounds_defines[] = {
    "#define DEFERRED_BOUNDS_SCISSOR_TIGHT 1\n",
    "#define DEFERRED_BOUNDS_SCISSOR_LOOSE 1\n",
    "#define DEFERRED_BOUNDS_VOLUME 1\n",
    "#define DEFERRED_BOUNDS_FULLSCREEN 1\n",
};

struct deferred {
    struct gbuffer gbuffer;
    struct heat heat;
    /* [0] once a pixel; [1] once a sample, for the edge pixels at msaa > 1. */
    struct scene_program ambient[2], light[2];
    GLint ambient_heat[2], light_heat[2];
    GLuint light_fbo, empty_vao;
    int bounds;
};

static void deferred_destroy(void *state);

static bool deferred_create(const struct technique_env *env, void **state, char *err,
                            size_t errlen)
{
    const struct deferred_options *o = env->options;
    struct deferred *d = calloc(1, sizeof(*d));
    if (!d) {
        snprintf(err, errlen, "deferred: out of memory");
        return false;
    }
    *state = d;
    d->bounds = o->light_bounds;
    if (!gbuffer_init(&d->gbuffer, env, &o->gbuffer, err, errlen) ||
        !heat_init(&d->heat, env, err, errlen))
        goto fail;
    d->light_fbo = gbuffer_light_fbo(&d->gbuffer, env, "deferred.light", err, errlen);
    if (!d->light_fbo)
        goto fail;
    const struct gl_stage ambient[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"deferred_ambient.frag"}},
    };
    const struct gl_stage light[] = {
        {GL_VERTEX_SHADER, {"deferred_light.vert"}},
        {GL_FRAGMENT_SHADER, {"deferred_light.frag"}},
    };
    for (int run = 0; run < gbuffer_shading_runs(&d->gbuffer); run++) {
        GLuint ambient_prog = gbuffer_program(&d->gbuffer, "deferred ambient", ambient, 2,
                                              bounds_defines[d->bounds], run == 1, err, errlen);
        if (!ambient_prog)
            goto fail;
        d->ambient[run] = gpu_scene_program(env->gpu, ambient_prog);
        GLuint light_prog = gbuffer_program(&d->gbuffer, "deferred lights", light, 2,
                                            bounds_defines[d->bounds], run == 1, err, errlen);
        if (!light_prog)
            goto fail;
        d->light[run] = gpu_scene_program(env->gpu, light_prog);
        d->ambient_heat[run] = heat_location(ambient_prog);
        d->light_heat[run] = heat_location(light_prog);
    }
    glGenVertexArrays(1, &d->empty_vao);
    return true;
fail:
    deferred_destroy(d);
    *state = NULL;
    return false;
}

static bool deferred_render(void *state, const struct technique_env *env, int64_t frame,
                            char *err, size_t errlen)
{
    struct deferred *d = state;
    bool heat = heat_wanted(env, frame);
    gpu_scene_set_light_rows(env->gpu, &frame, 1);
    int runs = gbuffer_shading_runs(&d->gbuffer);
    for (int run = 0; run < runs; run++) {
        heat_enable(d->ambient[run].prog, d->ambient_heat[run], heat);
        heat_enable(d->light[run].prog, d->light_heat[run], heat);
    }
    gbuffer_draw(&d->gbuffer, env, PASS_GBUFFER);
    gbuffer_edges_draw(&d->gbuffer, env, PASS_EDGES, frame);

    gpu_pass_begin(env->passes, PASS_LIGHTING, d->light_fbo, env->width, env->height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    gbuffer_bind(&d->gbuffer, env);
    if (heat)
        heat_bind(&d->heat); /* the ambient pass zeroes every pixel's count */
    glBindVertexArray(d->empty_vao);
    /* Each tile gets the ambient term, then every light in index order:
     * what each pixel sums is the same as in one draw of each. At msaa > 1
     * the pixels the edge pass left unmarked are shaded once, the marked
     * ones once a sample (the stencil keeps the two runs apart). */
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
         gpu_tiles_next(env->budget, &t);) {
        for (int run = 0; run < runs; run++) {
            gbuffer_shading_state(&d->gbuffer, run);
            glDisable(GL_BLEND);
            glDisable(GL_CULL_FACE);
            gpu_scene_bind(env->gpu, &d->ambient[run]);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            if (env->scene->light_count == 0)
                continue;
            if (heat)
                glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
            glEnable(GL_BLEND);
            glBlendFunc(GL_ONE, GL_ONE);
            if (d->bounds == LIGHT_BOUNDS_VOLUME) {
                /* The far side of each sphere covers its projection once,
                 * whether the eye is outside the sphere or inside it. */
                glEnable(GL_CULL_FACE);
                glCullFace(GL_FRONT);
            }
            gpu_scene_bind(env->gpu, &d->light[run]);
            glDrawArraysInstanced(GL_TRIANGLES, 0,
                                  d->bounds == LIGHT_BOUNDS_VOLUME ? VOLUME_VERTICES
                                                                   : RECT_VERTICES,
                                  env->scene->light_count);
        }
    }
    glBindVertexArray(0);
    if (heat)
        heat_done();
    gpu_pass_end(env->passes);
    return technique_keep_going(env, err, errlen);
}

static json_t *deferred_describe(void *state)
{
    struct deferred *d = state;
    return json_pack("{s:s, s:o, s:s}", "light_bounds", light_bounds_choices[d->bounds],
                     "gbuffer", gbuffer_describe(&d->gbuffer), "light_draw",
                     "one instanced draw of every light's bound, blended additively");
}

static void deferred_destroy(void *state)
{
    struct deferred *d = state;
    if (!d)
        return;
    for (int run = 0; run < 2; run++) {
        if (d->ambient[run].prog)
            glDeleteProgram(d->ambient[run].prog);
        if (d->light[run].prog)
            glDeleteProgram(d->light[run].prog);
    }
    if (d->empty_vao)
        glDeleteVertexArrays(1, &d->empty_vao);
    gbuffer_finish(&d->gbuffer);
    free(d);
}

const struct technique technique_deferred = {
    .info = &deferred_info,
    .create = deferred_create,
    .render = deferred_render,
    .describe = deferred_describe,
    .destroy = deferred_destroy,
};
