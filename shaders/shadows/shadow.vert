// The shadow pass: one caster into one cube face of one light's map, depth
// only (daemon/harness/shadows.c draws each caster that reaches the face).
#include "scene_data.glsl"
layout(location = 0) in vec3 a_pos;
layout(location = SB_LOC_SHADOW_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = SB_LOC_SHADOW_INSTANCE) uniform int u_instance;

void main()
{
    Instance inst = instances[u_instance];
    gl_Position = u_view_proj * vec4(inst.pos_scale.xyz + inst.pos_scale.w * a_pos, 1.0);
}
