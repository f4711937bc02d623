/* The visibility buffer (Burns and Hunt 2013, "The Visibility Buffer: A
 * Cache-Friendly Approach to Deferred Shading"): the geometry is drawn once
 * into a buffer of instance and triangle ids (32 bits a pixel when they
 * fit, else 64) over the output's depth, and one full-screen pass shades
 * every pixel: it fetches the pixel's triangle from the technique's copy of
 * the meshes, rebuilds the attributes and their derivatives at the pixel
 * (vis_fetch.glsl) and lights them with the lighting library, so that it
 * agrees with forward as the deferred family does, with a fraction of a
 * g-buffer's bytes. Passes:
 *   binning     lights="clustered": the froxel grid of the clustered
 *               techniques (shared/light_grid.c); else empty;
 *   visibility  the ids and the depth;
 *   classify    MSAA: the pixels whose samples hold more than one triangle
 *               marked in a stencil (shading runs once a sample there, once
 *               a pixel elsewhere); asset scenes: each pixel's material key
 *               written as the depth of a key target; else empty;
 *   shading     one full-screen draw, or in asset scenes one a material
 *               (its textures bound; the key's early GL_EQUAL depth test
 *               keeps it to its pixels: "material depth", as Nanite
 *               classifies), each pixel lit once (each sample at edges).
 * Render thread only. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"
#include "daemon/techniques/shared/light_grid.h"
#include "daemon/techniques/technique.h"
#include "daemon/techniques/visibility_buffer/visibility_buffer_info.h"

enum { PASS_BINNING, PASS_VISIBILITY, PASS_CLASSIFY, PASS_SHADING };
/* Material keys are window depths key / 65536: exact in a 32-bit float
 * depth, and in the key pass's interpolation of a constant. */
enum { VIS_MAX_KEYS = 65535 };

struct vis {
    struct visibility_buffer_options o;
    bool textured, wide, clustered;
    int triangle_bits, samples;
    GLuint ids_tex, key_tex;
    GLuint ids_fbo, key_fbo, shade_fbo;
    GLuint vertex_buf, index_buf, mesh_buf;
    double geometry_bytes;
    struct scene_program ids;
    GLuint edges_prog, classify_prog, empty_vao;
    /* [0] once a pixel; [1] (MSAA) once a sample, for the edge pixels. */
    GLuint shade_prog[2];
    int runs;
    /* Asset scenes: the distinct materials of the opaque and masked meshes,
     * each with a mesh that has it (gpu_scene_bind_material binds by mesh). */
    int keys;
    int *key_mesh;
    struct light_grid grid;
};

static void vis_destroy(void *state)
{
    struct vis *v = state;
    if (!v)
        return;
    if (v->ids.prog)
        glDeleteProgram(v->ids.prog);
    glDeleteProgram(v->edges_prog);
    glDeleteProgram(v->classify_prog);
    for (int r = 0; r < 2; r++)
        glDeleteProgram(v->shade_prog[r]);
    GLuint bufs[3] = {v->vertex_buf, v->index_buf, v->mesh_buf};
    glDeleteBuffers(3, bufs);
    if (v->empty_vao)
        glDeleteVertexArrays(1, &v->empty_vao);
    light_grid_finish(&v->grid);
    free(v->key_mesh);
    free(v);
}

/* Every mesh's vertices and indices copied into two storage buffers (on
 * the GPU: glCopyBufferSubData from the scene's own), and per mesh where
 * its own start, its material row and its material key. */
