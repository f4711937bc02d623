#include "daemon/techniques/shared/culled.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"
#include "daemon/techniques/shared/depth_prepass.h"
#include "daemon/techniques/shared/gbuffer.h"
#include "daemon/techniques/shared/heat.h"

struct culled {
    struct culled_config cfg;
    struct gbuffer gbuffer;
    struct depth_prepass prepass;
    struct light_grid grid;
    struct heat heat;
    /* [0] once a pixel; [1] (deferred at msaa > 1) once a sample, for the
     * edge pixels. */
    struct scene_program shade[2];
    GLint heat_loc[2];
    int runs;
    GLuint light_fbo, empty_vao;
    int pass_geometry, pass_edges, pass_binning, pass_shading;
};

/* The index of the pass named name in the frame's passes (the
 * technique's own come first, in its info's order), or -1. */
static int pass_named(const struct gpu_passes *p, const char *name)
{
    for (int i = 0; i < p->count; i++)
        if (strcmp(p->names[i], name) == 0)
            return i;
    return -1;
}

bool culled_create(const struct technique_env *env, const struct culled_config *cfg,
                   void **state, char *err, size_t errlen)
{
    struct culled *c = calloc(1, sizeof(*c));
    if (!c) {
        snprintf(err, errlen, "%s: out of memory", cfg->grid.technique);
        return false;
    }
    *state = c;
    c->cfg = *cfg;
    /* Each pass by the name the technique's info declares it under (the
     * deferred ones time their edge pass, MSAA, after the g-buffer). */
    c->pass_geometry = pass_named(env->passes, cfg->deferred ? "gbuffer" : "depth_prepass");
    c->pass_edges = cfg->deferred ? pass_named(env->passes, "edges") : -1;
    c->pass_binning = pass_named(env->passes, "binning");
    c->pass_shading = pass_named(env->passes, cfg->deferred ? "lighting" : "shading");
    if (c->pass_geometry < 0 || (cfg->deferred && c->pass_edges < 0) || c->pass_binning < 0 ||
        c->pass_shading < 0) {
        snprintf(err, errlen, "%s: its info must declare the passes %s", cfg->grid.technique,
                 cfg->deferred ? "gbuffer, edges, binning and lighting"
                               : "depth_prepass, binning and shading");
        goto fail;
    }
    c->runs = 1;
    if (!light_grid_init(&c->grid, env, &cfg->grid, err, errlen) ||
        !heat_init(&c->heat, env, err, errlen))
        goto fail;
    GLuint prog = 0;
    if (cfg->deferred) {
        if (!gbuffer_init(&c->gbuffer, env, &cfg->gbuffer, err, errlen))
            goto fail;
        c->light_fbo = gbuffer_light_fbo(&c->gbuffer, env, "culled.light", err, errlen);
        const struct gl_stage stages[] = {
            {GL_VERTEX_SHADER, {"fullscreen.vert"}},
            {GL_FRAGMENT_SHADER, {"culled_deferred.frag"}},
        };
        if (!c->light_fbo)
            goto fail;
        c->runs = gbuffer_shading_runs(&c->gbuffer);
        for (int run = 1; run < c->runs; run++) {
            GLuint p = gbuffer_program(&c->gbuffer, "culled deferred lighting", stages, 2, "",
                                       true, err, errlen);
            if (!p)
                goto fail;
            c->shade[run] = gpu_scene_program(env->gpu, p);
            c->heat_loc[run] = heat_location(p);
        }
        if (!(prog = gbuffer_program(&c->gbuffer, "culled deferred lighting", stages, 2, "",
                                     false, err, errlen)))
            goto fail;
        glGenVertexArrays(1, &c->empty_vao);
    } else {
        const struct gl_stage stages[] = {
            {GL_VERTEX_SHADER, {"scene.vert"}},
            {GL_FRAGMENT_SHADER, {"culled_forward.frag"}},
        };
        if (!depth_prepass_init(&c->prepass, env, err, errlen) ||
            !(prog = gl_program_build("culled forward shading", stages, 2, env->defines, err,
                                      errlen)))
            goto fail;
    }
    c->shade[0] = gpu_scene_program(env->gpu, prog);
    c->shade[0].after_prepass = !c->cfg.deferred;
    c->heat_loc[0] = heat_location(prog);
    return true;
fail:
    culled_destroy(c);
    *state = NULL;
    return false;
}

