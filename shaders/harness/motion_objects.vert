// The harness's motion vectors, moving instances (daemon/harness/motion.h):
// where scene.vert puts the instance this frame, with where its vertex was
// the frame before (the previous instance rows, gpu_scene_set_frame).
#include "frame.glsl"
#include "scene_data.glsl"
layout(location = 0) in vec3 a_pos;
layout(std430, binding = SB_SSBO_PREV_INSTANCES) readonly buffer PrevInstanceBuffer { vec4 prev_pos_scale[]; };
uniform int u_instance_base;
out vec4 v_now;
out vec4 v_before;

void main()
{
    int id = u_instance_base + gl_InstanceID;
    vec4 ps = instances[id].pos_scale;
    vec3 world = ps.xyz + ps.w * a_pos;
    vec4 pp = prev_pos_scale[id];
    v_now = u_frame.unjittered_view_proj * vec4(world, 1.0);
    v_before = u_frame.prev_view_proj * vec4(pp.xyz + pp.w * a_pos, 1.0);
    gl_Position = u_frame.view_proj * vec4(world, 1.0);
}
