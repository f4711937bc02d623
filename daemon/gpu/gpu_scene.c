#include "daemon/gpu/gpu_scene.h"

#include "daemon/gpu/bindings.h"
#include "daemon/scene/light_shape.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
        glEnableVertexAttribArray(4);
        glVertexAttribPointer(4, 2, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, tex));
        glEnableVertexAttribArray(5);
        glVertexAttribPointer(5, 4, GL_FLOAT, GL_FALSE, stride,
                              (void *)offsetof(struct mesh_vertex, tangent));
    }
    glBindVertexArray(0);

    /* std430 Instance (shaders/common/scene_data.glsl): three vec4s. */
    enum { INSTANCE_FLOATS = 12 };
    size_t n = (size_t)s->instance_count;
    float *inst = calloc(n * INSTANCE_FLOATS, sizeof(float));
    size_t lights = (size_t)(s->light_count ? s->light_count : 1);
    /* std430 Light (shaders/common/scene_data.glsl): three vec4s. */
    enum { LIGHT_FLOATS = 12 };
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
    }
    glGenBuffers(1, &g->instance_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->instance_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * INSTANCE_FLOATS * sizeof(float)), inst,
                 GL_STATIC_DRAW);
    glGenBuffers(1, &g->light_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->light_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(lights * LIGHT_FLOATS * sizeof(float)), light,
                 GL_STATIC_DRAW);
    glGenBuffers(1, &g->position_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    free(inst);
    free(light);
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
    glDeleteBuffers(1, &g->light_buffer);
    glDeleteBuffers(1, &g->position_buffer);
    free(g->position_scratch);
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

struct scene_program gpu_scene_program(const struct gpu_scene *g, GLuint prog)
{
    (void)g;
    struct scene_program p = {prog, glGetUniformLocation(prog, "u_instance_base")};
    return p;
}

void gpu_scene_bind(const struct gpu_scene *g, const struct scene_program *p)
{
    glUseProgram(p->prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_INSTANCES, g->instance_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHTS, g->light_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_POSITIONS, g->position_buffer);
}

void gpu_scene_draw(const struct gpu_scene *g, const struct scene_program *p)
{
    const struct scene *s = g->scene;
    int base = 0;
    for (int m = 0; m < g->mesh_count; m++) {
        if (!s->mesh_instance_count[m])
            continue;
        glUniform1i(p->instance_base, base);
        glBindVertexArray(g->vao[m]);
        glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count,
                                GL_UNSIGNED_INT, NULL, s->mesh_instance_count[m]);
        base += s->mesh_instance_count[m];
    }
    glBindVertexArray(0);
}
