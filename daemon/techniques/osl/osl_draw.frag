in vec2 v_uv;
flat in vec4 v_chart;
flat in ivec4 v_tile;
layout(location = 0) out vec4 out_color;

#ifdef OSL_SEEN
// osl.visibility "seen": mark the atlas blocks this fragment's bilinear
// footprint reads, with the frame. The next frame shades what was seen and
// checks that each block read here held its scheduled shading
// (osl_select.comp). Only fragments that pass the depth test mark, except
// in asset scenes: there an alpha-masked fragment may discard, and early
// fragment tests would write its depth all the same, so the tests run late
// and fragments behind others mark too (more shading, never less).
#if !defined(SCENE_TEXTURED)
layout(early_fragment_tests) in;
#endif
layout(r32i, binding = SB_IMG_OSL_MARKS) writeonly uniform iimage2D u_marks;
uniform int u_frame_index;
#endif

uniform sampler2D u_atlas;
uniform vec2 u_atlas_size;

#if defined(SCENE_TEXTURED)
// The mask's cut-out at the pixel, as every other technique draws it.
#include "surface.glsl"
#endif

void main()
{
#if defined(SCENE_TEXTURED)
    surface_alpha_clip();
#endif
    // Clamp to the centres of the first and last texels inside the chart:
    // the bilinear footprint then never leaves the chart, which is the gutter.
    float size = float(v_tile.z);
    vec2 lo = (ceil(v_chart.xy * size - 0.5) + 0.5) / size;
    vec2 hi = (floor(v_chart.zw * size - 0.5) + 0.5) / size;
    vec2 uv = clamp(v_uv, lo, hi);
    vec2 atlas_uv = (vec2(v_tile.xy) + uv * size) / u_atlas_size;
#ifdef OSL_SEEN
    // The texels bilinear filtering reads with a weight above zero (at a
    // texel centre, only that texel: the clamp above puts the chart's last
    // centres there), and their blocks.
    vec2 at = vec2(v_tile.xy) + uv * size - 0.5;
    ivec2 t0 = ivec2(floor(at));
    ivec2 b0 = t0 >> 3, b1 = (t0 + ivec2(greaterThan(fract(at), vec2(0.0)))) >> 3;
    for (int y = b0.y; y <= b1.y; y++)
        for (int x = b0.x; x <= b1.x; x++)
            imageStore(u_marks, ivec2(x, y), ivec4(u_frame_index));
#endif
    out_color = vec4(texture(u_atlas, atlas_uv).rgb, 1.0);
}
