#include "daemon/gpu/gpu_scene.h"

#include "daemon/gpu/bindings.h"
#include "daemon/scene/asset.h"
#include "daemon/scene/light_shape.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool gpu_scene_check_units(char *err, size_t errlen)
{
    GLint combined = 0, fragment = 0;
    glGetIntegerv(GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, &combined);
    glGetIntegerv(GL_MAX_TEXTURE_IMAGE_UNITS, &fragment);
    /* Units 0..16 are the harness's and techniques' (bindings.h), 20..24
     * the material's; a fragment shader samples at most 5 + 4 g-buffer
     * planes + depth + the look's 5. */
    if (combined <= SB_TEX_MATERIAL_EMISSIVE || fragment < 16) {
        snprintf(err, errlen,
                 "scene: asset materials need texture units up to %d, and 16 in the fragment "
                 "stage: this device has GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS %d, "
                 "GL_MAX_TEXTURE_IMAGE_UNITS %d",
                 SB_TEX_MATERIAL_EMISSIVE, (int)combined, (int)fragment);
        return false;
    }
    return true;
}

/* glTF sampler values, with the defaults glTF gives an absent one (and a
 * value outside the enumeration: the cache reader passes only valid ones,
 * this keeps GL from an error if it ever does not). */
static GLint wrap_mode(uint32_t w)
{
    return w == GL_CLAMP_TO_EDGE || w == GL_MIRRORED_REPEAT ? (GLint)w : GL_REPEAT;
}

static GLint min_filter(uint32_t f)
{
    return (f >= GL_NEAREST_MIPMAP_NEAREST && f <= GL_LINEAR_MIPMAP_LINEAR) || f == GL_NEAREST ||
                   f == GL_LINEAR
               ? (GLint)f
               : GL_LINEAR_MIPMAP_LINEAR;
}

static GLuint image_texture(const struct asset_image *im, bool srgb)
{
    GLuint t;
    int edge = (int)(im->width > im->height ? im->width : im->height), levels = 1;
    while (edge >>= 1)
        levels++;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexStorage2D(GL_TEXTURE_2D, levels, srgb ? GL_SRGB8_ALPHA8 : GL_RGBA8, (GLsizei)im->width,
                   (GLsizei)im->height);
    /* The file's first row at v = 0: glTF's uv origin is the image's
     * top-left corner, so its rows go in as stored. */
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)im->width, (GLsizei)im->height, GL_RGBA,
                    GL_UNSIGNED_BYTE, im->rgba);
    glGenerateMipmap(GL_TEXTURE_2D);
    glBindTexture(GL_TEXTURE_2D, 0);
    return t;
}

/* std430 SurfaceMaterial (shaders/common/surface.glsl): 16 floats, then
 * each slot's texture transform as two rows of 4. */
enum { MATERIAL_FLOATS = 16 + ASSET_TEX_SLOTS * 8 };

static void material_row(const struct asset_material *m, bool normal_maps, float *o)
{
    /* glTF's default material: every factor at its default (white,
     * metallic 1, roughness 1), no textures, opaque, one-sided. */
    static const struct asset_material none = {
        .base_color = {1, 1, 1, 1}, .metallic = 1, .roughness = 1, .alpha_cutoff = 0.5f,
        .tex = {{-1, 0, 0, 0, 0, 0, 1, ASSET_UV_IDENTITY}, {-1, 0, 0, 0, 0, 0, 1, ASSET_UV_IDENTITY},
                {-1, 0, 0, 0, 0, 0, 1, ASSET_UV_IDENTITY}, {-1, 0, 0, 0, 0, 0, 1, ASSET_UV_IDENTITY},
                {-1, 0, 0, 0, 0, 0, 1, ASSET_UV_IDENTITY}}};
    if (!m)
        m = &none;
    memcpy(&o[0], m->base_color, 4 * sizeof(float));
    memcpy(&o[4], m->emissive, 3 * sizeof(float));
    o[7] = m->alpha_mode == ASSET_ALPHA_MASK ? m->alpha_cutoff : -1.0f;
    o[8] = m->metallic;
    o[9] = m->roughness;
    o[10] = m->tex[ASSET_TEX_NORMAL].scale;
    o[11] = m->tex[ASSET_TEX_OCCLUSION].scale;
    int32_t bits[4] = {0, 0, (int32_t)m->alpha_mode, m->double_sided};
    for (int t = 0; t < ASSET_TEX_SLOTS; t++) {
        if (m->tex[t].image < 0 || (t == ASSET_TEX_NORMAL && !normal_maps))
            continue;
        bits[0] |= 1 << t;
        bits[1] |= (m->tex[t].uv_set == 1) << t;
    }
    memcpy(&o[12], bits, sizeof(bits));
    for (int t = 0; t < ASSET_TEX_SLOTS; t++) {
        float x[6];
        asset_uv_transform_matrix(&m->tex[t].transform, x);
        float *row = &o[16 + 8 * t];
        row[0] = x[0], row[1] = x[1], row[2] = x[2], row[3] = 0.0f;
        row[4] = x[3], row[5] = x[4], row[6] = x[5], row[7] = 0.0f;
    }
}

