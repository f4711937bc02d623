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

// The surface a g-buffer pixel holds. With MSAA (SB_MSAA_SAMPLES) the
// planes and the depth are multisampled: a program built with
// GBUFFER_PER_SAMPLE runs once a sample (gl_SampleID) and reads its own;
// one built without runs once a pixel, for pixels the edge pass left
// unmarked (all samples of one surface), and reads sample 0's planes with
// the depth at the centre of the sample pattern (the mean of the samples'
// depths: on a plane depth is linear in window position), so that it
// shades the point forward shades.
#include "msaa.glsl"
layout(binding = SB_TEX_DEPTH) uniform msaa_sampler2D u_gbuffer_depth;
layout(binding = SB_TEX_GBUFFER0) uniform msaa_sampler2D u_gbuffer_albedo;
layout(binding = SB_TEX_GBUFFER1) uniform msaa_sampler2D u_gbuffer_normal;
layout(binding = SB_TEX_GBUFFER2) uniform msaa_sampler2D u_gbuffer_material;
#if defined(SCENE_TEXTURED)
// Asset scenes' fourth plane: emissive (rgb), occlusion (a), rgba16f.
layout(binding = SB_TEX_GBUFFER3) uniform msaa_sampler2D u_gbuffer_surface;
#endif
#ifdef SB_MSAA_SAMPLES
// Each sample's position within its pixel (glGetMultisamplefv), and their
// mean, set at create (gbuffer.c).
uniform vec2 u_sample_pos[SB_MSAA_SAMPLES];
uniform vec2 u_sample_centre;
#endif

struct Surface {
    vec3 P, N, albedo;
    float specular, shininess, metallic, roughness;
#if defined(SCENE_TEXTURED)
    vec3 emissive;   // added once, with the ambient term
    float occlusion; // scales the ambient term only
#endif
};

void gbuffer_planes(ivec2 pixel, int i, inout Surface s)
{
    s.N = gbuffer_decode_normal(msaa_fetch(u_gbuffer_normal, pixel, i));
    s.albedo = gbuffer_decode_albedo(msaa_fetch(u_gbuffer_albedo, pixel, i));
    vec4 m = msaa_fetch(u_gbuffer_material, pixel, i);
    s.specular = m.r;
    s.shininess = m.g;
    s.metallic = m.b;
    s.roughness = m.a;
#if defined(SCENE_TEXTURED)
    vec4 e = msaa_fetch(u_gbuffer_surface, pixel, i);
    s.emissive = e.rgb;
    s.occlusion = e.a;
#endif
}

#ifdef SB_MSAA_SAMPLES
// Forward at MSAA shades each surface in a pixel once, at the pixel's
// centre (its attributes extrapolated there), and so does lighting here: P,
// a point of the surface within the pixel, moves along the surface's plane
// (normal N) to where the ray through the centre meets it. Seen edge-on the
// plane gives no such point, and P stays.
vec3 gbuffer_at_centre(ivec2 pixel, vec3 P, vec3 N)
{
    vec3 eye = u_frame.eye.xyz;
    vec3 dir = normalize(gbuffer_position(vec2(pixel) + 0.5, 1.0) - eye);
    float facing = dot(dir, N);
    if (abs(facing) < 0.05)
        return P;
    vec3 C = eye + dir * (dot(P - eye, N) / facing);
    // A curved surface's shading normal is not its triangle's plane: near a
    // silhouette the move would leave the pixel; then P stays.
    float footprint = distance(P, eye) * 2.0 * u_frame.viewport.w / u_frame.proj[1][1];
    return distance(C, P) < footprint ? C : P;
}
#endif

// False for background pixels (nothing drawn: depth 1).
bool gbuffer_surface(ivec2 pixel, out Surface s)
{
#if !defined(SB_MSAA_SAMPLES)
    float depth = texelFetch(u_gbuffer_depth, pixel, 0).r;
    if (depth >= 1.0)
        return false;
    s.P = gbuffer_position(vec2(pixel) + 0.5, depth);
    gbuffer_planes(pixel, 0, s);
#elif defined(GBUFFER_PER_SAMPLE)
    int i = gl_SampleID;
    float depth = texelFetch(u_gbuffer_depth, pixel, i).r;
    if (depth >= 1.0)
        return false;
    gbuffer_planes(pixel, i, s);
    s.P = gbuffer_at_centre(pixel, gbuffer_position(vec2(pixel) + u_sample_pos[i], depth), s.N);
#else
    float depth = 0.0;
    for (int i = 0; i < SB_MSAA_SAMPLES; i++)
        depth += texelFetch(u_gbuffer_depth, pixel, i).r;
    depth /= float(SB_MSAA_SAMPLES);
    if (texelFetch(u_gbuffer_depth, pixel, 0).r >= 1.0)
        return false;
    gbuffer_planes(pixel, 0, s);
    s.P = gbuffer_at_centre(pixel, gbuffer_position(vec2(pixel) + u_sample_centre, depth), s.N);
#endif
    return true;
}

#ifdef SB_MSAA_SAMPLES
// True when the samples of pixel hold more than one surface: one is
// background and another not, or their normals, albedo or material differ,
// or a sample lies off the plane through sample 0 (a surface behind another
// of the same orientation and colour). Coplanar samples of one object (the
// two triangles of a quad) are one surface: shading them once is exact.
bool gbuffer_edge(ivec2 pixel)
{
    float d0 = texelFetch(u_gbuffer_depth, pixel, 0).r;
    vec4 n0 = texelFetch(u_gbuffer_normal, pixel, 0);
    vec4 a0 = texelFetch(u_gbuffer_albedo, pixel, 0);
    vec4 m0 = texelFetch(u_gbuffer_material, pixel, 0);
#if defined(SCENE_TEXTURED)
    vec4 e0 = texelFetch(u_gbuffer_surface, pixel, 0);
#endif
    vec3 P0 = gbuffer_position(vec2(pixel) + u_sample_pos[0], d0);
    vec3 N0 = gbuffer_decode_normal(n0);
    // 24-bit depth is good to about 1e-4 of the distance at the scenes'
    // depths: ten times that is noise, a surface behind another is not.
    float tolerance = 1e-3 * max(distance(P0, u_frame.eye.xyz), 1.0);
    for (int i = 1; i < SB_MSAA_SAMPLES; i++) {
        float d = texelFetch(u_gbuffer_depth, pixel, i).r;
        if ((d >= 1.0) != (d0 >= 1.0))
            return true;
        if (d0 >= 1.0)
            continue;
        if (texelFetch(u_gbuffer_normal, pixel, i) != n0 ||
            texelFetch(u_gbuffer_albedo, pixel, i) != a0 ||
            texelFetch(u_gbuffer_material, pixel, i) != m0)
            return true;
#if defined(SCENE_TEXTURED)
        if (texelFetch(u_gbuffer_surface, pixel, i) != e0)
            return true;
#endif
        vec3 P = gbuffer_position(vec2(pixel) + u_sample_pos[i], d);
        if (abs(dot(P - P0, N0)) > tolerance)
            return true;
    }
    return false;
}
#endif

// The surface's material, as the lighting library's Material forms take it
// (scene_data.glsl declares the struct).
Material surface_material(Surface s)
{
    return Material(s.albedo, s.specular, s.shininess, s.metallic, s.roughness);
}
