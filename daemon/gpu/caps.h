#ifndef SHADEBENCH_GPU_CAPS_H
#define SHADEBENCH_GPU_CAPS_H

/* The device's limits, queried once when the context comes up, so that
 * techniques check a job against them without GL calls and /v1/info serves
 * them from HTTP threads. gpu_caps_query: render thread only; the filled
 * struct and its JSON are immutable afterwards and may be read anywhere. */

#include <jansson.h>
#include <stdbool.h>

#include "daemon/gpu/gpu_memory.h"

struct gpu_caps {
    int max_texture_size, max_renderbuffer_size, max_viewport[2];
    int max_color_attachments, max_draw_buffers, max_texture_units;
    int max_compute_work_group_count[3], max_compute_work_group_size[3];
    int max_compute_invocations, max_compute_shared_bytes, max_compute_image_uniforms;
    int max_ssbo_bindings, max_uniform_block_bytes;
    long long max_ssbo_bytes;
    int timer_query_bits;
    /* Multisampling: GL_MAX_SAMPLES, GL_MAX_COLOR_TEXTURE_SAMPLES,
     * GL_MAX_DEPTH_TEXTURE_SAMPLES, GL_MAX_INTEGER_SAMPLES, and max_msaa,
     * the most a job's "msaa" may ask: the least of the first three (the
     * harness's output and the g-buffers are multisampled textures, none of
     * them integer), capped at 8. */
    int max_samples, max_color_texture_samples, max_depth_texture_samples, max_integer_samples;
    int max_msaa;
    bool debug_groups; /* glPushDebugGroup available (KHR_debug / GL 4.3) */
};

void gpu_caps_query(struct gpu_caps *c);
/* New reference. */
json_t *gpu_caps_json(const struct gpu_caps *c);

/* GPU memory now, through GL (gpu_memory.h's reader over glGetIntegerv).
 * Render thread, context current; outside every timed region. */
void gpu_memory_sample_gl(struct gpu_memory_sample *out);

#endif
