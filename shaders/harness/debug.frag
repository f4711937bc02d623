// look.debug's pass (daemon/look/debug.c): every opaque and alpha-masked
// surface's channel in place of the lit image, the harness's pass for every
// technique; the transparent pass draws the blended ones the same way. An
// asset scene's channels come from the shared surface code
// (surface_debug_here, which says how each is encoded); a procedural
// scene's from its instances' constant materials, with the viewer's grey
// checks where it has nothing to show (no maps, no uv sets).
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 out_color;

#if !defined(SCENE_TEXTURED)
vec3 debug_checks()
{
    vec2 f = fract(0.02 * gl_FragCoord.xy);
    vec2 a = step(0.5, f), b = step(0.5, vec2(1.0) - f);
    return vec3(0.9 + a.x * a.y + b.x * b.y);
}

vec3 procedural_debug(vec3 n, Material m)
{
#if defined(LOOK_DEBUG_SHADING_NORMAL) || defined(LOOK_DEBUG_GEOMETRIC_NORMAL)
    return n * 0.5 + 0.5;
#elif defined(LOOK_DEBUG_BASE_COLOR)
    return pow(max(m.albedo, vec3(0.0)), vec3(1.0 / 2.2));
#elif defined(LOOK_DEBUG_METALLIC)
    return vec3(clamp(m.metallic, 0.0, 1.0));
#elif defined(LOOK_DEBUG_ROUGHNESS)
    return vec3(clamp(m.roughness, 0.0, 1.0));
#elif defined(LOOK_DEBUG_EMISSIVE)
    return vec3(0.0);
#elif defined(LOOK_DEBUG_ALPHA)
    return vec3(1.0);
#else
    return debug_checks();
#endif
}
#endif

void main()
{
#if defined(SCENE_TEXTURED)
    out_color = vec4(surface_debug_here(normalize(v_normal)), 1.0);
#else
    vec3 n = normalize(v_normal);
    out_color = vec4(procedural_debug(gl_FrontFacing ? n : -n, instance_material(v_instance)), 1.0);
#endif
}
