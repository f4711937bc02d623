// The light grid shared by tiled and clustered shading: screen tiles of
// u_grid.tile pixels, cut into depth slices for clusters (one slice for
// tiles), each cell pointing at its list of light indices in ascending
// order. daemon/techniques/shared/light_grid.c builds it; struct
// light_grid_block there is this block's layout.
#include "lighting.glsl"

layout(std140, binding = SB_UBO_LIGHT_GRID) uniform LightGridBlock {
    ivec4 dims;   // cells in x, y, z; cells in all
    vec4 tile;    // tile width, height in pixels; their reciprocals
    vec4 slices;  // view depth where the slices start and end, slices per unit
                  // (linear) or per unit of log depth (exponential), 1 = exponential
    ivec4 lists;  // most lights a cell keeps (0: lists placed by offset), index
                  // capacity, 32-bit words of light bits per cell, 1 = overflow falls back
    ivec4 counts; // lights, statistics record of this frame, 32-bit summary
                  // words per cell (one bit per word of light bits)
} u_grid;

const uint CELL_OVERFLOW = 0x80000000u;

// Per cell: offset into light_index, kept count | CELL_OVERFLOW.
layout(std430, binding = SB_SSBO_LIGHT_GRID) buffer LightCells { uvec2 light_cells[]; };
layout(std430, binding = SB_SSBO_LIGHT_INDICES) buffer LightIndices { uint light_index[]; };

// The slice holding view depth d (distance along the view axis).
int grid_slice(float d)
{
    float s = u_grid.slices.w > 0.5 ? log(d / u_grid.slices.x) * u_grid.slices.z
                                    : (d - u_grid.slices.x) * u_grid.slices.z;
    return clamp(int(floor(s)), 0, u_grid.dims.z - 1);
}

// View depth where slice k starts (k = dims.z: where the last one ends);
// the first and last slices reach the near and far planes.
float grid_slice_start(int k)
{
    if (k <= 0)
        return u_frame.clip.x;
    if (k >= u_grid.dims.z)
        return u_frame.clip.y;
    return u_grid.slices.w > 0.5 ? u_grid.slices.x * exp(float(k) / u_grid.slices.z)
                                 : u_grid.slices.x + float(k) / u_grid.slices.z;
}

// The cell of the pixel at window position frag (a pixel centre) whose
// surface lies at view depth d.
int grid_cell(vec2 frag, float d)
{
    ivec2 t = min(ivec2(frag * u_grid.tile.zw), u_grid.dims.xy - 1);
    int z = u_grid.dims.z > 1 ? grid_slice(d) : 0;
    return (z * u_grid.dims.y + t.y) * u_grid.dims.x + t.x;
}

// Ambient plus every light of the cell's list, in ascending index order as
// forward sums them (lights left out contribute exactly 0 there, so the
// sums agree). An overflowed cell under the fallback policy loops over
// every light: slower, never wrong. evaluations: lights evaluated.
// The ambient term is scaled by occlusion (asset materials' occlusion
// maps, surface.glsl; 1 elsewhere).
vec3 shade_cell(int cell, vec3 P, vec3 N, Material m, float occlusion, out uint evaluations)
{
    vec3 V = normalize(u_frame.eye.xyz - P);
    vec3 color = occlusion * light_ambient(m, P, N, V);
    uvec2 c = light_cells[cell];
    if ((c.y & CELL_OVERFLOW) != 0u && u_grid.lists.w != 0) {
        for (int i = 0; i < u_frame.counts.y; i++)
            color += light_contribution(i, light_position(i, 0), P, N, V, m);
        evaluations = uint(u_frame.counts.y);
        return color;
    }
    uint count = c.y & ~CELL_OVERFLOW;
    for (uint j = 0u; j < count; j++) {
        int i = int(light_index[c.x + j]);
        color += light_contribution(i, light_position(i, 0), P, N, V, m);
    }
    evaluations = count;
    return color;
}

vec3 shade_cell(int cell, vec3 P, vec3 N, Material m, out uint evaluations)
{
    return shade_cell(cell, P, N, m, 1.0, evaluations);
}
