#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/motion.h"

#include <stdio.h>
#include <string.h>

#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

bool motion_vectors_init(struct motion_vectors *m, struct gpu_targets *pool,
                         const struct gpu_scene *gpu, GLuint depth_tex, int w, int h,
                         const char *defines, char *err, size_t errlen)
{
    memset(m, 0, sizeof(*m));
    m->width = w, m->height = h, m->depth_tex = depth_tex;
    m->tex = gpu_targets_texture(pool, "motion", GL_RG16F, w, h, err, errlen);
    if (!m->tex ||
        !(m->camera_fbo = gpu_targets_fbo(pool, "motion", &m->tex, 1, 0, err, errlen)) ||
        !(m->object_fbo = gpu_targets_fbo(pool, "motion.objects", &m->tex, 1, depth_tex, err,
                                          errlen)))
        return false;
    const struct gl_stage camera[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"motion_camera.frag"}},
    };
    const struct gl_stage objects[] = {
        {GL_VERTEX_SHADER, {"motion_objects.vert"}},
        {GL_FRAGMENT_SHADER, {"motion_objects.frag"}},
    };
    if (!(m->camera_prog = gl_program_build("motion vectors (camera)", camera, 2, defines, err,
                                            errlen)))
        return false;
    GLuint prog = gl_program_build("motion vectors (objects)", objects, 2, defines, err, errlen);
    if (!prog)
        return false;
    m->objects = gpu_scene_program(gpu, prog);
    glGenVertexArrays(1, &m->empty_vao);
    return true;
}

void motion_vectors_draw(const struct motion_vectors *m, const struct gpu_passes *passes,
                         int pass, const struct gpu_scene *gpu)
{
    gpu_pass_begin(passes, pass, m->camera_fbo, m->width, m->height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(m->camera_prog);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_POST_DEPTH);
    glBindTexture(GL_TEXTURE_2D, m->depth_tex);
    glBindVertexArray(m->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    const struct scene *s = gpu->scene;
    if (s->mover >= 0) {
        /* The moving instances over it, where the depth shows them: the
         * same transform as every scene program's, pulled a little nearer
         * so that the test against their own depth passes. */
        glBindFramebuffer(GL_FRAMEBUFFER, m->object_fbo);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LEQUAL);
        glDepthMask(GL_FALSE);
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(-1.0f, -1.0f);
        gpu_scene_bind(gpu, &m->objects);
        gpu_scene_draw_instance(gpu, &m->objects, s->mover);
        glDisable(GL_POLYGON_OFFSET_FILL);
        glDepthMask(GL_TRUE);
    }
    gpu_pass_end(passes);
}

void motion_vectors_finish(struct motion_vectors *m)
{
    if (m->camera_prog)
        glDeleteProgram(m->camera_prog);
    if (m->objects.prog)
        glDeleteProgram(m->objects.prog);
    if (m->empty_vao)
        glDeleteVertexArrays(1, &m->empty_vao);
    memset(m, 0, sizeof(*m));
}
