/* Omni shadow maps: see shadows.h. Casters are drawn one instance at a time
 * (an explicit uniform per draw), culled against the light's sphere and
 * each face's frustum on the CPU as seed 002 culls by bounding boxes; back
 * faces go into the maps (front faces culled), so that lit surfaces are
 * compared against the far side of their own object and the bias only has
 * to cover contact. */
#define _POSIX_C_SOURCE 200809L
#include "daemon/look/shadows.h"

#include <epoxy/gl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"
#include "daemon/lighting/cube_faces.h"
#include "daemon/lighting/shadow_plan.h"
#include "daemon/scene/light_shape.h"

static const float SHADOW_NEAR = 0.02f;

/* shaders/common/shadows.glsl, ShadowLight (std430). A directional light's
 * row: params size (0: unshadowed), 0, 0, its map's index. */
struct shadow_light_gpu {
    float pos_far[4];
    float params[4]; /* size, widen, near, layer */
    int32_t faces[12];
};

/* shaders/common/shadows.glsl, SunShadow (std430): a directional light's
 * fitted projection; params: size, one texel in world units, the depth
 * range in world units, the array layer. */
struct sun_shadow_gpu {
    float view_proj[16];
    float params[4];
};

enum { MAX_DROPPED_LISTED = 64 };

struct look_shadows {
    struct shadow_spec spec;
    const struct scene *scene;
    struct gpu_scene *gpu;
    struct shadow_plan plan;
    GLuint prog, fbo, depth, ssbo;
    GLint material_loc; /* asset scenes: alpha-masked casters read their material */
    struct shadow_light_gpu *rows;
    int *casters; /* scratch: instances within the light */
    int border;
    double bytes;
    /* Timed frames. */
    int frames;
    double mapped_sum, texels_sum, faces_sum, draws_sum, dropped_sum;
    int mapped_min, mapped_max, dropped_max, culled_last, no_casters_last;
    double texels_max;
    int frames_with_drops;
    int dropped_lights[MAX_DROPPED_LISTED], ndropped_lights, dropped_distinct;
    unsigned char *ever_dropped;
    int tile_hist[16]; /* faces by log2 size at the first timed frame */
    /* Directional lights: the first SHADOW_MAX_SUNS by index get a layer of
     * sun_depth (sun_of[light], -1 for others); the scene's bounds and the
     * lights' directions never change, so the projections are fitted once. */
    GLuint sun_depth, sun_fbo, sun_ssbo;
    int suns, sun_size, directional_total;
    int *sun_of;
    struct sun_shadow_gpu sun_rows[SHADOW_MAX_SUNS];
};

/* The directional lights' maps: a depth array with a layer for each of the
 * first SHADOW_MAX_SUNS (one 1 x 1 layer when there are none, so that the
 * lighting library's sampler always has a texture), and their fitted
 * projections. */
static bool create_suns(struct look_shadows *sh, char *err, size_t errlen)
{
    const struct scene *s = sh->scene;
    for (int i = 0; i < s->light_count; i++) {
        sh->sun_of[i] = -1;
        if (s->lights[i].type != SCENE_LIGHT_DIRECTIONAL)
            continue;
        sh->directional_total++;
        if (sh->suns == SHADOW_MAX_SUNS)
            continue;
        int k = sh->suns++;
        sh->sun_of[i] = k;
        struct sun_shadow_gpu *row = &sh->sun_rows[k];
        sh->sun_size = shadow_sun_size(&sh->spec);
        shadow_sun_fit(&s->bounds, s->lights[i].direction, sh->sun_size, row->view_proj,
                       &row->params[1], &row->params[2]);
        row->params[0] = (float)sh->sun_size;
        row->params[3] = (float)k;
    }
    int size = sh->suns ? sh->sun_size : 1, layers = sh->suns ? sh->suns : 1;
    glGenTextures(1, &sh->sun_depth);
    glBindTexture(GL_TEXTURE_2D_ARRAY, sh->sun_depth);
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_DEPTH_COMPONENT32F, size, size, layers);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
    sh->bytes += 4.0 * size * size * layers;
    glGenFramebuffers(1, &sh->sun_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, sh->sun_fbo);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, sh->sun_depth, 0, 0);
    bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!complete) {
        snprintf(err, errlen, "look.shadows: the directional lights' framebuffer is incomplete");
        return false;
    }
    glGenBuffers(1, &sh->sun_ssbo);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, sh->sun_ssbo);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)sizeof(sh->sun_rows), sh->sun_rows,
                 GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    return true;
}

