#ifndef SHADEBENCH_GPU_SCENE_H
#define SHADEBENCH_GPU_SCENE_H

/* The scene's GL objects, shared by every technique: one VAO per mesh, the
 * instance buffer (position and scale, albedo and mesh, material), the
 * light buffers, per-frame light positions and the camera uniforms. Render
 * thread only (it holds the GL context). */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/scene/scene.h"

struct gpu_scene {
    const struct scene *scene;
    struct scene_camera camera; /* the camera the programs draw with */
    bool camera_per_bind;       /* moving, or set: gpu_scene_bind sets it on each program */
    GLuint vao[SCENE_MESH_COUNT], vbo[SCENE_MESH_COUNT], ebo[SCENE_MESH_COUNT];
    GLuint instance_buffer, light_buffer, position_buffer;
    int position_rows;          /* rows allocated in position_buffer */
    int64_t uploaded_frame;     /* frame in row 0 when rows == 1, else INT64_MIN */
    float *position_scratch;
};

bool gpu_scene_init(struct gpu_scene *g, const struct scene *s, char *err, size_t errlen);
void gpu_scene_finish(struct gpu_scene *g);

/* Uploads light positions, row r holding frames[r]; rows == 1 for techniques
 * that light the current frame only. Skips the upload when unchanged.
 * Interim, until the harness calls gpu_scene_set_camera every frame: when
 * the scene's camera moves, this also sets the camera of frames[0] (the
 * frame being drawn), which is what makes moving cameras render today. */
void gpu_scene_set_light_rows(struct gpu_scene *g, const int64_t *frames, int rows);

/* The camera the next binds draw with (u_view_proj, u_eye). A static scene
 * never needs it: programs get the frame-0 camera when registered. Once
 * called, every bind sets the camera; call it once per frame before the
 * frame's first gpu_scene_bind. */
void gpu_scene_set_camera(struct gpu_scene *g, const struct scene_camera *c);

/* A program that reads the scene, with the uniforms the scene sets. */
struct scene_program {
    GLuint prog;
    GLint instance_base; /* -1 for programs that draw no instances */
    GLint view_proj, eye; /* camera uniforms, -1 where the program has none */
};

/* Sets the scene's uniforms on prog once (the frame-0 camera and the light
 * count), so that frames only bind: no uniform lookups in the timed region. */
struct scene_program gpu_scene_program(const struct gpu_scene *g, GLuint prog);

/* Uses the program and binds the scene buffers; for a moving camera, also
 * sets the current camera on it (two uniform calls, no lookups). Programs
 * are not tracked, so a technique may delete its programs at any time. */
void gpu_scene_bind(const struct gpu_scene *g, const struct scene_program *p);

/* Instanced draw of every object, one call per mesh. */
void gpu_scene_draw(const struct gpu_scene *g, const struct scene_program *p);

#endif
