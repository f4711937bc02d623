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

// One bilinear sample of the atlas at uv (clamped to the centres of the
// first and last texels inside the chart: the bilinear footprint then never
// leaves the chart, which is the gutter), marking with osl.visibility
// "seen" the blocks it reads.
vec3 atlas_sample(vec2 uv)
{
    float size = float(v_tile.z);
    vec2 lo = (ceil(v_chart.xy * size - 0.5) + 0.5) / size;
    vec2 hi = (floor(v_chart.zw * size - 0.5) + 0.5) / size;
    uv = clamp(uv, lo, hi);
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
    return texture(u_atlas, atlas_uv).rgb;
}

void main()
{
#if defined(SCENE_TEXTURED)
    // Asset scenes: where a pixel covers several texels (far or small), one
    // bilinear sample aliases detail the other techniques' mipmapped
    // textures average away; up to 4 x 4 samples spread over the pixel's
    // footprint (a box filter) average it here too. Derivatives first, in
    // uniform control flow (the mask's discard follows).
    float size = float(v_tile.z);
    vec2 dx = dFdx(v_uv), dy = dFdy(v_uv);
    int nx = clamp(int(ceil(length(dx) * size)), 1, 4);
    int ny = clamp(int(ceil(length(dy) * size)), 1, 4);
    surface_alpha_clip();
    vec3 sum = vec3(0.0);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++)
            sum += atlas_sample(v_uv + ((float(i) + 0.5) / float(nx) - 0.5) * dx +
                                ((float(j) + 0.5) / float(ny) - 0.5) * dy);
    out_color = vec4(sum / float(nx * ny), 1.0);
#else
    out_color = vec4(atlas_sample(v_uv), 1.0);
#endif
}
