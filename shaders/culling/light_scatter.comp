// Light binning, first half: one invocation per light finds the cells its
// sphere touches (the tight screen rectangle, then the slices or the tile's
// depth bounds, then a sphere-box test per cell) and sets the light's bit
// in each. Bits make the result independent of invocation order, so the
// lists light_compact.comp writes are the same every run.
#include "light_grid.glsl"
#include "light_bounds.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = SB_SSBO_LIGHT_BITS) buffer LightBits { uint light_bits[]; };
#if defined(GRID_TILES)
layout(std430, binding = SB_SSBO_TILE_DEPTH) readonly buffer TileDepth { vec2 tile_depth[]; };
#endif

// View-space x (or y) at view depth d of the window coordinate px along an
// axis of the projection (scale and off-centre term).
float view_at(float px, float size, float d, float p_scale, float p_shift)
{
    float ndc = px / size * 2.0 - 1.0;
    return (ndc + p_shift) * d / p_scale;
}

void main()
{
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_grid.counts.x)
        return;
    vec3 world = light_position(i, 0);
    float r = lights[i].color_radius.w;
    ivec4 rect = light_rect(LIGHT_RECT_TIGHT, world, r);
    if (rect.x >= rect.z || rect.y >= rect.w)
        return;
    vec3 c = (u_frame.view * vec4(world, 1.0)).xyz;
    ivec2 size = ivec2(u_grid.tile.xy);
    ivec2 t0 = rect.xy / size, t1 = min((rect.zw - 1) / size, u_grid.dims.xy - 1);
    int z0 = 0, z1 = 0;
#if !defined(GRID_TILES)
    z0 = grid_slice(max(-c.z - r, u_frame.clip.x));
    z1 = grid_slice(-c.z + r);
#endif
    float px = u_frame.proj[0][0], sx = u_frame.proj[2][0];
    float py = u_frame.proj[1][1], sy = u_frame.proj[2][1];
    uint word = uint(i) >> 5u, bit = 1u << (uint(i) & 31u);
    for (int z = z0; z <= z1; z++) {
        for (int ty = t0.y; ty <= t1.y; ty++) {
            for (int tx = t0.x; tx <= t1.x; tx++) {
                int cell = (z * u_grid.dims.y + ty) * u_grid.dims.x + tx;
#if defined(GRID_TILES)
                vec2 dr = tile_depth[cell];
                if (dr.x > dr.y)
                    continue; // no surface in this tile
#else
                vec2 dr = vec2(grid_slice_start(z), grid_slice_start(z + 1));
#endif
                // The cell's view-space box, padded by a thousandth of its depth so
                // that rounding where the shader picks a pixel's cell never leaves a
                // light out.
                float pad = 1e-3 * dr.y + 1e-4;
                vec2 xr = vec2(float(tx * size.x), float(min((tx + 1) * size.x, int(u_frame.viewport.x))));
                vec2 yr = vec2(float(ty * size.y), float(min((ty + 1) * size.y, int(u_frame.viewport.y))));
                float x00 = view_at(xr.x, u_frame.viewport.x, dr.x, px, sx);
                float x01 = view_at(xr.x, u_frame.viewport.x, dr.y, px, sx);
                float x10 = view_at(xr.y, u_frame.viewport.x, dr.x, px, sx);
                float x11 = view_at(xr.y, u_frame.viewport.x, dr.y, px, sx);
                float y00 = view_at(yr.x, u_frame.viewport.y, dr.x, py, sy);
                float y01 = view_at(yr.x, u_frame.viewport.y, dr.y, py, sy);
                float y10 = view_at(yr.y, u_frame.viewport.y, dr.x, py, sy);
                float y11 = view_at(yr.y, u_frame.viewport.y, dr.y, py, sy);
                vec3 lo = vec3(min(min(x00, x01), min(x10, x11)), min(min(y00, y01), min(y10, y11)),
                               -dr.y) - pad;
                vec3 hi = vec3(max(max(x00, x01), max(x10, x11)), max(max(y00, y01), max(y10, y11)),
                               -dr.x) + pad;
                vec3 q = clamp(c, lo, hi) - c;
                if (dot(q, q) <= r * r)
                    atomicOr(light_bits[cell * u_grid.lists.z + int(word)], bit);
            }
        }
    }
}