static bool materials_init(struct gpu_scene *g, const struct scene *s, char *err, size_t errlen)
{
    const struct asset *a = s->asset;
    if (!gpu_scene_check_units(err, errlen))
        return false;
    size_t rows = a->material_count + 1; /* glTF's default material last */
    float *buf = calloc(rows * MATERIAL_FLOATS, sizeof(float));
    g->image_tex_count = (int)a->image_count * 2;
    g->image_tex = calloc((size_t)(g->image_tex_count ? g->image_tex_count : 1), sizeof(GLuint));
    g->sampler_count = (int)a->material_count * ASSET_TEX_SLOTS;
    g->samplers = calloc((size_t)(g->sampler_count ? g->sampler_count : 1), sizeof(GLuint));
    g->mesh_material = calloc((size_t)g->mesh_count, sizeof(*g->mesh_material));
    if (!buf || !g->image_tex || !g->samplers || !g->mesh_material) {
        free(buf);
        snprintf(err, errlen, "out of memory for the asset's materials");
        return false;
    }
    for (uint32_t m = 0; m < a->material_count; m++)
        material_row(&a->materials[m], s->spec.normal_maps, &buf[m * MATERIAL_FLOATS]);
    material_row(NULL, true, &buf[a->material_count * MATERIAL_FLOATS]);
    glGenBuffers(1, &g->material_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->material_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(rows * MATERIAL_FLOATS * sizeof(float)),
                 buf, GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    free(buf);
    if (g->sampler_count)
        glGenSamplers(g->sampler_count, g->samplers);
    for (uint32_t m = 0; m < a->material_count; m++)
        for (int t = 0; t < ASSET_TEX_SLOTS; t++) {
            const struct asset_texture_ref *r = &a->materials[m].tex[t];
            GLuint smp = g->samplers[m * ASSET_TEX_SLOTS + (uint32_t)t];
            glSamplerParameteri(smp, GL_TEXTURE_WRAP_S, wrap_mode(r->wrap_s));
            glSamplerParameteri(smp, GL_TEXTURE_WRAP_T, wrap_mode(r->wrap_t));
            glSamplerParameteri(smp, GL_TEXTURE_MIN_FILTER, min_filter(r->min_filter));
            glSamplerParameteri(smp, GL_TEXTURE_MAG_FILTER,
                                r->mag_filter == GL_NEAREST ? GL_NEAREST : GL_LINEAR);
            /* Anisotropic filtering stays off (its sample pattern is the
             * driver's: the same job would differ between devices). */
            if (r->image < 0)
                continue;
            bool srgb = t == ASSET_TEX_BASE_COLOR || t == ASSET_TEX_EMISSIVE;
            GLuint *tex = &g->image_tex[r->image * 2 + srgb];
            if (!*tex)
                *tex = image_texture(&a->images[r->image], srgb);
        }
    for (int sm = 0; sm < g->mesh_count; sm++) {
        struct gpu_mesh_material *mm = &g->mesh_material[sm];
        int am = s->mesh_asset_index ? s->mesh_asset_index[sm] : -1;
        mm->material = -1;
        if (am < 0)
            continue;
        int mat = a->meshes[am].material;
        mm->material = mat >= 0 ? mat : (int)a->material_count;
        mm->attributes = (a->meshes[am].has_uv0 ? 1 : 0) | (a->meshes[am].has_texcoord1 ? 2 : 0) |
                         (a->meshes[am].has_color ? 4 : 0);
        if (mat < 0)
            continue;
        mm->double_sided = a->materials[mat].double_sided;
        for (int t = 0; t < ASSET_TEX_SLOTS; t++) {
            const struct asset_texture_ref *r = &a->materials[mat].tex[t];
            bool srgb = t == ASSET_TEX_BASE_COLOR || t == ASSET_TEX_EMISSIVE;
            mm->tex[t] = r->image >= 0 ? g->image_tex[r->image * 2 + srgb] : 0;
            mm->sampler[t] = g->samplers[(uint32_t)mat * ASSET_TEX_SLOTS + (uint32_t)t];
        }
    }
    return true;
}

bool gpu_scene_init(struct gpu_scene *g, const struct scene *s, char *err, size_t errlen)
{
    memset(g, 0, sizeof(*g));
    g->scene = s;
    g->uploaded_frame = INT64_MIN;
    g->mesh_count = s->mesh_count;
    g->vao = calloc((size_t)g->mesh_count, sizeof(GLuint));
    g->vbo = calloc((size_t)g->mesh_count, sizeof(GLuint));
    g->ebo = calloc((size_t)g->mesh_count, sizeof(GLuint));
    if (!g->vao || !g->vbo || !g->ebo) {
        snprintf(err, errlen, "out of memory for scene buffers");
        gpu_scene_finish(g);
        return false;
    }
    glGenVertexArrays(g->mesh_count, g->vao);
    glGenBuffers(g->mesh_count, g->vbo);
    glGenBuffers(g->mesh_count, g->ebo);
    for (int m = 0; m < g->mesh_count; m++) {
        const struct mesh *mesh = &s->meshes[m];
        glBindVertexArray(g->vao[m]);
        glBindBuffer(GL_ARRAY_BUFFER, g->vbo[m]);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(mesh->vertex_count * sizeof(struct mesh_vertex)),
                     mesh->vertices, GL_STATIC_DRAW);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ebo[m]);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(mesh->index_count * sizeof(uint32_t)),
                     mesh->indices, GL_STATIC_DRAW);
        GLsizei stride = sizeof(struct mesh_vertex);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, pos));
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, normal));
        glEnableVertexAttribArray(2);
        glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, uv));
        glEnableVertexAttribArray(3);
        glVertexAttribPointer(3, 4, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, chart));
        /* The file's two uv sets in one vec4 (a program that declares a
         * vec2 there reads TEXCOORD_0). */
        glEnableVertexAttribArray(4);
        glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, tex));
        glEnableVertexAttribArray(5);
        glVertexAttribPointer(5, 4, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, tangent));
        glEnableVertexAttribArray(6);
        glVertexAttribPointer(6, 4, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, color));
    }
    glBindVertexArray(0);

    /* std430 Instance (shaders/common/scene_data.glsl): three vec4s. */
    enum { INSTANCE_FLOATS = 12 };
    size_t n = (size_t)s->instance_count;
    float *inst = calloc(n * INSTANCE_FLOATS, sizeof(float));
    size_t lights = (size_t)(s->light_count ? s->light_count : 1);
    /* std430 Light (shaders/common/scene_data.glsl): three vec4s. */
    enum { LIGHT_FLOATS = 16 };
    float *light = calloc(lights * LIGHT_FLOATS, sizeof(float));
    g->position_scratch = calloc(lights * 4, sizeof(float));
    if (!inst || !light || !g->position_scratch) {
        free(inst);
        free(light);
        snprintf(err, errlen, "out of memory for scene buffers");
        gpu_scene_finish(g);
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        const struct scene_instance *in = &s->instances[i];
        float *o = &inst[i * INSTANCE_FLOATS];
        memcpy(&o[0], in->pos, sizeof(in->pos));
        o[3] = in->scale;
        memcpy(&o[4], in->albedo, sizeof(in->albedo));
        o[7] = (float)in->mesh;
        o[8] = in->material.specular;
        o[9] = in->material.shininess;
        o[10] = in->material.metallic;
        o[11] = in->material.roughness;
    }
    for (int i = 0; i < s->light_count; i++) {
        const struct scene_light *l = &s->lights[i];
        float *o = &light[i * LIGHT_FLOATS];
        memcpy(&o[0], l->color, sizeof(l->color));
        o[3] = l->radius;
        if (l->type != SCENE_LIGHT_POINT)
            memcpy(&o[4], l->direction, sizeof(l->direction));
        o[7] = (float)l->type;
        if (l->type == SCENE_LIGHT_SPOT) {
            o[8] = l->cos_outer;
            o[9] = l->cos_inner;
            o[10] = scene_light_cone_scale(l);
            o[11] = scene_light_sin_outer(l);
        }
        o[12] = (float)l->falloff;
        o[13] = l->range;
    }
    glGenBuffers(1, &g->instance_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->instance_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * INSTANCE_FLOATS * sizeof(float)), inst,
                 GL_STATIC_DRAW);
    /* The positions the frame before: the same as now until something moves. */
    float *prev = calloc(n ? n * 4 : 4, sizeof(float));
    if (!prev) {
        free(inst);
        free(light);
        snprintf(err, errlen, "out of memory for scene buffers");
        gpu_scene_finish(g);
        return false;
    }
    for (size_t i = 0; i < n; i++)
        memcpy(&prev[i * 4], &inst[i * INSTANCE_FLOATS], 4 * sizeof(float));
    glGenBuffers(1, &g->prev_instance_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->prev_instance_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((n ? n : 1) * 4 * sizeof(float)), prev,
                 s->mover >= 0 ? GL_STREAM_DRAW : GL_STATIC_DRAW);
    free(prev);
    g->instances_frame = INT64_MIN;
    if (s->mover >= 0) {
        g->instance_rows = inst; /* kept: each frame uploads them */
        inst = NULL;
    }
    glGenBuffers(1, &g->light_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->light_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(lights * LIGHT_FLOATS * sizeof(float)), light,
                 GL_STATIC_DRAW);
    glGenBuffers(1, &g->position_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    free(inst);
    free(light);
    if (s->asset && !materials_init(g, s, err, errlen)) {
        gpu_scene_finish(g);
        return false;
    }
    return true;
}

