// G-buffer layouts, chosen by #define (daemon/techniques/shared/gbuffer.c
// passes one of each pair):
//   GBUFFER_NORMAL_OCTAHEDRAL (rg: world normal, octahedral, in [-1, 1]),
//   GBUFFER_NORMAL_FLOAT3 (rgb: world normal),
//   GBUFFER_NORMAL_XY_RECONSTRUCT_Z (rg: view-space x and y; z rebuilt as
//     sqrt(1 - x² - y²), which loses its sign: seed 004's packing);
//   GBUFFER_ALBEDO_RGBA8 (rgb, 8 bits a channel),
//   GBUFFER_ALBEDO_PACK_SHIFT (r: seed 001's first packing of a colour into one
//     float, channels scaled by powers of 1/255 and unpacked with fract),
//   GBUFFER_ALBEDO_PACK_BASE10 (r: seed 001's second, three decimal digits a
//     channel in one float).
// A third plane holds the material's specular weight and exponent (rg,
// 32-bit floats: exact). Position is never stored: it is rebuilt from the
// depth texture with the frame block's inverse view-projection.
#include "frame.glsl"

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
    // The seed's colours came from 8-bit textures: quantise as they were.
    vec4 q = vec4(round(clamp(c, 0.0, 1.0) * 255.0) / 255.0, 1.0);
    return vec4(dot(q, vec4(1.0, 1.0 / 255.0, 1.0 / 65025.0, 1.0 / 16581375.0)), 0.0, 0.0, 0.0);
#elif defined(GBUFFER_ALBEDO_PACK_BASE10)
    vec3 d = round(clamp(c, 0.0, 1.0) * 999.0);
    return vec4(d.r * 1000000.0 + d.g * 1000.0 + d.b, 0.0, 0.0, 0.0);
#else
    return vec4(c, 1.0);
#endif
}

vec3 gbuffer_decode_albedo(vec4 g)
{
#if defined(GBUFFER_ALBEDO_PACK_SHIFT)
    vec4 e = fract(vec4(1.0, 255.0, 65025.0, 16581375.0) * g.r);
    e -= e.yzww * vec4(1.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0, 0.0);
    return e.rgb;
#elif defined(GBUFFER_ALBEDO_PACK_BASE10)
    float v = g.r;
    float r = floor(v / 1000000.0);
    float gg = floor((v - r * 1000000.0) / 1000.0);
    float b = v - r * 1000000.0 - gg * 1000.0;
    return clamp(vec3(r, gg, b) / 999.0, 0.0, 1.0);
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
    float specular, shininess;
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
    vec2 m = texelFetch(u_gbuffer_material, pixel, 0).rg;
    s.specular = m.r;
    s.shininess = m.g;
    return true;
}