/* Binds a caster's mesh and, in asset scenes, its material (an alpha-masked
 * caster cuts its holes with its own textures) and face culling (a
 * double-sided one casts from both faces; the others keep the pass's
 * front-face culling). */
static void bind_caster(struct look_shadows *sh, int mesh)
{
    glBindVertexArray(sh->gpu->vao[mesh]);
    if (!sh->gpu->mesh_material)
        return;
    gpu_scene_bind_material(sh->gpu, mesh, sh->material_loc);
    if (sh->gpu->mesh_material[mesh].double_sided)
        glDisable(GL_CULL_FACE);
    else
        glEnable(GL_CULL_FACE);
}

/* Directional map k: every caster (the ground and blended meshes never
 * cast), back faces, into its layer. */
static void render_sun(struct look_shadows *sh, int k)
{
    const struct scene *s = sh->scene;
    glBindFramebuffer(GL_FRAMEBUFFER, sh->sun_fbo);
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, sh->sun_depth, 0, k);
    glViewport(0, 0, sh->sun_size, sh->sun_size);
    glClear(GL_DEPTH_BUFFER_BIT);
    glUniformMatrix4fv(SB_LOC_SHADOW_VIEW_PROJ, 1, GL_FALSE, sh->sun_rows[k].view_proj);
    int bound_mesh = -1;
    for (int c = 0; c < s->instance_count; c++) {
        const struct scene_instance *in = &s->instances[c];
        if (in->mesh == SCENE_MESH_PLANE || in->mesh >= s->asset_blend_first)
            continue;
        if ((int)in->mesh != bound_mesh) {
            bound_mesh = (int)in->mesh;
            bind_caster(sh, bound_mesh);
        }
        glUniform1i(SB_LOC_SHADOW_INSTANCE, c);
        glDrawElements(GL_TRIANGLES, (GLsizei)s->meshes[in->mesh].index_count, GL_UNSIGNED_INT,
                       NULL);
        sh->draws_sum += 1;
    }
}

struct look_shadows *look_shadows_create(const struct shadow_spec *spec,
                                               const struct scene *s, struct gpu_scene *gpu,
                                               const struct gpu_caps *caps, char *err,
                                               size_t errlen)
{
    struct look_shadows *sh = calloc(1, sizeof(*sh));
    if (!sh) {
        snprintf(err, errlen, "look.shadows: out of memory");
        return NULL;
    }
    sh->spec = *spec;
    sh->scene = s;
    sh->gpu = gpu;
    sh->border = spec->layout == SHADOW_LAYOUT_ATLAS ? shadow_border(spec->pcf) : 0;
    sh->mapped_min = s->light_count;
    size_t n = (size_t)(s->light_count ? s->light_count : 1);
    sh->rows = calloc(n, sizeof(*sh->rows));
    sh->casters = calloc((size_t)(s->instance_count ? s->instance_count : 1), sizeof(int));
    sh->ever_dropped = calloc(n, 1);
    sh->sun_of = calloc(n, sizeof(int));
    if (!sh->rows || !sh->casters || !sh->ever_dropped || !sh->sun_of ||
        !shadow_plan_init(&sh->plan, s->light_count, spec)) {
        snprintf(err, errlen, "look.shadows: out of memory for %d lights", s->light_count);
        goto fail;
    }
    int limit = spec->layout == SHADOW_LAYOUT_ATLAS ? caps->max_texture_size : caps->max_texture_size;
    if (spec->atlas > limit || spec->tile > limit) {
        snprintf(err, errlen, "look.shadows.atlas %d exceeds this device's GL_MAX_TEXTURE_SIZE %d",
                 spec->atlas, limit);
        goto fail;
    }
    const struct gl_stage stages[] = {{GL_VERTEX_SHADER, {"shadow.vert"}},
                                      {GL_FRAGMENT_SHADER, {"shadow.frag"}}};
    /* Asset scenes: casters with an alpha mask cast what they show. */
    if (!(sh->prog = gl_program_build("shadows", stages, 2,
                                      s->asset ? "#define SCENE_TEXTURED 1\n" : NULL, err,
                                      errlen)))
        goto fail;
    sh->material_loc = glGetUniformLocation(sh->prog, "u_material");
    glGenTextures(1, &sh->depth);
    GLenum target = spec->layout == SHADOW_LAYOUT_ATLAS ? GL_TEXTURE_2D : GL_TEXTURE_CUBE_MAP_ARRAY;
    glBindTexture(target, sh->depth);
    if (spec->layout == SHADOW_LAYOUT_ATLAS) {
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT32F, spec->atlas, spec->atlas);
        sh->bytes = 4.0 * spec->atlas * spec->atlas;
    } else {
        int layers = sh->plan.layers > 0 ? sh->plan.layers : 1;
        glTexStorage3D(GL_TEXTURE_CUBE_MAP_ARRAY, 1, GL_DEPTH_COMPONENT32F, spec->tile, spec->tile,
                       6 * layers);
        sh->bytes = 4.0 * 6.0 * layers * spec->tile * spec->tile;
    }
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &sh->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, sh->fbo);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (spec->layout == SHADOW_LAYOUT_ATLAS) {
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, sh->depth, 0);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
            snprintf(err, errlen, "look.shadows: the atlas framebuffer is incomplete");
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
            goto fail;
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glGenBuffers(1, &sh->ssbo);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, sh->ssbo);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * sizeof(*sh->rows)), NULL,
                 GL_DYNAMIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    if (!create_suns(sh, err, errlen))
        goto fail;
    return sh;
