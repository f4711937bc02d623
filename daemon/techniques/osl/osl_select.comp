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
//
// With a budget (osl.budget_texels, u_budget >= 0 blocks) the selection is
// cut by priority, deterministically whatever order the invocations run in:
// u_mode 0 lists only the blocks that must be shaded (the first frame, and
// blocks never shaded: nothing unshaded may be shown), and counts the other
// candidates in a histogram of priority keys (counts do not depend on
// order). u_mode 3 (one invocation) walks the keys from the highest down and
// sets the cut: the highest key whose candidates, added to the ones above,
// overrun the budget. u_mode 4 lists every candidate above the cut. The set
// shaded is a function of the counts and the keys alone; the list's order
// is not, but each entry is shaded on its own, so the image is the same.
layout(local_size_x = 64) in;

// Per block: x version held, y the last frame it held the scheduled shading,
// z the frame whose lights its shading is in effect (for the staleness of a
// read), w the last frame it was shaded; then (priority key or -1, 0, 0, 0).
layout(std430, binding = SB_SSBO_OSL_BLOCK_TILE) readonly buffer BlockTile { uint block_instance[]; };
layout(std430, binding = SB_SSBO_OSL_SHADED) buffer Shaded { ivec4 shaded[]; };
layout(std430, binding = SB_SSBO_OSL_VERSIONS) readonly buffer Versions { ivec2 versions[]; }; // version, light row
layout(std430, binding = SB_SSBO_OSL_LIST) writeonly buffer List { uvec2 list[]; };           // block, light row
layout(std430, binding = SB_SSBO_OSL_STATS) buffer Stats {
    uvec4 dispatch;     // groups x, y, z of the lighting pass; w: blocks selected this frame
    uint blocks_total;  // blocks shaded over the counted frames
    uint blocks_max;    // the most in one counted frame
    uint stale_blocks;  // blocks a counted frame's raster pass read with other shading
    int cut;            // this frame's priority cut (u_mode 3): keys above it are shaded
    uint overflow_frames; // counted frames whose must-shade blocks alone overran the budget
    uint deferred_total;  // candidates left for a later frame, over the counted frames
    uint unshaded_reads;  // blocks a counted frame read that were never shaded
    uint spare;
    uint age[64];         // blocks read over the counted frames (the staleness samples), by
                          // frames since the lights of their shading (63: 63 or more)
    uint hist[OSL_KEYS];  // this frame's candidates by priority key (with a budget)
};
layout(r32i, binding = SB_IMG_OSL_MARKS) readonly uniform iimage2D u_marks;

uniform int u_frame_index;
uniform int u_initial;
uniform int u_mode;       // 0 select, 1 size the dispatch, 2 only count the last frame's reads,
                          // 3 set the budget's cut, 4 list the candidates above it
uniform int u_count;      // this frame counts towards the figures
uniform int u_count_prev; // and the frame before
uniform int u_seen_since; // a mark from this frame on counts as seen (INT_MIN + 1: any mark)
uniform int u_margin;     // blocks around a marked one that count as seen (motion)
uniform ivec2 u_blocks;   // the atlas in blocks
uniform int u_max_groups; // the device's work-group count limit in x
uniform int u_budget;     // blocks a frame may shade; -1: no limit

const int NEVER = int(0x80000000u); // INT_MIN: no shading held

// Priority: how many frames the block has been behind its schedule (1 to
// 31), doubled in weight when the raster pass read the block itself rather
// than a neighbour; the low bits spread blocks of one level over OSL_KEYS /
// 64 sub-keys by a hash of the block, so that the cut inside a level is
// deterministic and leaves little of the budget unused.
int priority(uint b, ivec4 held, bool read_itself)
{
    int lag = clamp(u_frame_index - held.y, 1, 31);
    int level = (read_itself ? 32 : 0) + lag;
    uint h = b * 2654435761u;
    return level * (OSL_KEYS / 64) + int(h >> 28) % (OSL_KEYS / 64);
}

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
    if (u_mode == 3) {
        if (gl_LocalInvocationIndex != 0u)
            return;
        int left = u_budget - int(dispatch.w);
        if (left < 0 && u_count != 0)
            overflow_frames += 1u;
        cut = -1;
        uint sum = 0u, total = 0u;
        for (int k = OSL_KEYS - 1; k >= 0; k--) {
            total += hist[k];
            if (cut < 0 && sum + hist[k] > uint(max(left, 0)))
                cut = k;
            if (cut < 0)
                sum += hist[k];
            hist[k] = 0u; // ready for the next frame
        }
        if (u_count != 0)
            deferred_total += total - sum;
        return;
    }
    uint b = gl_GlobalInvocationID.x;
    if (b >= uint(u_blocks.x * u_blocks.y))
        return;
    uint inst = block_instance[b];
    if (inst == 0xffffffffu)
        return;
    inst &= 0xffffffu; // the level above bit 24
    ivec4 held = shaded[b * 2u];
    if (u_mode == 4) {
        int key = shaded[b * 2u + 1u].x;
        if (key > cut) {
            ivec2 v = versions[inst];
            list[atomicAdd(dispatch.w, 1u)] = uvec2(b, uint(v.y));
            shaded[b * 2u] = ivec4(v.x, u_frame_index, u_frame_index - v.y, u_frame_index);
        }
        return;
    }
    ivec2 at = ivec2(int(b) % u_blocks.x, int(b) / u_blocks.x);
    int mark = imageLoad(u_marks, at).x;
    // The frame before read this block: did it hold that frame's shading,
    // and how old were the lights it was shaded with?
    // (A still camera marked once: every mark is a read of every frame.)
    bool read_prev = u_seen_since == NEVER + 1 ? mark >= u_seen_since : mark == u_frame_index - 1;
    if (u_count_prev != 0 && read_prev) {
        if (held.y != u_frame_index - 1)
            atomicAdd(stale_blocks, 1u);
        if (held.x == NEVER) {
            atomicAdd(unshaded_reads, 1u);
        } else {
            atomicAdd(age[clamp(u_frame_index - 1 - held.z, 0, 63)], 1u);
        }
    }
    if (u_mode == 2)
        return;
    ivec2 v = versions[inst];
    int key = -1;
    if (held.x != v.x) {
        bool seen = u_initial != 0;
        for (int dy = -u_margin; dy <= u_margin && !seen; dy++)
            for (int dx = -u_margin; dx <= u_margin && !seen; dx++) {
                ivec2 q = at + ivec2(dx, dy);
                if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, u_blocks)))
                    seen = imageLoad(u_marks, q).x >= u_seen_since;
            }
        if (seen) {
            if (u_budget < 0 || u_initial != 0 || held.x == NEVER) {
                list[atomicAdd(dispatch.w, 1u)] = uvec2(b, uint(v.y));
                shaded[b * 2u] = ivec4(v.x, u_frame_index, u_frame_index - v.y, u_frame_index);
            } else {
                key = priority(b, held, mark >= u_seen_since);
                atomicAdd(hist[key], 1u);
            }
        }
    } else {
        // Holds what the schedule asks: its lights are in effect as of s(k).
        shaded[b * 2u] = ivec4(v.x, u_frame_index, u_frame_index - v.y, held.w);
    }
    if (u_budget >= 0)
        shaded[b * 2u + 1u].x = key;
}