static bool copy_geometry(struct vis *v, const struct technique_env *env, char *err,
                          size_t errlen)
{
    const struct scene *s = env->scene;
    const struct gpu_scene *g = env->gpu;
    GLsizeiptr vbytes = 0, ibytes = 0;
    for (int m = 0; m < s->mesh_count; m++) {
        vbytes += (GLsizeiptr)(s->meshes[m].vertex_count * sizeof(struct mesh_vertex));
        ibytes += (GLsizeiptr)(s->meshes[m].index_count * sizeof(uint32_t));
    }
    int32_t *table = calloc((size_t)s->mesh_count * 4, sizeof(int32_t));
    v->key_mesh = calloc((size_t)s->mesh_count + 1, sizeof(int));
    if (!table || !v->key_mesh) {
        free(table);
        snprintf(err, errlen, "visibility_buffer: out of memory");
        return false;
    }
    glGenBuffers(1, &v->vertex_buf);
    glGenBuffers(1, &v->index_buf);
    glGenBuffers(1, &v->mesh_buf);
    glBindBuffer(GL_COPY_WRITE_BUFFER, v->vertex_buf);
    glBufferData(GL_COPY_WRITE_BUFFER, vbytes ? vbytes : 16, NULL, GL_STATIC_DRAW);
    glBindBuffer(GL_COPY_WRITE_BUFFER, v->index_buf);
    glBufferData(GL_COPY_WRITE_BUFFER, ibytes ? ibytes : 16, NULL, GL_STATIC_DRAW);
    GLsizeiptr vat = 0, iat = 0;
    for (int m = 0; m < s->mesh_count; m++) {
        const struct mesh *mesh = &s->meshes[m];
        GLsizeiptr vb = (GLsizeiptr)(mesh->vertex_count * sizeof(struct mesh_vertex));
        GLsizeiptr ib = (GLsizeiptr)(mesh->index_count * sizeof(uint32_t));
        table[m * 4 + 0] = (int32_t)(iat / (GLsizeiptr)sizeof(uint32_t));
        table[m * 4 + 1] = (int32_t)(vat / (GLsizeiptr)sizeof(struct mesh_vertex));
        table[m * 4 + 2] = g->mesh_material ? g->mesh_material[m].material : -1;
        if (vb) {
            glBindBuffer(GL_COPY_READ_BUFFER, g->vbo[m]);
            glBindBuffer(GL_COPY_WRITE_BUFFER, v->vertex_buf);
            glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, vat, vb);
        }
        if (ib) {
            glBindBuffer(GL_COPY_READ_BUFFER, g->ebo[m]);
            glBindBuffer(GL_COPY_WRITE_BUFFER, v->index_buf);
            glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, iat, ib);
        }
        vat += vb, iat += ib;
        /* Keys: one per distinct material row among the meshes the
         * technique draws (opaque and masked: before asset_blend_first). */
        if (!v->textured || table[m * 4 + 2] < 0 || m >= s->asset_blend_first ||
            !s->mesh_instance_count[m])
            continue;
        int key = 0;
        for (int k = 1; k <= v->keys && !key; k++)
            if (g->mesh_material[v->key_mesh[k]].material == table[m * 4 + 2])
                key = k;
        if (!key) {
            if (v->keys >= VIS_MAX_KEYS) {
                free(table);
                snprintf(err, errlen, "visibility_buffer: the scene has more than %d materials",
                         VIS_MAX_KEYS);
                return false;
            }
            key = ++v->keys;
            v->key_mesh[key] = m;
        }
        table[m * 4 + 3] = key;
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, v->mesh_buf);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)s->mesh_count * 4 * sizeof(int32_t)),
                 table, GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    glBindBuffer(GL_COPY_READ_BUFFER, 0);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
    free(table);
    v->geometry_bytes = (double)vbytes + (double)ibytes;
    return true;
}

/* The key target holds the MSAA edge stencil and asset scenes' material keys. */
static bool vis_uses_key(const struct vis *v)
{
    return v->samples > 1 || v->textured;
}

