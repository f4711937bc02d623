// Thesis ForwardProg: every light evaluated for every fragment.
#include "lighting.glsl"
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 out_color;

void main()
{
#if defined(SCENE_TEXTURED)
    out_color = vec4(surface_shade_all_lights(v_world, surface_here(normalize(v_normal))), 1.0);
#else
    out_color = vec4(shade_all_lights(v_world, normalize(v_normal), instance_material(v_instance), 0),
                     1.0);
#endif
}
