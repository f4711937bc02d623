in vec3 v_pos;
in vec3 v_normal;
layout(location = 0) out vec4 out_position; // w = 1 marks a covered texel
layout(location = 1) out vec4 out_normal;

#if defined(SCENE_TEXTURED)
// Asset scenes: the material baked with the geometry, once, at the texel's
// own footprint (the derivatives of uv0 across a texel of the UV-space
// raster choose the mip level): the shading normal (normal-mapped) and
// metallic, albedo and roughness, emissive and occlusion. The lighting
// pass then shades many objects in one dispatch without their textures.
#define SURFACE_VERTEX_COLOR 1 // osl_texgen.vert passes COLOR_0
#include "surface.glsl"
layout(location = 2) out vec4 out_albedo;  // linear base colour, roughness (+ 2 double-sided)
layout(location = 3) out vec4 out_surface; // emissive, occlusion
#endif

void main()
{
    out_position = vec4(v_pos, 1.0);
#if defined(SCENE_TEXTURED)
    // Front faces: object space has no viewer; a double-sided material's
    // back is shaded as its front.
    TexturedSurface s = material_surface(u_material, v_tex, normalize(v_normal), v_tangent, true,
                                          SURFACE_COLOR);
    out_normal = vec4(s.N, s.m.metallic);
    // A double-sided material is shaded on the side the viewer sees, which
    // object space cannot know: the lighting pass flips the normal then.
    bool two_sided = materials[u_material].slots.w != 0;
    out_albedo = vec4(s.m.albedo, s.m.roughness + (two_sided ? 2.0 : 0.0));
    out_surface = vec4(s.emissive, s.occlusion);
#else
    out_normal = vec4(v_normal, 0.0);
#endif
}