static bool targets(struct vis *v, const struct technique_env *env, char *err, size_t errlen)
{
    struct gpu_targets *pool = env->targets;
    int w = env->width, h = env->height, n = env->samples;
    v->ids_tex = gpu_targets_texture_ms(pool, "vis.ids", v->wide ? GL_RG32UI : GL_R32UI, w, h, n,
                                        err, errlen);
    if (!v->ids_tex)
        return false;
    /* The key target (edge stencil, material keys) only where it is used. */
    if (vis_uses_key(v) && !(v->key_tex = gpu_targets_texture_ms(pool, "vis.key",
                                                                 GL_DEPTH32F_STENCIL8, w, h, n,
                                                                 err, errlen)))
        return false;
    if (gpu_targets_samples(pool, v->ids_tex) != n ||
        (v->key_tex && gpu_targets_samples(pool, v->key_tex) != n)) {
        snprintf(err, errlen, "visibility_buffer: the driver gave the id buffer %d samples and "
                 "the output %d", gpu_targets_samples(pool, v->ids_tex), n);
        return false;
    }
    v->ids_fbo = gpu_targets_fbo(pool, "vis.ids", &v->ids_tex, 1, env->output_depth, err, errlen);
    if (!v->ids_fbo)
        return false;
    v->key_fbo = v->key_tex ? gpu_targets_fbo(pool, "vis.key", NULL, 0, v->key_tex, err, errlen)
                            : env->output_fbo;
    GLuint color = env->output_color;
    v->shade_fbo = v->key_fbo ? gpu_targets_fbo(pool, "vis.shade", &color, 1, v->key_tex, err,
                                                errlen)
                              : 0;
    return v->shade_fbo != 0;
}

static bool programs(struct vis *v, const struct technique_env *env, char *err, size_t errlen)
{
    char defines[1536];
    snprintf(defines, sizeof(defines), "%s%s#define VIS_TRIANGLE_BITS %d\n%s", env->defines,
             v->wide ? "#define VIS_WIDE 1\n" : "", v->triangle_bits < 0 ? 0 : v->triangle_bits,
             v->clustered ? "#define VIS_CLUSTERED 1\n" : "");
    const struct gl_stage ids[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {"vis_ids.frag"}},
    };
    const struct gl_stage edges[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"vis_edges.frag"}},
    };
    const struct gl_stage classify[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"vis_classify.frag"}},
    };
    const struct gl_stage shade[] = {
        {GL_VERTEX_SHADER, {"vis_key.vert"}},
        {GL_FRAGMENT_SHADER, {"vis_shade.frag"}},
    };
    GLuint prog = gl_program_build("visibility_buffer ids", ids, 2, defines, err, errlen);
    if (!prog)
        return false;
    v->ids = gpu_scene_program(env->gpu, prog);
    if (v->samples > 1 &&
        !(v->edges_prog = gl_program_build("visibility_buffer edges", edges, 2, defines, err,
                                           errlen)))
        return false;
    if (v->textured &&
        !(v->classify_prog = gl_program_build("visibility_buffer classify", classify, 2, defines,
                                              err, errlen)))
        return false;
    for (int r = 0; r < v->runs; r++) {
        char more[1600];
        snprintf(more, sizeof(more), "%s%s", defines, r ? "#define VIS_PER_SAMPLE 1\n" : "");
        if (!(v->shade_prog[r] = gl_program_build("visibility_buffer shading", shade, 2, more, err,
                                                  errlen)))
            return false;
    }
    return true;
}

