#ifndef SHADEBENCH_GPU_TARGETS_H
#define SHADEBENCH_GPU_TARGETS_H

/* A pool of named, typed render targets (2D textures) and the framebuffers
 * over them. A target is re-created only when its size or format changes,
 * so consecutive jobs at one size allocate nothing. The harness owns the
 * pool; techniques ask it for their planes (g-buffers, light grids' depth
 * bounds) by name. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

#define GPU_TARGETS_MAX 32

struct gpu_targets;

struct gpu_targets *gpu_targets_create(void);
/* Deletes every texture and framebuffer. Accepts NULL. */
void gpu_targets_destroy(struct gpu_targets *t);

/* The texture named name with this format and size (created or re-created as
 * needed; filtering nearest, clamped). 0 with err filled when the pool is full
 * or GL refuses. */
GLuint gpu_targets_texture(struct gpu_targets *t, const char *name, GLenum format, int w, int h,
                           char *err, size_t errlen);

/* The framebuffer named name with these colour attachments (in draw-buffer
 * order) and depth texture (0 for none), checked complete. */
GLuint gpu_targets_fbo(struct gpu_targets *t, const char *name, const GLuint *colors, int ncolors,
                       GLuint depth, char *err, size_t errlen);

/* Bytes the pool holds, for results. */
double gpu_targets_bytes(const struct gpu_targets *t);

#endif
