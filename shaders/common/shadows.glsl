// Omni shadow maps for the lighting library (LOOK_SHADOWS): how much of
// light i reaches P, from the maps the harness's shadow pass rendered this
// frame (daemon/harness/shadows.c). Each light's six faces lie in one depth
// atlas (or, with SHADOW_CUBES, in a layer of a cube map array); a light
// without a map this frame (culled, nothing to cast, or dropped when the
// atlas was full) is unshadowed. A directional light has an orthographic
// map of its own instead (shadow_sun_visibility). Percentage-closer filtering over
// (2 SHADOW_PCF + 1)^2 bilinear comparisons; the receiver is moved
// SHADOW_NORMAL_OFFSET shadow-map texels along its normal and compared
// SHADOW_BIAS world units nearer the light.
#include "cube_faces.glsl"

// daemon/harness/shadows.c, struct shadow_light_gpu (std430, 80 bytes).
struct ShadowLight {
    vec4 pos_far;  // where the map was rendered from, and its far plane (the light's radius)
    vec4 params;   // face size in texels (0: no map), widening, near plane, cube layer
    ivec4 faces01; // atlas corners of faces 0 and 1
    ivec4 faces23;
    ivec4 faces45;
};
layout(std430, binding = SB_SSBO_SHADOW_LIGHTS) readonly buffer ShadowBuffer {
    ShadowLight shadow_lights[];
};

// daemon/look/shadows.c, struct sun_shadow_gpu (std430, 80 bytes): a
// directional light's orthographic projection fitted to the scene's bounds.
struct SunShadow {
    mat4 view_proj;
    vec4 params; // size in texels, one texel in world units, depth range in world units, layer
};
layout(std430, binding = SB_SSBO_SHADOW_SUNS) readonly buffer SunShadowBuffer {
    SunShadow sun_shadows[];
};
layout(binding = SB_TEX_SHADOW_SUNS) uniform sampler2DArrayShadow u_shadow_suns;

#if defined(SHADOW_CUBES)
layout(binding = SB_TEX_SHADOW_CUBES) uniform samplerCubeArrayShadow u_shadow_cubes;
#else
layout(binding = SB_TEX_SHADOW_ATLAS) uniform sampler2DShadow u_shadow_atlas;
#endif

float shadow_visibility(int i, vec3 P, vec3 N, float nl)
{
    ShadowLight s = shadow_lights[i];
    float size = s.params.x;
    if (size <= 0.0)
        return 1.0;
    vec3 d = P - s.pos_far.xyz;
    // One texel of the face at this distance, in world units.
    float texel = 2.0 * s.params.y * length(d) / size;
    d += N * (SHADOW_NORMAL_OFFSET * texel);
    int f = cube_face_of(d);
    vec3 fw, sa, ta;
    cube_face_axes(f, fw, sa, ta);
    float major = dot(d, fw);
    float ref = cube_face_depth(max(major - SHADOW_BIAS, s.params.z), s.params.z, s.pos_far.w);
    float sum = 0.0;
#if defined(SHADOW_CUBES)
    // Taps stepped a texel apart on the face's plane.
    float step = 2.0 * major / size;
    for (int y = -SHADOW_PCF; y <= SHADOW_PCF; y++)
        for (int x = -SHADOW_PCF; x <= SHADOW_PCF; x++)
            sum += texture(u_shadow_cubes, vec4(d + (float(x) * sa + float(y) * ta) * step,
                                                s.params.w), ref);
#else
    ivec2 corner = f == 0 ? s.faces01.xy : f == 1 ? s.faces01.zw : f == 2 ? s.faces23.xy
                 : f == 3 ? s.faces23.zw : f == 4 ? s.faces45.xy : s.faces45.zw;
    // Texel coordinates in the tile; the border keeps every tap inside it.
    vec2 st = vec2(dot(d, sa), dot(d, ta)) / (major * s.params.y);
    vec2 at = (st * 0.5 + 0.5) * size;
    for (int y = -SHADOW_PCF; y <= SHADOW_PCF; y++)
        for (int x = -SHADOW_PCF; x <= SHADOW_PCF; x++) {
            vec2 tc = clamp(at + vec2(x, y), vec2(0.5), vec2(size - 0.5)) + vec2(corner);
            sum += texture(u_shadow_atlas, vec3(tc * (1.0 / SHADOW_ATLAS_SIZE), ref));
        }
#endif
    return sum / float((2 * SHADOW_PCF + 1) * (2 * SHADOW_PCF + 1));
}

// Directional light i: its map (shadow_lights[i].params: size, 0 when it has
// none, and the map's index in w), the same filter, normal offset and bias
// as the omni maps. Outside the fitted bounds: lit.
float shadow_sun_visibility(int i, vec3 P, vec3 N)
{
    vec4 p = shadow_lights[i].params;
    if (p.x <= 0.0)
        return 1.0;
    SunShadow s = sun_shadows[int(p.w)];
    vec3 q = P + N * (SHADOW_NORMAL_OFFSET * s.params.y);
    vec3 c = (s.view_proj * vec4(q, 1.0)).xyz * 0.5 + 0.5;
    if (any(lessThan(c, vec3(0.0))) || any(greaterThan(c, vec3(1.0))))
        return 1.0;
    float ref = c.z - SHADOW_BIAS / s.params.z;
    float texel = 1.0 / s.params.x, sum = 0.0;
    for (int y = -SHADOW_PCF; y <= SHADOW_PCF; y++)
        for (int x = -SHADOW_PCF; x <= SHADOW_PCF; x++)
            sum += texture(u_shadow_suns, vec4(c.xy + vec2(x, y) * texel, s.params.w, ref));
    return sum / float((2 * SHADOW_PCF + 1) * (2 * SHADOW_PCF + 1));
}
