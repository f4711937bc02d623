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
uniform vec2 u_atlas_size;   // the whole texture
#ifdef OSL_LEVELS
// Levels (resolution "auto"): each tile's coarser levels lie below level 0
// (u_atlas_size0), as osl_level_origin (osl_gl.h) places them; each
// fragment reads the finest level with u_density to twice that texels a
// pixel (along each axis, on average), no coarser than leaves its chart 4
// texels across, and marks that level's blocks: shading follows the
// pixels that cover each part of an object, not the object's size.
uniform ivec2 u_atlas_size0;
uniform float u_density;

ivec2 level_origin(int l)
{
    return l == 0 ? ivec2(0) : ivec2(u_atlas_size0.x - (u_atlas_size0.x >> (l - 1)), u_atlas_size0.y);
}
#endif


#if defined(SCENE_TEXTURED)
// The mask's cut-out at the pixel, as every other technique draws it.
#define SURFACE_VERTEX_COLOR 1 // osl_draw.vert passes COLOR_0
#include "surface.glsl"
#endif

// One bilinear sample of the atlas at uv (clamped to the centres of the
// first and last texels inside the chart: the bilinear footprint then never
// leaves the chart, which is the gutter), marking with osl.visibility
// "seen" the blocks it reads.
// tile_at, size: the tile's level this fragment samples, its origin in the
// atlas and its edge in texels.
#if defined(OSL_SPLIT)
// Asset scenes under Phong: the specular light beside the diffuse in u_atlas
// (osl_light.comp's shade_split).
uniform sampler2D u_atlas_specular;
in vec3 v_normal;
vec3 g_specular = vec3(0.0); // atlas_sample's second plane, summed
vec3 g_normal;               // the pixel's normal-mapped normal
#endif

vec3 atlas_sample(vec2 uv, vec2 tile_at, float size)
{
    vec2 lo = (ceil(v_chart.xy * size - 0.5) + 0.5) / size;
    vec2 hi = (floor(v_chart.zw * size - 0.5) + 0.5) / size;
    uv = clamp(uv, lo, hi);
    vec2 atlas_uv = (tile_at + uv * size) / u_atlas_size;
#ifdef OSL_SEEN
    // The texels bilinear filtering reads with a weight above zero (at a
    // texel centre, only that texel: the clamp above puts the chart's last
    // centres there), and their blocks.
    vec2 at = tile_at + uv * size - 0.5;
    ivec2 t0 = ivec2(floor(at));
    ivec2 b0 = t0 >> 3, b1 = (t0 + ivec2(greaterThan(fract(at), vec2(0.0)))) >> 3;
    for (int y = b0.y; y <= b1.y; y++)
        for (int x = b0.x; x <= b1.x; x++)
            imageStore(u_marks, ivec2(x, y), ivec4(u_frame_index));
#endif
#ifdef OSL_MARK_ONLY
    return vec3(0.0); // a moving camera's marking pass writes no colour
#else
#if defined(OSL_SPLIT)
    // The diffuse light at this pixel's normal from its direction and
    // colour shares (osl_light.comp's shade_split).
    vec4 spec = texture(u_atlas_specular, atlas_uv), dir = texture(u_atlas, atlas_uv);
    g_specular += spec.rgb;
    return 3.0 * vec3(dir.w, spec.a, 1.0 - dir.w - spec.a) * max(dot(g_normal, dir.xyz), 0.0);
#else
    return texture(u_atlas, atlas_uv).rgb;
#endif
#endif
}

void main()
{
    vec2 tile_at = vec2(v_tile.xy);
    float size = float(v_tile.z);
#ifdef OSL_LEVELS
    {
        float size0 = float(v_tile.z);
        // Level-0 texels per pixel by area (the footprint's Jacobian's
        // determinant): the finest level with at least u_density texels a
        // pixel along each axis on average, so that a level's texels per
        // covered pixel lie in [d^2, 4 d^2). Where the whole shading is per
        // texel (no OSL_SPLIT), along the footprint's shorter axis (the
        // Jacobian's smaller singular value) instead: a specular highlight
        // then never spans fewer texels than pixels in any direction.
        vec2 jx = dFdx(v_uv) * size0, jy = dFdy(v_uv) * size0;
        float det = abs(jx.x * jy.y - jx.y * jy.x);
#if defined(OSL_SPLIT)
        float rho = sqrt(det);
#else
        float s2 = dot(jx, jx) + dot(jy, jy);
        float rho = det / max(sqrt(0.5 * (s2 + sqrt(max(s2 * s2 - 4.0 * det * det, 0.0)))), 1e-12);
#endif
        int level = int(floor(log2(max(rho, 1e-6) / u_density)));
        ivec2 chart = ivec2((v_chart.zw - v_chart.xy) * size0);
        int cap = min(findMSB(v_tile.z) - 3, findMSB(max(min(chart.x, chart.y), 4)) - 2);
        level = clamp(level, 0, max(cap, 0));
        tile_at = vec2(level_origin(level) + (v_tile.xy >> level));
        size = float(v_tile.z >> level);
    }
#endif
#if defined(SCENE_TEXTURED)
    // Asset scenes: where a pixel covers several texels (far or small), one
    // bilinear sample aliases detail the other techniques' mipmapped
    // textures average away; up to 4 x 4 samples spread over the pixel's
    // footprint (a box filter) average it here too. Derivatives first, in
    // uniform control flow (the mask's discard follows).
    vec2 dx = dFdx(v_uv), dy = dFdy(v_uv);
    int nx = clamp(int(ceil(length(dx) * size)), 1, 4);
    int ny = clamp(int(ceil(length(dy) * size)), 1, 4);
#if defined(OSL_SPLIT) && !defined(OSL_MARK_ONLY)
    // The base colour, occlusion and emissive at the pixel, as forward's
    // material_surface samples them.
    // The normal too: the diffuse light is applied at the pixel's
    // normal-mapped normal (atlas_sample).
    TexturedSurface ts = material_surface_grad(u_material, v_tex, dFdx(v_tex), dFdy(v_tex),
                                               normalize(v_normal), v_tangent, gl_FrontFacing,
                                               SURFACE_COLOR);
    vec3 base = ts.m.albedo;
    float occlusion = ts.occlusion;
    vec3 emissive = ts.emissive;
    g_normal = ts.N;
#endif
    surface_alpha_clip();
    vec3 sum = vec3(0.0);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++)
            sum += atlas_sample(v_uv + ((float(i) + 0.5) / float(nx) - 0.5) * dx +
                                    ((float(j) + 0.5) / float(ny) - 0.5) * dy,
                                tile_at, size);
#if defined(OSL_SPLIT) && !defined(OSL_MARK_ONLY)
    float w = 1.0 / float(nx * ny);
    out_color = vec4(base * (sum * w) + occlusion * light_ambient(base) + g_specular * w + emissive,
                     1.0);
#else
    out_color = vec4(sum / float(nx * ny), 1.0);
#endif
#else
    out_color = vec4(atlas_sample(v_uv, tile_at, size), 1.0);
#endif
}
