// Forward shading over the light grid (Forward+, clustered forward): after
// the depth pre-pass, each visible fragment loops over its cell's lights.
#include "light_grid.glsl"
#include "heat.glsl"
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
// The heat map's image writes would otherwise make the driver run the
// shader before the depth test, shading every hidden fragment the pre-pass
// is there to skip.
layout(early_fragment_tests) in;
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 out_color;

void main()
{
    // gl_FragCoord.w is 1 / clip w, and clip w is the view depth.
    int cell = grid_cell(gl_FragCoord.xy, 1.0 / gl_FragCoord.w);
    uint evaluations;
#if defined(SCENE_TEXTURED)
    TexturedSurface t = surface_here(normalize(v_normal));
    vec3 color = shade_cell(cell, v_world, t.N, t.m, t.occlusion, evaluations) + t.emissive;
#else
    Material m = instance_material(v_instance);
    vec3 color = shade_cell(cell, v_world, normalize(v_normal), m, evaluations);
#endif
    heat_add(ivec2(gl_FragCoord.xy), evaluations);
    out_color = vec4(color, 1.0);
}
