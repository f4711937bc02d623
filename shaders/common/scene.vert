// Instanced scene geometry in world space, for every program that draws the
// objects.
#include "frame.glsl"
#include "scene_data.glsl"
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;

uniform int u_instance_base;

out vec3 v_world;
out vec3 v_normal;
flat out int v_instance;

void main()
{
    int id = u_instance_base + gl_InstanceID;
    Instance inst = instances[id];
    vec3 world = inst.pos_scale.xyz + inst.pos_scale.w * a_pos;
    v_world = world;
    v_normal = a_normal; // uniform scale, no rotation: object normal is world normal
    v_instance = id;
    gl_Position = u_frame.view_proj * vec4(world, 1.0);
}
