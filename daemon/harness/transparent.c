#include "daemon/harness/transparent.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"

bool transparent_init(struct transparent *t, const struct gpu_scene *g, const char *defines,
                      char *err, size_t errlen)
{
    memset(t, 0, sizeof(*t));
    const struct scene *s = g->scene;
    if (!scene_has_blended(s))
        return true;
    t->count = s->mesh_count - s->asset_blend_first;
    t->order = malloc((size_t)t->count * sizeof(int));
    t->depth = malloc((size_t)t->count * sizeof(float));
    if (!t->order || !t->depth) {
        snprintf(err, errlen, "transparent pass: out of memory");
        transparent_finish(t);
        return false;
    }
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {"transparent.frag"}},
    };
    GLuint prog = gl_program_build("transparent", stages, 2, defines, err, errlen);
    if (!prog) {
        transparent_finish(t);
        return false;
    }
    t->program = gpu_scene_program(g, prog);
    return true;
}

void transparent_finish(struct transparent *t)
{
    if (!t)
        return;
    if (t->program.prog)
        glDeleteProgram(t->program.prog);
    free(t->order);
    free(t->depth);
    memset(t, 0, sizeof(*t));
}

void transparent_draw(struct transparent *t, const struct gpu_scene *g,
                      const struct gpu_passes *passes, int pass, GLuint fbo, int width,
                      int height, const float eye[3])
{
    const struct scene *s = g->scene;
    /* Back to front by the distance from the eye to each mesh's instance
     * centre (one instance a mesh), ties by mesh index: an insertion sort,
     * since blended meshes are few and the order changes little from one
     * frame to the next. */
    int base = 0;
    for (int m = 0; m < s->asset_blend_first; m++)
        base += s->mesh_instance_count[m];
    for (int i = 0; i < t->count; i++) {
        const float *p = s->instances[base + i].pos;
        float d[3] = {p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
        float key = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        int j = i;
        for (; j > 0 && t->depth[j - 1] < key; j--) {
            t->depth[j] = t->depth[j - 1];
            t->order[j] = t->order[j - 1];
        }
        t->depth[j] = key;
        t->order[j] = s->asset_blend_first + i;
    }
    gpu_pass_begin(passes, pass, fbo, width, height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gpu_scene_bind(g, &t->program);
    for (int i = 0; i < t->count; i++)
        gpu_scene_draw_mesh(g, &t->program, t->order[i]);
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    gpu_pass_end(passes);
}
