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

/* The same, multisampled with samples samples a pixel when samples > 1
 * (a GL_TEXTURE_2D_MULTISAMPLE with fixed sample locations); samples 1 is
 * gpu_targets_texture. A name keeps one texture: asking with another count
 * re-creates it. */
GLuint gpu_targets_texture_ms(struct gpu_targets *t, const char *name, GLenum format, int w,
                              int h, int samples, char *err, size_t errlen);
/* A pool texture's samples as the driver allocated them (which may be more
 * than asked; 1 for a texture the pool does not hold), and the
 * target it binds as (GL_TEXTURE_2D or GL_TEXTURE_2D_MULTISAMPLE). */
int gpu_targets_samples(const struct gpu_targets *t, GLuint tex);
GLenum gpu_targets_kind(const struct gpu_targets *t, GLuint tex);

/* The framebuffer named name with these colour attachments (in draw-buffer
 * order) and depth texture (0 for none), checked complete. */
GLuint gpu_targets_fbo(struct gpu_targets *t, const char *name, const GLuint *colors, int ncolors,
                       GLuint depth, char *err, size_t errlen);

/* Bytes the pool holds (multisampled textures: every sample the driver
 * allocated), for results. */
double gpu_targets_bytes(const struct gpu_targets *t);

/* The pool keeps targets between jobs; what one run takes is the bytes of
 * the targets asked for since the last gpu_targets_new_epoch (the harness
 * starts one with each measured run), leftovers of earlier jobs excluded. */
void gpu_targets_new_epoch(struct gpu_targets *t);
double gpu_targets_bytes_in_use(const struct gpu_targets *t);

#endif
