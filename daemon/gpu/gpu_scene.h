#ifndef SHADEBENCH_GPU_SCENE_H
#define SHADEBENCH_GPU_SCENE_H

/* The scene's GL objects, shared by every technique: one VAO per mesh, the
 * instance buffer (position and scale, albedo and mesh, material), the
 * light buffers and per-frame light positions. Render
 * thread only (it holds the GL context). */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/scene/scene.h"

struct gpu_scene {
    const struct scene *scene;
    GLuint *vao, *vbo, *ebo; /* per mesh of the scene (scene.mesh_count) */
    int mesh_count;
    GLuint instance_buffer, light_buffer, position_buffer;
    int position_rows;          /* rows allocated in position_buffer */
    int64_t uploaded_frame;     /* frame in row 0 when rows == 1, else INT64_MIN */
    float *position_scratch;
};

bool gpu_scene_init(struct gpu_scene *g, const struct scene *s, char *err, size_t errlen);
void gpu_scene_finish(struct gpu_scene *g);

/* Uploads light positions, row r holding frames[r]; rows == 1 for techniques
 * that light the current frame only. Skips the upload when unchanged. The
 * camera is not the scene's business here: the harness puts each frame's in
 * the frame block (daemon/gpu/pass.h). */
void gpu_scene_set_light_rows(struct gpu_scene *g, const int64_t *frames, int rows);

/* A program that reads the scene, with the uniforms the scene sets. */
struct scene_program {
    GLuint prog;
    GLint instance_base; /* -1 for programs that draw no instances */
};

/* Looks up prog's per-draw uniform once, so that frames only bind: no
 * uniform lookups in the timed region. */
struct scene_program gpu_scene_program(const struct gpu_scene *g, GLuint prog);

/* Uses the program and binds the scene buffers at their bindings.h points. */
void gpu_scene_bind(const struct gpu_scene *g, const struct scene_program *p);

/* Instanced draw of every object, one call per mesh. */
void gpu_scene_draw(const struct gpu_scene *g, const struct scene_program *p);

#endif
