// Light binning, first half: one invocation per light finds the cells its
// sphere touches (the tight screen rectangle, then the slices or the tile's
// depth bounds, then a sphere-box test per cell) and sets its bit in each,
// and on a word's first bit the word's bit in the cell's summary. Bits make
// the result independent of invocation order, so the lists
// light_compact.comp writes are the same every run; the summary lets it
// visit only the words that hold lights (and zero them for the next frame).
// A spot light's sphere is its cone's bounding sphere (light_shape.glsl),
// and a cell that sphere touches is kept only if the cone itself may touch
// the cell's bounding sphere (Wronski's cone test). A directional light
// lights everything: its bit goes into every cell (of tiles, every tile with
// a surface), so lists stay in ascending index order, as forward sums.
#include "light_grid.glsl"
#include "light_bounds.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = SB_SSBO_LIGHT_BITS) buffer LightBits { uint light_bits[]; };
layout(std430, binding = SB_SSBO_LIGHT_SUMMARY) buffer LightSummary { uint light_summary[]; };
#if defined(GRID_TILES)
layout(std430, binding = SB_SSBO_TILE_DEPTH) readonly buffer TileDepth { vec2 tile_depth[]; };
#endif

// View-space x (or y) per unit of view depth at window coordinate px on an
// axis of size pixels, for the projection's scale and off-centre terms.
float view_slope(float px, float size, float p_scale, float p_shift)
{
    return (px / size * 2.0 - 1.0 + p_shift) / p_scale;
}

void main()
{
    int i = int(gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u + gl_GlobalInvocationID.x);
    if (i >= u_grid.counts.x)
        return;
    vec3 apex = light_position(i, 0), world;
    float r;
    // An orthographic view (scene.camera's "orthographic") has no frusta to
    // test cells with: every light is binned everywhere, exact but slower.
    bool ortho = u_frame.proj[2][3] == 0.0;
    bool everywhere = !light_bound_sphere(i, apex, world, r) || ortho;
    bool spot = light_type(i) == LIGHT_SPOT && !ortho;
    ivec4 rect = everywhere ? ivec4(0, 0, ivec2(u_frame.viewport.xy))
                            : light_rect(LIGHT_RECT_TIGHT, world, r);
    if (rect.x >= rect.z || rect.y >= rect.w)
        return;
    vec3 c = (u_frame.view * vec4(world, 1.0)).xyz;
    // The cone in view space, and the slack its test is given: the test's
    // rounding must never leave out a cell a sliver of the cone lights.
    vec3 apex_v = (u_frame.view * vec4(apex, 1.0)).xyz;
    vec3 axis_v = mat3(u_frame.view) * lights[i].direction_type.xyz;
    float range = lights[i].color_radius.w, cone_slack = 1e-3 * range + 1e-4;
    ivec2 size = ivec2(u_grid.tile.xy);
    ivec2 t0 = rect.xy / size, t1 = min((rect.zw - 1) / size, u_grid.dims.xy - 1);
    int z0 = 0, z1 = 0;
#if !defined(GRID_TILES)
    z0 = everywhere ? 0 : grid_slice(max(-c.z - r, u_frame.clip.x));
    z1 = everywhere ? u_grid.dims.z - 1 : grid_slice(-c.z + r);
#endif
    float px = u_frame.proj[0][0], sx = u_frame.proj[2][0];
    float py = u_frame.proj[1][1], sy = u_frame.proj[2][1];
    vec2 vp = u_frame.viewport.xy;
    uint word = uint(i) >> 5u, bit = 1u << (uint(i) & 31u);
    for (int z = z0; z <= z1; z++) {
#if !defined(GRID_TILES)
        vec2 dr = vec2(grid_slice_start(z), grid_slice_start(z + 1));
        // The slab's nearest depth to the centre: with a row's nearest y it
        // skips whole rows of the slab that the sphere misses.
        float dz = c.z - clamp(c.z, -dr.y - 1e-3 * dr.y - 1e-4, -dr.x + 1e-3 * dr.y + 1e-4);
#endif
        for (int ty = t0.y; ty <= t1.y; ty++) {
            float y0 = view_slope(float(ty) * u_grid.tile.y, vp.y, py, sy);
            float y1 = view_slope(min(float(ty + 1) * u_grid.tile.y, vp.y), vp.y, py, sy);
#if !defined(GRID_TILES)
            float pad_row = 1e-3 * dr.y + 1e-4;
            float dy = c.y - clamp(c.y, y0 * (y0 >= 0.0 ? dr.x : dr.y) - pad_row,
                                   y1 * (y1 >= 0.0 ? dr.y : dr.x) + pad_row);
            if (!everywhere && dz * dz + dy * dy > r * r)
                continue;
#endif
            for (int tx = t0.x; tx <= t1.x; tx++) {
                int cell = (z * u_grid.dims.y + ty) * u_grid.dims.x + tx;
#if defined(GRID_TILES)
                vec2 dr = tile_depth[cell];
                if (dr.x > dr.y)
                    continue; // no surface in this tile
#endif
                // The cell's view-space box (x and y grow linearly with depth
                // along the tile's sides), padded by a thousandth of its depth
                // so that rounding where the shader picks a pixel's cell never
                // leaves a light out.
                float x0 = view_slope(float(tx) * u_grid.tile.x, vp.x, px, sx);
                float x1 = view_slope(min(float(tx + 1) * u_grid.tile.x, vp.x), vp.x, px, sx);
                float pad = 1e-3 * dr.y + 1e-4;
                vec3 lo = vec3(x0 * (x0 >= 0.0 ? dr.x : dr.y), y0 * (y0 >= 0.0 ? dr.x : dr.y),
                               -dr.y) - pad;
                vec3 hi = vec3(x1 * (x1 >= 0.0 ? dr.y : dr.x), y1 * (y1 >= 0.0 ? dr.y : dr.x),
                               -dr.x) + pad;
                vec3 q = clamp(c, lo, hi) - c;
                bool touches = everywhere || dot(q, q) <= r * r;
                if (touches && spot)
                    touches = light_cone_touches_sphere(apex_v, axis_v, range,
                                                        lights[i].cone.x, lights[i].cone.w,
                                                        0.5 * (lo + hi),
                                                        0.5 * length(hi - lo) + cone_slack);
                if (touches &&
                    atomicOr(light_bits[cell * u_grid.lists.z + int(word)], bit) == 0u)
                    atomicOr(light_summary[cell * u_grid.counts.z + int(word >> 5u)],
                             1u << (word & 31u));
            }
        }
    }
}