static void binning(struct culled *c, const struct technique_env *env, int64_t frame)
{
    gpu_pass_begin(env->passes, c->pass_binning, env->output_fbo, env->width, env->height);
    light_grid_build(&c->grid, env, frame);
    gpu_pass_end(env->passes);
}

bool culled_render(void *state, const struct technique_env *env, int64_t frame, char *err,
                   size_t errlen)
{
    struct culled *c = state;
    bool tiles = c->cfg.grid.kind == LIGHT_GRID_TILES;
    bool heat = heat_wanted(env, frame);
    gpu_scene_set_light_rows(env->gpu, &frame, 1);
    for (int run = 0; run < c->runs; run++)
        heat_enable(c->shade[run].prog, c->heat_loc[run], heat);
    if (!tiles)
        binning(c, env, frame);
    if (c->cfg.deferred) {
        gbuffer_draw(&c->gbuffer, env, c->pass_geometry);
        gbuffer_edges_draw(&c->gbuffer, env, c->pass_edges, frame);
    } else
        depth_prepass_draw(&c->prepass, env, c->pass_geometry);
    if (tiles)
        binning(c, env, frame);

    if (c->cfg.deferred) {
        gpu_pass_begin(env->passes, c->pass_shading, c->light_fbo, env->width, env->height);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        gbuffer_bind(&c->gbuffer, env);
        /* Per-sample shading adds each sample's evaluations: from zero. */
        if (heat && c->runs > 1)
            heat_clear(&c->heat, c->light_fbo);
        else if (heat)
            heat_bind(&c->heat);
        light_grid_bind(&c->grid);
        glBindVertexArray(c->empty_vao);
        struct gpu_tiles t;
        for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
             gpu_tiles_next(env->budget, &t);)
            for (int run = 0; run < c->runs; run++) {
                gbuffer_shading_state(&c->gbuffer, run);
                gpu_scene_bind(env->gpu, &c->shade[run]);
                glDrawArrays(GL_TRIANGLES, 0, 3);
            }
        glBindVertexArray(0);
    } else {
        gpu_pass_begin(env->passes, c->pass_shading, env->output_fbo, env->width, env->height);
        depth_prepass_shading_state();
        if (heat)
            heat_clear(&c->heat, env->output_fbo);
        gpu_scene_bind(env->gpu, &c->shade[0]);
        light_grid_bind(&c->grid);
        struct gpu_tiles t;
        for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
             gpu_tiles_next(env->budget, &t);)
            gpu_scene_draw(env->gpu, &c->shade[0]);
    }
    if (heat)
        heat_done();
    gpu_pass_end(env->passes);
    return technique_keep_going(env, err, errlen);
}

json_t *culled_describe(void *state)
{
    struct culled *c = state;
    json_t *d = light_grid_describe(&c->grid);
    if (d && c->cfg.deferred)
        json_object_set_new(d, "gbuffer", gbuffer_describe(&c->gbuffer));
    return d;
}

bool culled_verify(void *state, char *err, size_t errlen)
{
    struct culled *c = state;
    return light_grid_verify(&c->grid, err, errlen);
}

void culled_destroy(void *state)
{
    struct culled *c = state;
    if (!c)
        return;
    for (int run = 0; run < 2; run++)
        if (c->shade[run].prog)
            glDeleteProgram(c->shade[run].prog);
    if (c->empty_vao)
        glDeleteVertexArrays(1, &c->empty_vao);
    gbuffer_finish(&c->gbuffer);
    depth_prepass_finish(&c->prepass);
    light_grid_finish(&c->grid);
    free(c);
}