fail:
    look_shadows_destroy(sh);
    return NULL;
}

/* Whether a sphere (centre relative to the light d, radius r) reaches the
 * face's frustum (widened by w): inside all four side planes, or nearly. */
static bool sphere_meets_face(const float d[3], float r, const float fw[3], const float sa[3],
                              const float ta[3], float w)
{
    float f = d[0] * fw[0] + d[1] * fw[1] + d[2] * fw[2];
    if (f < -r)
        return false;
    float s = d[0] * sa[0] + d[1] * sa[1] + d[2] * sa[2];
    float t = d[0] * ta[0] + d[1] * ta[1] + d[2] * ta[2];
    float norm = sqrtf(w * w + 1.0f);
    /* Planes f w -+ s >= 0 and f w -+ t >= 0, normalised. */
    return (f * w - s) / norm >= -r && (f * w + s) / norm >= -r && (f * w - t) / norm >= -r &&
           (f * w + t) / norm >= -r;
}

static void draw_casters(struct look_shadows *sh, int ncasters, const float light[3], int face,
                         float widen)
{
    const struct scene *s = sh->scene;
    float fw[3], sa[3], ta[3];
    cube_face_axes(face, fw, sa, ta);
    int bound_mesh = -1;
    for (int c = 0; c < ncasters; c++) {
        int i = sh->casters[c];
        const struct scene_instance *in = &s->instances[i];
        float d[3] = {in->pos[0] - light[0], in->pos[1] - light[1], in->pos[2] - light[2]};
        if (!sphere_meets_face(d, scene_instance_bound(s, i), fw, sa, ta, widen))
            continue;
        if ((int)in->mesh != bound_mesh) {
            bound_mesh = (int)in->mesh;
            bind_caster(sh, bound_mesh);
        }
        glUniform1i(SB_LOC_SHADOW_INSTANCE, i);
        glDrawElements(GL_TRIANGLES, (GLsizei)s->meshes[in->mesh].index_count, GL_UNSIGNED_INT,
                       NULL);
        sh->draws_sum += 1;
    }
}

