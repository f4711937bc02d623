// The cost floor: same geometry and passes, flat per-object colour, no lights.
#include "frame.glsl"
#include "scene_data.glsl"
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 out_color;

void main()
{
#if defined(SCENE_TEXTURED)
    // The base colour (texture times factor), alpha-masked like every pass.
    out_color = vec4(surface_here(normalize(v_normal)).m.albedo, 1.0);
#else
    out_color = vec4(instances[v_instance].albedo_mesh.rgb, 1.0);
#endif
}
