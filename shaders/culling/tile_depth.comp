// Per-tile depth bounds for tiled shading: the nearest and farthest view
// depth of the surfaces in each tile (background excluded), one work group
// per tile. A tile with no surface gets an empty range (near > far). With
// MSAA every sample counts: a light that touches only an edge pixel's far
// sample still lands in the tile's list.
#include "light_grid.glsl"
#include "msaa.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = SB_TEX_DEPTH) uniform msaa_sampler2D u_depth;
layout(std430, binding = SB_SSBO_TILE_DEPTH) writeonly buffer TileDepth { vec2 tile_depth[]; };

shared uint s_near, s_far;

void main()
{
    if (gl_LocalInvocationIndex == 0u) {
        s_near = floatBitsToUint(3.0e38);
        s_far = 0u;
    }
    barrier();
    ivec2 tile = ivec2(gl_WorkGroupID.xy);
    ivec2 size = ivec2(u_grid.tile.xy);
    ivec2 start = tile * size, end = min(start + size, ivec2(u_frame.viewport.xy));
    float lo = 3.0e38, hi = 0.0;
    for (int y = start.y + int(gl_LocalInvocationID.y); y < end.y; y += 8)
        for (int x = start.x + int(gl_LocalInvocationID.x); x < end.x; x += 8)
            for (int i = 0; i < MSAA_SAMPLES; i++) {
                float depth = msaa_fetch(u_depth, ivec2(x, y), i).r;
                if (depth < 1.0) {
                    // View depth from the depth-buffer value (the projection's z row;
                    // an orthographic one's is linear).
                    float d = u_frame.proj[2][3] == 0.0
                                  ? (u_frame.proj[3][2] - (depth * 2.0 - 1.0)) / u_frame.proj[2][2]
                                  : u_frame.proj[3][2] / (depth * 2.0 - 1.0 + u_frame.proj[2][2]);
                    lo = min(lo, d);
                    hi = max(hi, d);
                }
            }
    // Non-negative floats order as their bit patterns do.
    if (hi > 0.0) {
        atomicMin(s_near, floatBitsToUint(lo));
        atomicMax(s_far, floatBitsToUint(hi));
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u)
        tile_depth[tile.y * u_grid.dims.x + tile.x] =
            s_far == 0u ? vec2(1.0, 0.0) : vec2(uintBitsToFloat(s_near), uintBitsToFloat(s_far));
}
