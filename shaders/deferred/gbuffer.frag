// The g-buffer pass: each visible surface's normal and albedo in the layouts
// gbuffer.glsl's defines choose; depth goes to the output's depth texture.
#include "gbuffer.glsl"
#include "scene_data.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 g_albedo;
layout(location = 1) out vec4 g_normal;

void main()
{
    g_albedo = gbuffer_encode_albedo(instances[v_instance].albedo_mesh.rgb);
    g_normal = gbuffer_encode_normal(normalize(v_normal));
}