bool look_shadows_render(struct look_shadows *sh, const struct gpu_passes *passes, int pass,
                            int64_t frame, bool timed, struct gpu_budget *budget, char *err,
                            size_t errlen)
{
    const struct scene *s = sh->scene;
    const struct shadow_spec *spec = &sh->spec;
    struct shadow_plan *p = &sh->plan;
    if (!shadow_plan_frame(p, s, spec, frame, err, errlen))
        return false;
    bool atlas = spec->layout == SHADOW_LAYOUT_ATLAS;
    gpu_pass_begin(passes, pass, sh->fbo, atlas ? spec->atlas : spec->tile,
                   atlas ? spec->atlas : spec->tile);
    glCullFace(GL_FRONT);
    glUseProgram(sh->prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_INSTANCES, sh->gpu->instance_buffer);
    if (sh->gpu->material_buffer)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_MATERIALS, sh->gpu->material_buffer);
    if (atlas)
        glEnable(GL_SCISSOR_TEST);
    int faces = 0; /* drawn this frame: six a point light, fewer a spot */
    double draws_before = sh->draws_sum;
    gpu_loop_begin(budget);
    for (int i = 0; i < p->lights && gpu_loop_step(budget); i++) {
        const struct shadow_light_plan *l = &p->light[i];
        struct shadow_light_gpu *row = &sh->rows[i];
        memset(row, 0, sizeof(*row));
        if (l->status == SHADOW_DIRECTIONAL && sh->sun_of[i] >= 0) {
            /* Its map is drawn after the omni faces. Past SHADOW_MAX_SUNS:
             * size 0, unshadowed (counted). */
            row->params[0] = (float)sh->sun_size;
            row->params[3] = (float)sh->sun_of[i];
        }
        if (l->status != SHADOW_MAPPED)
            continue;
        float radius = s->lights[i].radius;
        float widen = shadow_face_widen(l->size, sh->border);
        memcpy(row->pos_far, l->pos, sizeof(l->pos));
        row->pos_far[3] = radius;
        row->params[0] = (float)l->size;
        row->params[1] = widen;
        row->params[2] = SHADOW_NEAR;
        row->params[3] = (float)l->x[0];
        for (int f = 0; f < 6; f++)
            row->faces[f * 2] = l->x[f], row->faces[f * 2 + 1] = l->y[f];
        /* Casters within the light's reach (the ground never casts). */
        int ncasters = 0;
        for (int k = 0; k < s->instance_count; k++) {
            const struct scene_instance *in = &s->instances[k];
            /* Blended (glass) meshes cast none: they would cast as opaque. */
            if (in->mesh == SCENE_MESH_PLANE || in->mesh >= s->asset_blend_first)
                continue;
            /* A spot light's casters are those its cone reaches. */
            if (scene_light_reaches(&s->lights[i], l->pos, in->pos, scene_instance_bound(s, k)))
                sh->casters[ncasters++] = k;
        }
        const struct scene_light *light = &s->lights[i];
        for (int f = 0; f < 6; f++) {
            /* A spot renders only the faces its cone reaches (one, for a
             * spot of up to 30 degrees along an axis). */
            if (light->type == SCENE_LIGHT_SPOT &&
                !shadow_cone_meets_face(light->direction, light->cos_outer, f, widen))
                continue;
            faces++;
            float vp[16];
            cube_face_view_proj(f, l->pos, widen, SHADOW_NEAR, radius, vp);
            if (atlas) {
                glViewport(l->x[f], l->y[f], l->size, l->size);
                glScissor(l->x[f], l->y[f], l->size, l->size);
            } else {
                glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, sh->depth, 0,
                                          l->x[0] * 6 + f);
            }
            glClear(GL_DEPTH_BUFFER_BIT);
            glUniformMatrix4fv(SB_LOC_SHADOW_VIEW_PROJ, 1, GL_FALSE, vp);
            draw_casters(sh, ncasters, l->pos, f, widen);
        }
    }
    gpu_loop_end(budget);
    glDisable(GL_SCISSOR_TEST);
    for (int k = 0; k < sh->suns; k++)
        render_sun(sh, k);
    if (sh->suns)
        glBindFramebuffer(GL_FRAMEBUFFER, sh->fbo);
    glBindVertexArray(0);
    glCullFace(GL_BACK);
    if (gpu_budget_stopped(budget)) {
        gpu_pass_end(passes);
        snprintf(err, errlen, "stopped");
        return false;
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, sh->ssbo);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                    (GLsizeiptr)((size_t)p->lights * sizeof(*sh->rows)), sh->rows);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    gpu_pass_end(passes);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_SHADOW_LIGHTS, sh->ssbo);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_SHADOW_SUNS, sh->sun_ssbo);
    glActiveTexture(GL_TEXTURE0 + (atlas ? SB_TEX_SHADOW_ATLAS : SB_TEX_SHADOW_CUBES));
    glBindTexture(atlas ? GL_TEXTURE_2D : GL_TEXTURE_CUBE_MAP_ARRAY, sh->depth);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_SHADOW_SUNS);
    glBindTexture(GL_TEXTURE_2D_ARRAY, sh->sun_depth);
    glActiveTexture(GL_TEXTURE0);

    if (!timed) {
        sh->draws_sum = draws_before;
        return true;
    }
    if (sh->frames == 0)
        for (int i = 0; i < p->lights; i++)
            if (p->light[i].status == SHADOW_MAPPED) {
                int lg = 0;
                while ((1 << (lg + 1)) <= p->light[i].size && lg < 15)
                    lg++;
                sh->tile_hist[lg] += 6;
            }
    sh->frames++;
    sh->mapped_sum += p->mapped;
    sh->texels_sum += p->texels;
    sh->faces_sum += faces;
    sh->dropped_sum += p->dropped;
    sh->mapped_min = p->mapped < sh->mapped_min ? p->mapped : sh->mapped_min;
    sh->mapped_max = p->mapped > sh->mapped_max ? p->mapped : sh->mapped_max;
    sh->dropped_max = p->dropped > sh->dropped_max ? p->dropped : sh->dropped_max;
    sh->texels_max = p->texels > sh->texels_max ? p->texels : sh->texels_max;
    sh->culled_last = p->culled;
    sh->no_casters_last = p->no_casters;
    if (p->dropped) {
        sh->frames_with_drops++;
        for (int i = 0; i < p->lights; i++)
            if (p->light[i].status == SHADOW_DROPPED && !sh->ever_dropped[i]) {
                sh->ever_dropped[i] = 1;
                sh->dropped_distinct++;
                if (sh->ndropped_lights < MAX_DROPPED_LISTED)
                    sh->dropped_lights[sh->ndropped_lights++] = i;
            }
    }
    return true;
}

