#ifndef SHADEBENCH_GPU_PASS_H
#define SHADEBENCH_GPU_PASS_H

/* Named, timed passes and the per-frame uniform block. Not a render graph:
 * a technique calls gpu_pass_begin/end around each of its passes, in the
 * order its info declares them, and the harness adds its own (resolve).
 *
 * gpu_pass_begin opens the pass's GPU timer section and a debug group named
 * after it (so apitrace and RenderDoc captures read as the result does),
 * binds the framebuffer and its full viewport, and sets the baseline state
 * every pass may assume:
 *   depth test on (GL_LESS), depth writes on, back faces culled (CCW front),
 *   blending, scissor and stencil off, all colour channels written.
 * Programs, vertex arrays, buffers and textures are left as they are: a pass
 * binds what it uses. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stdint.h>

#include "daemon/gpu/gpu_timer.h"

#define GPU_MAX_PASSES GPU_TIMER_MAX_SECTIONS

struct gpu_passes {
    struct gpu_timer *timer;
    const char *names[GPU_MAX_PASSES];
    int count;
    bool debug_groups;
};

/* names: NULL-terminated; false when there are more than GPU_MAX_PASSES. */
bool gpu_passes_init(struct gpu_passes *p, struct gpu_timer *timer, const char *const *names,
                     bool debug_groups);
/* Appends a harness pass; returns its index or -1. */
int gpu_passes_add(struct gpu_passes *p, const char *name);

void gpu_pass_begin(const struct gpu_passes *p, int pass, GLuint fbo, int w, int h);
void gpu_pass_end(const struct gpu_passes *p);

/* The per-frame uniform block (std140), bound at SB_UBO_FRAME for every
 * program: shaders/common/frame.glsl declares the same layout. proj and
 * everything made from it carry this frame's jitter (the projection's
 * sub-pixel offset, 0 unless a stage asks for it: common/frame_needs.h);
 * unjittered_view_proj and prev_view_proj are without it, for motion. */
struct gpu_frame_data {
    float view[16], proj[16], view_proj[16];
    float inv_view[16], inv_proj[16], inv_view_proj[16];
    float eye[4];      /* xyz */
    float viewport[4]; /* width, height, 1/width, 1/height */
    float clip[4];     /* near, far */
    int32_t counts[4]; /* frame (low 31 bits), lights, instances */
    float unjittered_view_proj[16]; /* this frame's, without the jitter */
    float prev_view_proj[16];       /* the frame before's, without its jitter */
    float jitter[4];                /* pixels: this frame's offset (xy), the frame before's (zw) */
};

/* What the harness tells a frame's stages of time (the frame contract):
 * the frame's index, whether a history kept from the frames before must be
 * dropped at it (the first frame an instance draws, and history_frames
 * before each captured frame, so that frame k stays a pure function of k),
 * and this frame's jitter in pixels. Valid during the frame. */
struct gpu_frame_time {
    int64_t frame;
    bool restart;
    float jitter[2];
};

struct gpu_frame_block {
    GLuint ubo;
};

bool gpu_frame_block_init(struct gpu_frame_block *b);
void gpu_frame_block_finish(struct gpu_frame_block *b);
/* Uploads d and binds it at SB_UBO_FRAME. */
void gpu_frame_block_update(struct gpu_frame_block *b, const struct gpu_frame_data *d);

/* Column-major 4x4 inverse (general); false when singular. */
bool mat4_invert(const float m[16], float out[16]);

#endif