void gpu_scene_finish(struct gpu_scene *g)
{
    if (!g || !g->scene)
        return;
    if (g->vao)
        glDeleteVertexArrays(g->mesh_count, g->vao);
    if (g->vbo)
        glDeleteBuffers(g->mesh_count, g->vbo);
    if (g->ebo)
        glDeleteBuffers(g->mesh_count, g->ebo);
    free(g->vao);
    free(g->vbo);
    free(g->ebo);
    glDeleteBuffers(1, &g->instance_buffer);
    glDeleteBuffers(1, &g->prev_instance_buffer);
    free(g->instance_rows);
    glDeleteBuffers(1, &g->light_buffer);
    glDeleteBuffers(1, &g->position_buffer);
    free(g->position_scratch);
    if (g->material_buffer)
        glDeleteBuffers(1, &g->material_buffer);
    if (g->image_tex && g->image_tex_count)
        glDeleteTextures(g->image_tex_count, g->image_tex);
    if (g->samplers && g->sampler_count)
        glDeleteSamplers(g->sampler_count, g->samplers);
    free(g->image_tex);
    free(g->samplers);
    free(g->mesh_material);
    memset(g, 0, sizeof(*g));
}

void gpu_scene_set_light_rows(struct gpu_scene *g, const int64_t *frames, int rows)
{
    const struct scene *s = g->scene;
    if (rows == 1 && g->position_rows == 1 &&
        (g->uploaded_frame == frames[0] || (!s->spec.dynamic && g->uploaded_frame != INT64_MIN)))
        return;
    size_t row_floats = (size_t)(s->light_count ? s->light_count : 1) * 4;
    GLsizeiptr bytes = (GLsizeiptr)(row_floats * sizeof(float) * (size_t)rows);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->position_buffer);
    /* Orphan the old storage so a frame still in flight never forces a wait. */
    glBufferData(GL_SHADER_STORAGE_BUFFER, bytes, NULL, GL_STREAM_DRAW);
    for (int r = 0; r < rows; r++) {
        for (int i = 0; i < s->light_count; i++) {
            scene_light_position(s, i, frames[r], &g->position_scratch[i * 4]);
            g->position_scratch[i * 4 + 3] = 1.0f;
        }
        glBufferSubData(GL_SHADER_STORAGE_BUFFER,
                        (GLintptr)(row_floats * sizeof(float) * (size_t)r),
                        (GLsizeiptr)(row_floats * sizeof(float)), g->position_scratch);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    g->position_rows = rows;
    g->uploaded_frame = rows == 1 ? frames[0] : INT64_MIN;
}