static bool vis_create(const struct technique_env *env, void **state, char *err, size_t errlen)
{
    const struct visibility_buffer_options *o = env->options;
    const struct scene *s = env->scene;
    struct vis *v = calloc(1, sizeof(*v));
    if (!v) {
        snprintf(err, errlen, "visibility_buffer: out of memory");
        return false;
    }
    *state = v;
    v->o = *o;
    v->textured = s->asset != NULL;
    v->clustered = o->lights == VIS_LIGHTS_CLUSTERED;
    v->samples = env->samples > 1 ? env->samples : 1;
    v->runs = v->samples > 1 ? 2 : 1;
    long long max_triangles = 1;
    for (int m = 0; m < s->mesh_count; m++)
        if ((long long)s->meshes[m].index_count / 3 > max_triangles)
            max_triangles = (long long)s->meshes[m].index_count / 3;
    v->triangle_bits = vis_triangle_bits(s->instance_count, max_triangles);
    v->wide = o->ids == VIS_IDS_WIDE || v->triangle_bits < 0;
    GLint blocks = 0;
    glGetIntegerv(GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS, &blocks);
    if (blocks < 16) {
        snprintf(err, errlen, "visibility_buffer: its shading reads up to 16 storage buffers; "
                 "this device's GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS is %d", (int)blocks);
        goto fail;
    }
    if (!copy_geometry(v, env, err, errlen) || !targets(v, env, err, errlen) ||
        !programs(v, env, err, errlen))
        goto fail;
    if (v->clustered) {
        const struct light_grid_config cfg = {
            .kind = LIGHT_GRID_CLUSTERS,
            .grid = {o->cluster.grid[0], o->cluster.grid[1], o->cluster.grid[2]},
            .slices = o->cluster.slices,
            .max_per_cell = o->cluster.max_lights_per_cluster,
            .overflow = o->cluster.overflow,
            .binning = LIGHT_BINNING_GPU,
            .technique = "visibility_buffer",
        };
        if (!light_grid_init(&v->grid, env, &cfg, err, errlen))
            goto fail;
    }
    glGenVertexArrays(1, &v->empty_vao);
    return !gl_error_take("visibility_buffer setup", err, errlen);
fail:
    vis_destroy(v);
    *state = NULL;
    return false;
}

static void bind_geometry(const struct vis *v)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_VIS_VERTICES, v->vertex_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_VIS_INDICES, v->index_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_VIS_MESHES, v->mesh_buf);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER0);
    glBindTexture(v->samples > 1 ? GL_TEXTURE_2D_MULTISAMPLE : GL_TEXTURE_2D, v->ids_tex);
    glActiveTexture(GL_TEXTURE0);
}

/* A full-screen draw of prog over the bound framebuffer, in the budget's
 * tiles, with the empty vertex array. */
static void fullscreen(const struct technique_env *env, const struct vis *v, GLuint prog)
{
    glUseProgram(prog);
    glBindVertexArray(v->empty_vao);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
         gpu_tiles_next(env->budget, &t);)
        glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
}

static void classify(const struct vis *v, const struct technique_env *env)
{
    gpu_pass_begin(env->passes, PASS_CLASSIFY, v->key_fbo, env->width, env->height);
    if (!vis_uses_key(v)) {
        gpu_pass_end(env->passes); /* nothing to classify: timed at about 0 */
        return;
    }
    glClearDepth(1.0);
    glClearStencil(0);
    glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    glDisable(GL_CULL_FACE);
    gpu_scene_bind(env->gpu, &v->ids); /* the scene's buffers, for the fetch */
    bind_geometry(v);
    if (v->samples > 1) {
        /* Edge pixels: stencil 1 on every sample. */
        glDisable(GL_DEPTH_TEST);
        glDepthMask(GL_FALSE);
        glEnable(GL_STENCIL_TEST);
        glStencilFunc(GL_ALWAYS, 1, 0xff);
        glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
        glStencilMask(0xff);
        fullscreen(env, v, v->edges_prog);
        glDisable(GL_STENCIL_TEST);
        glDepthMask(GL_TRUE);
    }
    if (v->textured) {
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_ALWAYS);
        fullscreen(env, v, v->classify_prog);
        glDepthFunc(GL_LESS);
    }
    gpu_pass_end(env->passes);
}

