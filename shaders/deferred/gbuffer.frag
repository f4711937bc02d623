// The g-buffer pass: each visible surface's normal and albedo in the layouts
// gbuffer.glsl's defines choose, and its material; depth goes to the
// output's depth texture.
#include "gbuffer.glsl"
#include "scene_data.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 g_albedo;
layout(location = 1) out vec4 g_normal;
layout(location = 2) out vec4 g_material;

void main()
{
    Material m = instance_material(v_instance);
    g_albedo = gbuffer_encode_albedo(m.albedo);
    g_normal = gbuffer_encode_normal(normalize(v_normal));
    g_material = vec4(m.specular, m.shininess, 0.0, 0.0);
}