void gpu_scene_set_frame(struct gpu_scene *g, int64_t frame)
{
    const struct scene *s = g->scene;
    if (s->mover < 0 || g->instances_frame == frame)
        return;
    enum { INSTANCE_FLOATS = 12 };
    float now[4], before[4];
    scene_instance_at(s, s->mover, frame, now);
    scene_instance_at(s, s->mover, frame - 1, before);
    memcpy(&g->instance_rows[(size_t)s->mover * INSTANCE_FLOATS], now, sizeof(now));
    size_t n = (size_t)s->instance_count;
    /* Orphaned, not overwritten: a frame still in flight keeps its rows. */
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->instance_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * INSTANCE_FLOATS * sizeof(float)),
                 g->instance_rows, GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->prev_instance_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * 4 * sizeof(float)), NULL,
                 GL_STREAM_DRAW);
    float *prev = glMapBufferRange(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(n * 4 * sizeof(float)),
                                   GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
    if (prev) {
        for (size_t i = 0; i < n; i++)
            memcpy(&prev[i * 4], &g->instance_rows[i * INSTANCE_FLOATS], 4 * sizeof(float));
        memcpy(&prev[(size_t)s->mover * 4], before, sizeof(before));
        glUnmapBuffer(GL_SHADER_STORAGE_BUFFER);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    g->instances_frame = frame;
}

struct scene_program gpu_scene_program(const struct gpu_scene *g, GLuint prog)
{
    (void)g;
    struct scene_program p = {prog, glGetUniformLocation(prog, "u_instance_base"),
                              glGetUniformLocation(prog, "u_material"), false,
                              glGetUniformLocation(prog, "u_mesh_attributes")};
    return p;
}

void gpu_scene_bind(const struct gpu_scene *g, const struct scene_program *p)
{
    glUseProgram(p->prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_INSTANCES, g->instance_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHTS, g->light_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_POSITIONS, g->position_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_PREV_INSTANCES, g->prev_instance_buffer);
    if (g->material_buffer)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_MATERIALS, g->material_buffer);
}