static void shading(const struct vis *v, const struct technique_env *env)
{
    gpu_pass_begin(env->passes, PASS_SHADING, v->shade_fbo, env->width, env->height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_FALSE);
    if (v->textured)
        glDepthFunc(GL_EQUAL);
    else
        glDisable(GL_DEPTH_TEST);
    if (v->clustered)
        light_grid_bind(&v->grid);
    glBindVertexArray(v->empty_vao);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
         gpu_tiles_next(env->budget, &t);)
        for (int r = 0; r < v->runs; r++) {
            if (v->runs > 1) {
                glEnable(GL_STENCIL_TEST);
                glStencilFunc(GL_EQUAL, r, 0xff);
                glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
            }
            struct scene_program p = v->ids;
            p.prog = v->shade_prog[r];
            gpu_scene_bind(env->gpu, &p);
            bind_geometry(v);
            if (!v->textured) {
                glUniform1f(SB_LOC_VIS_KEY, 0.0f);
                glDrawArrays(GL_TRIANGLES, 0, 3);
                continue;
            }
            for (int k = 1; k <= v->keys; k++) {
                gpu_scene_bind_material(env->gpu, v->key_mesh[k], -1);
                glUniform1f(SB_LOC_VIS_KEY, (float)k / 65536.0f);
                glDrawArrays(GL_TRIANGLES, 0, 3);
            }
        }
    glBindVertexArray(0);
    glDisable(GL_STENCIL_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
    gpu_pass_end(env->passes);
}

static bool vis_render(void *state, const struct technique_env *env, int64_t frame, char *err,
                       size_t errlen)
{
    struct vis *v = state;
    gpu_scene_set_light_rows(env->gpu, &frame, 1);

    gpu_pass_begin(env->passes, PASS_BINNING, env->output_fbo, env->width, env->height);
    if (v->clustered)
        light_grid_build(&v->grid, env, frame);
    gpu_pass_end(env->passes);

    gpu_pass_begin(env->passes, PASS_VISIBILITY, v->ids_fbo, env->width, env->height);
    static const GLuint none[4] = {0, 0, 0, 0};
    glClearBufferuiv(GL_COLOR, 0, none);
    glClearDepth(1.0);
    glClearStencil(0);
    glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &v->ids);
    /* Once, as the g-buffer's pass draws (shared/gbuffer.c): its cost is
     * the geometry's, which screen tiles would not cut but repeat, every
     * tile transforming and binning every triangle again. */
    gpu_scene_draw(env->gpu, &v->ids);
    gpu_pass_end(env->passes);

    classify(v, env);
    shading(v, env);
    return technique_keep_going(env, err, errlen);
}

static bool vis_verify(void *state, char *err, size_t errlen)
{
    struct vis *v = state;
    return !v->clustered || light_grid_verify(&v->grid, err, errlen);
}

static json_t *vis_describe(void *state)
{
    struct vis *v = state;
    /* Bytes a pixel the technique keeps beside the output's colour: the ids,
     * the depth (24-bit, with stencil: 4) and, where it is used, the key
     * target (a 32-bit float depth and stencil: 8). */
    double ids = v->wide ? 8.0 : 4.0, key = vis_uses_key(v) ? 8.0 : 0.0;
    json_t *d = json_pack(
        "{s:s, s:o, s:f, s:{s:f, s:f, s:f}, s:f, s:i, s:s, s:s}", "ids",
        v->wide ? "rg32ui (instance + 1, triangle)" : "r32ui ((instance + 1) << triangle_bits | "
                                                      "triangle)",
        "triangle_bits", v->wide ? json_null() : json_integer(v->triangle_bits),
        "bytes_per_pixel", (ids + 4.0 + key) * v->samples, "bytes_per_sample", "ids", ids,
        "depth", 4.0, "material_key", key, "geometry_copy_bytes", v->geometry_bytes,
        "material_passes", v->textured ? v->keys : 1, "lights",
        v->clustered ? "clustered" : "all", "attributes",
        "rebuilt at each pixel's centre from the triangle's vertices with perspective-correct "
        "barycentrics (homogeneous edge functions), derivatives across the pixel's 2x2 quad");
    if (v->clustered) {
        json_t *g = light_grid_describe(&v->grid);
        if (g)
            json_object_update(d, g);
        json_decref(g);
    } else {
        /* Every light, as forward: a list that cannot overflow. */
        json_object_set_new(d, "overflow", json_pack("{s:i}", "frames", 0));
    }
    return d;
}

const struct technique technique_visibility_buffer = {
    .info = &visibility_buffer_info,
    .create = vis_create,
    .render = vis_render,
    .verify = vis_verify,
    .describe = vis_describe,
    .destroy = vis_destroy,
};
