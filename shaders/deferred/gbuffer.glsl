// G-buffer layouts, chosen by #define (daemon/techniques/shared/gbuffer.c
// passes one of each pair):
//   GBUFFER_NORMAL_OCTAHEDRAL (rg: world normal, octahedral, in [-1, 1]),
//   GBUFFER_NORMAL_FLOAT3 (rgb: world normal),
//   GBUFFER_NORMAL_XY_RECONSTRUCT_Z (rg: view-space x and y; z rebuilt as
//     sqrt(1 - x² - y²), which loses its sign: seed 004's packing);
//   GBUFFER_ALBEDO_RGBA8 (rgb, 8 bits a channel),
//   GBUFFER_ALBEDO_PACK_SHIFT (r: seed 001's first packing of a colour into one
//     float, bytes shifted by powers of 255; a byte of 255 is kept to 254),
//   GBUFFER_ALBEDO_PACK_BASE10 (r: seed 001's second, decimal digits a
//     channel in one float: two, 100 levels, the most that fit a float).
// A third plane holds the material: specular weight and exponent (rg), and
// under LIGHTING_PBR metallic and roughness (ba), 32-bit floats: exact. Position is never stored: it is rebuilt from the
// depth texture with the frame block's inverse view-projection.
#include "frame.glsl"
#include "scene_data.glsl"

vec2 gbuffer_sign_not_zero(vec2 v)
{
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

vec4 gbuffer_encode_normal(vec3 n)
{
#if defined(GBUFFER_NORMAL_FLOAT3)
    return vec4(n, 0.0);
#elif defined(GBUFFER_NORMAL_XY_RECONSTRUCT_Z)
    return vec4((mat3(u_frame.view) * n).xy, 0.0, 0.0);
#else
    vec2 e = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0)
        e = (1.0 - abs(e.yx)) * gbuffer_sign_not_zero(e);
    return vec4(e, 0.0, 0.0);
#endif
}

vec3 gbuffer_decode_normal(vec4 g)
{
#if defined(GBUFFER_NORMAL_FLOAT3)
    return normalize(g.xyz);
#elif defined(GBUFFER_NORMAL_XY_RECONSTRUCT_Z)
    vec3 v = vec3(g.xy, sqrt(max(0.0, 1.0 - dot(g.xy, g.xy))));
    return normalize(mat3(u_frame.inv_view) * v);
#else
    vec3 n = vec3(g.xy, 1.0 - abs(g.x) - abs(g.y));
    float t = max(-n.z, 0.0);
    n.xy -= t * gbuffer_sign_not_zero(n.xy);
    return normalize(n);
#endif
}

vec4 gbuffer_encode_albedo(vec3 c)
{
#if defined(GBUFFER_ALBEDO_PACK_SHIFT)
    // Seed 001's first packing: the channels' bytes "shifted" into one float
    // by multiplication, r·255² + g·255 + b. As base-255 digits a byte can
    // be 254 at most (a channel of 1.0 carried into the next digit, which
    // the seed's fract() unpacking turned into 0: white came out black), and
    // the sum is an integer below 2²⁴, which a float holds exactly (the
    // seed's fractions of 1/255 powers, with alpha as a fourth byte, did
    // not).
    vec3 q = min(round(clamp(c, 0.0, 1.0) * 255.0), 254.0);
    return vec4(q.r * 65025.0 + q.g * 255.0 + q.b, 0.0, 0.0, 0.0);
#elif defined(GBUFFER_ALBEDO_PACK_BASE10)
    // Seed 001's second packing: decimal digits a channel in one float. The
    // seed's three digits a channel need 30 bits, so wherever red was large
    // the float's 24-bit mantissa dropped blue and carried into green (white
    // came out red); two digits a channel (100 levels) fit it exactly.
    vec3 d = round(clamp(c, 0.0, 1.0) * 99.0);
    return vec4(d.r * 10000.0 + d.g * 100.0 + d.b, 0.0, 0.0, 0.0);
#else
    return vec4(c, 1.0);
#endif
}

vec3 gbuffer_decode_albedo(vec4 g)
{
#if defined(GBUFFER_ALBEDO_PACK_SHIFT)
    uint n = uint(round(g.r));
    return vec3(float(n / 65025u), float((n / 255u) % 255u), float(n % 255u)) / 255.0;
#elif defined(GBUFFER_ALBEDO_PACK_BASE10)
    uint n = uint(round(g.r));
    return vec3(float(n / 10000u), float((n / 100u) % 100u), float(n % 100u)) / 99.0;
#else
    return g.rgb;
#endif
}

// World position of the pixel at window position frag (pixel centre) with
// depth-buffer value depth (0..1).
vec3 gbuffer_position(vec2 frag, float depth)
{
    vec4 ndc = vec4(frag * u_frame.viewport.zw * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec4 w = u_frame.inv_view_proj * ndc;
    return w.xyz / w.w;
}

// The surface a g-buffer pixel holds.
layout(binding = SB_TEX_DEPTH) uniform sampler2D u_gbuffer_depth;
layout(binding = SB_TEX_GBUFFER0) uniform sampler2D u_gbuffer_albedo;
layout(binding = SB_TEX_GBUFFER1) uniform sampler2D u_gbuffer_normal;
layout(binding = SB_TEX_GBUFFER2) uniform sampler2D u_gbuffer_material;

struct Surface {
    vec3 P, N, albedo;
    float specular, shininess, metallic, roughness;
};

// False for background pixels (nothing drawn: depth 1).
bool gbuffer_surface(ivec2 pixel, out Surface s)
{
    float depth = texelFetch(u_gbuffer_depth, pixel, 0).r;
    if (depth >= 1.0)
        return false;
    s.P = gbuffer_position(vec2(pixel) + 0.5, depth);
    s.N = gbuffer_decode_normal(texelFetch(u_gbuffer_normal, pixel, 0));
    s.albedo = gbuffer_decode_albedo(texelFetch(u_gbuffer_albedo, pixel, 0));
    vec4 m = texelFetch(u_gbuffer_material, pixel, 0);
    s.specular = m.r;
    s.shininess = m.g;
    s.metallic = m.b;
    s.roughness = m.a;
    return true;
}

// The surface's material, as the lighting library's Material forms take it
// (scene_data.glsl declares the struct).
Material surface_material(Surface s)
{
    return Material(s.albedo, s.specular, s.shininess, s.metallic, s.roughness);
}
