#ifndef SHADEBENCH_TRANSPARENT_H
#define SHADEBENCH_TRANSPARENT_H

/* The harness's "transparent" pass: an asset scene's blended (glTF
 * "BLEND") meshes, drawn after the technique's opaque work and the sky,
 * the same way for every technique, as deferred renderers do: sorted back
 * to front by instance centre at each frame (a pure function of the
 * frame's camera), forward-shaded over every light (surface.glsl), blended
 * SRC_ALPHA, ONE_MINUS_SRC_ALPHA, depth-tested against the technique's
 * depth with depth writes off. Only for scenes with blended materials.
 * Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"

struct transparent {
    struct scene_program program;
    int *order;  /* blended meshes, sorted each frame: allocated once */
    float *depth; /* their distances this frame */
    int count;
};

/* Builds the program and the sort's scratch for s (nothing for a scene
 * without blended meshes: t->count 0). False with err. */
bool transparent_init(struct transparent *t, const struct gpu_scene *g, const char *defines,
                      char *err, size_t errlen);
/* Takes a zeroed or initialised t. */
void transparent_finish(struct transparent *t);

/* Pass `pass` of frame: the blended meshes into fbo, over what is there.
 * eye: the frame's camera position. No allocation. */
void transparent_draw(struct transparent *t, const struct gpu_scene *g,
                      const struct gpu_passes *passes, int pass, GLuint fbo, int width,
                      int height, const float eye[3]);

#endif
