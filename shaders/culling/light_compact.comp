// Light binning, second half: one invocation per cell turns its bits into a
// list of light indices in ascending order, packed into the shared index
// buffer. Clusters keep at most u_grid.lists.x lights. A cell over that
// bound, or that finds the buffer full, is flagged CELL_OVERFLOW and counted
// (cells, lights dropped) in this frame's statistics record: overflow is
// never silent. Under the fallback policy such a cell shades with every
// light and needs no list at all.
#include "light_grid.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = SB_SSBO_LIGHT_BITS) buffer LightBits { uint light_bits[]; };
layout(std430, binding = SB_SSBO_LIGHT_SUMMARY) buffer LightSummary { uint light_summary[]; };
// Per frame: overflowed cells, lights dropped, fullest cell, entries handed
// out, entries kept, cells with lights, 2 spare (struct light_grid_stats).
layout(std430, binding = SB_SSBO_CULL_STATS) buffer CullStats { uint cull_stats[]; };

void main()
{
    int cell = int(gl_GlobalInvocationID.x);
    if (cell >= u_grid.dims.w)
        return;
    // Only the words the summary marks hold lights: count them first.
    int base = cell * u_grid.lists.z, sbase = cell * u_grid.counts.z;
    uint count = 0u;
    for (int sw = 0; sw < u_grid.counts.z; sw++) {
        uint s = light_summary[sbase + sw];
        while (s != 0u) {
            count += uint(bitCount(light_bits[base + sw * 32 + findLSB(s)]));
            s &= s - 1u;
        }
    }
    uint rec = uint(u_grid.counts.y) * 8u;
    // fits: the lights the bound lets the list hold; keep: those written
    // (none when an overflowed cell falls back to every light anyway).
    uint fits = u_grid.lists.x > 0 ? min(count, uint(u_grid.lists.x)) : count;
    bool overflow = fits < count;
    uint keep = overflow && u_grid.lists.w != 0 ? 0u : fits, offset = 0u;
    if (keep > 0u) {
        offset = atomicAdd(cull_stats[rec + 3u], keep);
        if (offset + keep > uint(u_grid.lists.y)) {
            fits = keep = offset = 0u;
            overflow = true;
        }
    }
    if (overflow) {
        atomicAdd(cull_stats[rec + 0u], 1u);
        atomicAdd(cull_stats[rec + 1u], count - fits);
    }
    if (count > 0u) {
        atomicMax(cull_stats[rec + 2u], count);
        atomicAdd(cull_stats[rec + 4u], keep);
        atomicAdd(cull_stats[rec + 5u], 1u);
    }
    // Write the list in ascending order, zeroing every word read and the
    // summary, so that the next frame starts from empty bits without a clear.
    uint n = 0u;
    for (int sw = 0; sw < u_grid.counts.z; sw++) {
        uint s = light_summary[sbase + sw];
        light_summary[sbase + sw] = 0u;
        while (s != 0u) {
            int w = sw * 32 + findLSB(s);
            s &= s - 1u;
            uint b = light_bits[base + w];
            light_bits[base + w] = 0u;
            while (b != 0u && n < keep) {
                light_index[offset + n] = uint(w * 32 + findLSB(b));
                n++;
                b &= b - 1u;
            }
        }
    }
    light_cells[cell] = uvec2(offset, keep | (overflow ? CELL_OVERFLOW : 0u));
}
