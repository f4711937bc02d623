// The harness's motion vectors, camera motion (daemon/harness/motion.h):
// each pixel's surface rebuilt from the depth with this frame's (jittered)
// inverse view-projection, then projected with this frame's and the frame
// before's unjittered view-projections; pixels, this frame minus the one
// before. A still camera gives exactly 0: both projections are one matrix.
#include "frame.glsl"
layout(binding = SB_TEX_POST_DEPTH) uniform sampler2D u_depth;
layout(location = 0) out vec2 out_motion;

void main()
{
    float z = texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r;
    vec2 ndc = gl_FragCoord.xy * u_frame.viewport.zw * 2.0 - 1.0;
    vec4 world = u_frame.inv_view_proj * vec4(ndc, z * 2.0 - 1.0, 1.0);
    world /= world.w;
    vec4 now = u_frame.unjittered_view_proj * world;
    vec4 before = u_frame.prev_view_proj * world;
    // A surface behind the camera the frame before has no place there:
    // no motion rather than a mirrored one.
    out_motion = before.w > 0.0
                     ? (now.xy / now.w - before.xy / before.w) * 0.5 * u_frame.viewport.xy
                     : vec2(0.0);
}
