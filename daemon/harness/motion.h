#ifndef SHADEBENCH_MOTION_H
#define SHADEBENCH_MOTION_H

/* The harness's motion vectors (the frame contract's, for any stage that
 * declares it reads them: common/frame_needs.h): per pixel, how far the
 * surface it shows moved on screen since the frame before, in pixels
 * (this frame's position minus the frame before's, jitter left out), in an
 * RG16F target of the frame's size. A timed pass of its own after the
 * technique, the sky, the transparent pass and the MSAA resolve, before the
 * post chain: camera motion for every pixel from the single-sample depth
 * (the surface rebuilt with the jittered inverse view-projection, then
 * projected with this frame's and the frame before's unjittered ones), and
 * the moving instances (scene.mover) drawn over it with their own motion,
 * depth-tested against the same depth. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/gpu/targets.h"

struct motion_vectors {
    GLuint tex;                     /* RG16F, pixels */
    GLuint camera_fbo, object_fbo;  /* the target alone; with the frame's depth */
    GLuint camera_prog;
    struct scene_program objects;
    GLuint empty_vao, depth_tex;
    int width, height;
};

/* depth_tex: the single-sample depth the post chain reads (w x h). */
bool motion_vectors_init(struct motion_vectors *m, struct gpu_targets *pool,
                         const struct gpu_scene *gpu, GLuint depth_tex, int w, int h,
                         const char *defines, char *err, size_t errlen);
/* Pass `pass`: this frame's motion vectors. */
void motion_vectors_draw(const struct motion_vectors *m, const struct gpu_passes *passes,
                         int pass, const struct gpu_scene *gpu);
/* Takes a zeroed or initialised m (the target stays in the pool). */
void motion_vectors_finish(struct motion_vectors *m);

#endif
