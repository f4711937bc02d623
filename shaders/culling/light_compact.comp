// Light binning, second half: one invocation per cell turns its bits into a
// list of light indices in ascending order. Clusters keep at most
// u_grid.lists.x lights in a slot of their own; tiles take what they need
// from a shared index buffer. A cell that does not fit is flagged
// CELL_OVERFLOW and counted (cells, lights dropped) in this frame's
// statistics record: overflow is never silent.
#include "light_grid.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = SB_SSBO_LIGHT_BITS) readonly buffer LightBits { uint light_bits[]; };
// Per frame: overflowed cells, lights dropped, fullest cell, entries handed
// out, entries kept, cells with lights, 2 spare (struct light_grid_stats).
layout(std430, binding = SB_SSBO_CULL_STATS) buffer CullStats { uint cull_stats[]; };

void main()
{
    int cell = int(gl_GlobalInvocationID.x);
    if (cell >= u_grid.dims.w)
        return;
    int words = u_grid.lists.z, base = cell * words;
    uint count = 0u;
    for (int w = 0; w < words; w++)
        count += uint(bitCount(light_bits[base + w]));
    uint rec = uint(u_grid.counts.y) * 8u;
    uint keep = count, offset = 0u;
    bool overflow = false;
    if (u_grid.lists.x > 0) {
        offset = uint(cell * u_grid.lists.x);
        if (count > uint(u_grid.lists.x)) {
            keep = uint(u_grid.lists.x);
            overflow = true;
        }
    } else if (count > 0u) {
        offset = atomicAdd(cull_stats[rec + 3u], count);
        if (offset + count > uint(u_grid.lists.y)) {
            keep = 0u;
            offset = 0u;
            overflow = true;
        }
    }
    if (overflow) {
        atomicAdd(cull_stats[rec + 0u], 1u);
        atomicAdd(cull_stats[rec + 1u], count - keep);
    }
    if (count > 0u) {
        atomicMax(cull_stats[rec + 2u], count);
        atomicAdd(cull_stats[rec + 4u], keep);
        atomicAdd(cull_stats[rec + 5u], 1u);
    }
    uint n = 0u;
    for (int w = 0; w < words && n < keep; w++) {
        uint b = light_bits[base + w];
        while (b != 0u && n < keep) {
            light_index[offset + n] = uint(w * 32 + findLSB(b));
            n++;
            b &= b - 1u;
        }
    }
    light_cells[cell] = uvec2(offset, keep | (overflow ? CELL_OVERFLOW : 0u));
}
