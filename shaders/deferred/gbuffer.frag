// The g-buffer pass: each visible surface's normal and albedo in the layouts
// gbuffer.glsl's defines choose, and its material; depth goes to the
// output's depth texture.
#include "gbuffer.glsl"
#include "scene_data.glsl"
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 g_albedo;
layout(location = 1) out vec4 g_normal;
layout(location = 2) out vec4 g_material;
#if defined(SCENE_TEXTURED)
// Asset scenes: what the textures give beyond the material plane.
layout(location = 3) out vec4 g_surface; // emissive, occlusion
#endif

void main()
{
#if defined(SCENE_TEXTURED)
    // The sampled albedo, the normal-mapped normal, metallic and roughness
    // from their texture; the layouts' packing applies to them as to the
    // procedural scenes' constants.
    TexturedSurface t = surface_here(normalize(v_normal));
    g_albedo = gbuffer_encode_albedo(t.m.albedo);
    g_normal = gbuffer_encode_normal(t.N);
    g_material = vec4(t.m.specular, t.m.shininess, t.m.metallic, t.m.roughness);
    g_surface = vec4(t.emissive, t.occlusion);
#else
    Material m = instance_material(v_instance);
    g_albedo = gbuffer_encode_albedo(m.albedo);
    g_normal = gbuffer_encode_normal(normalize(v_normal));
    g_material = vec4(m.specular, m.shininess, m.metallic, m.roughness);
#endif
}
