// OSL's "seen" visibility (osl.visibility): which 8x8 atlas blocks to shade
// this frame, one invocation per block. A block is shaded when the raster
// pass sampled it or a neighbour in the frame before (the margin for
// motion), or on the first frame, and the shading it holds is not the one
// its object's schedule asks for now (u_versions: the due frame s(k), or one
// value for "no moving light reaches it"). The blocks go to a list that the
// lighting pass consumes by an indirect dispatch, whose size a second
// dispatch (u_mode 1) writes. Each block also records the last frame at
// which it held its scheduled shading, so that the next frame counts the
// blocks the raster pass read while they held other shading (u_mode 2 counts
// only that, after the last frame). With a still camera the raster pass
// marks once, on the first frame, every mark counts (u_seen_since) and no
// margin is needed: every frame reads the blocks the first one read.
layout(local_size_x = 64) in;

layout(std430, binding = SB_SSBO_OSL_BLOCK_TILE) readonly buffer BlockTile { uint block_instance[]; };
layout(std430, binding = SB_SSBO_OSL_SHADED) buffer Shaded { ivec2 shaded[]; }; // version held, frame it was the scheduled one
layout(std430, binding = SB_SSBO_OSL_VERSIONS) readonly buffer Versions { ivec2 versions[]; }; // version, light row
layout(std430, binding = SB_SSBO_OSL_LIST) writeonly buffer List { uvec2 list[]; };           // block, light row
layout(std430, binding = SB_SSBO_OSL_STATS) buffer Stats {
    uvec4 dispatch;     // groups x, y, z of the lighting pass; w: blocks selected this frame
    uint blocks_total;  // blocks shaded over the counted frames
    uint blocks_max;    // the most in one counted frame
    uint stale_blocks;  // blocks a counted frame's raster pass read with other shading
};
layout(r32i, binding = SB_IMG_OSL_MARKS) readonly uniform iimage2D u_marks;

uniform int u_frame_index;
uniform int u_initial;
uniform int u_mode;       // 0 select, 1 size the dispatch, 2 only count the last frame's stale reads
uniform int u_count;      // this frame counts towards the figures
uniform int u_count_prev; // and the frame before
uniform int u_seen_since; // a mark from this frame on counts as seen (INT_MIN + 1: any mark)
uniform int u_margin;     // blocks around a marked one that count as seen (motion)
uniform ivec2 u_blocks;   // the atlas in blocks
uniform int u_max_groups; // the device's work-group count limit in x

void main()
{
    if (u_mode == 1) {
        if (gl_LocalInvocationIndex != 0u)
            return; // one invocation of the one group
        uint n = dispatch.w;
        uint x = min(n, uint(u_max_groups));
        dispatch.xyz = uvec3(x, x == 0u ? 0u : (n + x - 1u) / x, 1u);
        if (u_count != 0) {
            blocks_total += n;
            blocks_max = max(blocks_max, n);
        }
        return;
    }
    uint b = gl_GlobalInvocationID.x;
    if (b >= uint(u_blocks.x * u_blocks.y))
        return;
    uint inst = block_instance[b];
    if (inst == 0xffffffffu)
        return;
    ivec2 at = ivec2(int(b) % u_blocks.x, int(b) / u_blocks.x);
    int mark = imageLoad(u_marks, at).x;
    ivec2 held = shaded[b];
    // The frame before read this block: did it hold that frame's shading?
    if (u_count_prev != 0 && mark == u_frame_index - 1 && held.y != u_frame_index - 1)
        atomicAdd(stale_blocks, 1u);
    if (u_mode == 2)
        return;
    ivec2 v = versions[inst];
    if (held.x != v.x) {
        bool seen = u_initial != 0;
        for (int dy = -u_margin; dy <= u_margin && !seen; dy++)
            for (int dx = -u_margin; dx <= u_margin && !seen; dx++) {
                ivec2 q = at + ivec2(dx, dy);
                if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, u_blocks)))
                    seen = imageLoad(u_marks, q).x >= u_seen_since;
            }
        if (!seen)
            return;
        list[atomicAdd(dispatch.w, 1u)] = uvec2(b, uint(v.y));
    }
    shaded[b] = ivec2(v.x, u_frame_index);
}