json_t *look_shadows_describe(const struct look_shadows *sh)
{
    const struct shadow_spec *spec = &sh->spec;
    double n = sh->frames > 0 ? sh->frames : 1;
    double capacity = (double)spec->atlas * spec->atlas;
    json_t *dropped = json_array(), *tiles = json_object();
    for (int i = 0; i < sh->ndropped_lights; i++)
        json_array_append_new(dropped, json_integer(sh->dropped_lights[i]));
    for (int lg = 0; lg < 16; lg++)
        if (sh->tile_hist[lg]) {
            char key[16];
            snprintf(key, sizeof(key), "%d", 1 << lg);
            json_object_set_new(tiles, key, json_integer(sh->tile_hist[lg]));
        }
    return json_pack(
        "{s:s, s:i, s:o, s:f, s:i, s:i, s:{s:f, s:i, s:i}, s:{s:f, s:f, s:f, s:f}, s:f, s:f, "
        "s:o, s:{s:s, s:i, s:f, s:i, s:i, s:o, s:s}, s:i, s:i, s:{s:i, s:i, s:i, s:s}, "
        "s:{s:i, s:s}}",
        "layout", shadow_layout_names[spec->layout], "atlas", spec->atlas, "tile",
        spec->tile ? json_integer(spec->tile) : json_string("auto"), "bytes", sh->bytes, "pcf",
        spec->pcf, "border_texels", sh->border, "lights_mapped", "mean", sh->mapped_sum / n, "min",
        sh->frames ? sh->mapped_min : 0, "max", sh->mapped_max, "atlas_use", "texels_mean",
        sh->texels_sum / n, "texels_max", sh->texels_max, "fraction_mean",
        sh->texels_sum / n / capacity, "fraction_max", sh->texels_max / capacity, "faces_per_frame",
        sh->faces_sum / n, "caster_draws_per_frame", sh->draws_sum / n, "faces_by_size_at_frame_1",
        tiles, RK_OVERFLOW, "policy", shadow_overflow_names[spec->overflow], RK_FRAMES_WITH_DROPS,
        sh->frames_with_drops, "dropped_mean", sh->dropped_sum / n, "dropped_max",
        sh->dropped_max, "lights_dropped", sh->dropped_distinct, "lights", dropped, "rule",
        "lights that needed a map but did not fit the atlas at min_tile, least important "
        "first; 'lights' lists the first 64 of them by index",
        "lights_culled_last_frame", sh->culled_last, "lights_without_casters_last_frame",
        sh->no_casters_last, "directional", "lights", sh->directional_total, "mapped", sh->suns,
        "map_size", sh->sun_size, "rule",
        "each of the first 4 directional lights (by index) gets an orthographic map, "
        "map_size texels square (half the atlas edge, 256 to 4096), fitted to the scene's "
        "bounds; PCF, bias and normal offset as the omni maps'",
        "skipped_lights", "directional", sh->directional_total - sh->suns, "note",
        "directional lights past the first 4 light unshadowed");
}

void look_shadows_destroy(struct look_shadows *sh)
{
    if (!sh)
        return;
    if (sh->prog)
        glDeleteProgram(sh->prog);
    glDeleteTextures(1, &sh->depth);
    glDeleteFramebuffers(1, &sh->fbo);
    glDeleteBuffers(1, &sh->ssbo);
    glDeleteTextures(1, &sh->sun_depth);
    glDeleteFramebuffers(1, &sh->sun_fbo);
    glDeleteBuffers(1, &sh->sun_ssbo);
    free(sh->sun_of);
    shadow_plan_finish(&sh->plan);
    free(sh->rows);
    free(sh->casters);
    free(sh->ever_dropped);
    free(sh);
}