void gpu_scene_bind_material(const struct gpu_scene *g, int mesh, GLint material_loc)
{
    if (!g->mesh_material || g->mesh_material[mesh].material < 0)
        return;
    const struct gpu_mesh_material *mm = &g->mesh_material[mesh];
    if (material_loc >= 0)
        glUniform1i(material_loc, mm->material);
    for (int t = 0; t < 5; t++) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_MATERIAL_BASE_COLOR + t);
        glBindTexture(GL_TEXTURE_2D, mm->tex[t]);
        glBindSampler(SB_TEX_MATERIAL_BASE_COLOR + t, mm->sampler[t]);
    }
    glActiveTexture(GL_TEXTURE0);
}

/* One mesh's instanced draw; instance_base is its first instance. */
static void draw_mesh(const struct gpu_scene *g, const struct scene_program *p, int m, int base)
{
    const struct scene *s = g->scene;
    bool uncull = false;
    if (g->mesh_material) {
        gpu_scene_bind_material(g, m, p->material);
        if (p->mesh_attributes >= 0)
            glUniform1i(p->mesh_attributes, g->mesh_material[m].attributes);
        /* Double-sided: both faces drawn (the shaders flip the normal of
         * back faces); the pass's culling state comes back after. */
        uncull = g->mesh_material[m].double_sided && glIsEnabled(GL_CULL_FACE);
        if (uncull)
            glDisable(GL_CULL_FACE);
    }
    bool masked = p->after_prepass && m >= s->asset_mask_first && m < s->asset_blend_first;
    if (masked)
        glDepthFunc(GL_EQUAL);
    glUniform1i(p->instance_base, base);
    glBindVertexArray(g->vao[m]);
    glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count, GL_UNSIGNED_INT,
                            NULL, s->mesh_instance_count[m]);
    if (masked)
        glDepthFunc(GL_LEQUAL);
    if (uncull)
        glEnable(GL_CULL_FACE);
}

void gpu_scene_draw_mesh(const struct gpu_scene *g, const struct scene_program *p, int mesh)
{
    const struct scene *s = g->scene;
    int base = 0;
    for (int m = 0; m < mesh; m++)
        base += s->mesh_instance_count[m];
    if (s->mesh_instance_count[mesh])
        draw_mesh(g, p, mesh, base);
    glBindVertexArray(0);
}

void gpu_scene_draw_instance(const struct gpu_scene *g, const struct scene_program *p,
                             int instance)
{
    const struct scene *s = g->scene;
    int m = s->instances[instance].mesh;
    gpu_scene_bind_material(g, m, p->material);
    glUniform1i(p->instance_base, instance);
    glBindVertexArray(g->vao[m]);
    glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count, GL_UNSIGNED_INT,
                            NULL, 1);
    glBindVertexArray(0);
}

void gpu_scene_draw(const struct gpu_scene *g, const struct scene_program *p)
{
    const struct scene *s = g->scene;
    int base = 0;
    /* Blended meshes come last (scene_asset.c orders them): the
     * transparent pass draws them. */
    for (int m = 0; m < s->asset_blend_first && m < g->mesh_count; m++) {
        if (!s->mesh_instance_count[m])
            continue;
        if (g->mesh_material)
            draw_mesh(g, p, m, base);
        else {
            /* The procedural scenes' path, call for call what it always was. */
            glUniform1i(p->instance_base, base);
            glBindVertexArray(g->vao[m]);
            glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count,
                                    GL_UNSIGNED_INT, NULL, s->mesh_instance_count[m]);
        }
        base += s->mesh_instance_count[m];
    }
    glBindVertexArray(0);
}
