// The per-frame uniform block: daemon/gpu/pass.h, struct gpu_frame_data.
layout(std140, binding = SB_UBO_FRAME) uniform FrameBlock {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view;
    mat4 inv_proj;
    mat4 inv_view_proj;
    vec4 eye;      // xyz
    vec4 viewport; // width, height, 1/width, 1/height
    vec4 clip;     // near, far
    ivec4 counts;  // frame, lights, instances
    // proj and the matrices made from it carry this frame's jitter; these
    // two are without it (motion vectors).
    mat4 unjittered_view_proj;
    mat4 prev_view_proj; // the frame before's
    vec4 jitter;         // pixels: this frame's offset (xy), the frame before's (zw)
} u_frame;
