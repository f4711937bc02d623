// The shadow pass: one caster into one cube face of one light's map, depth
// only (daemon/harness/shadows.c draws each caster that reaches the face).
#include "scene_data.glsl"
layout(location = 0) in vec3 a_pos;
layout(location = SB_LOC_SHADOW_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = SB_LOC_SHADOW_INSTANCE) uniform int u_instance;
#if defined(SCENE_TEXTURED)
layout(location = 4) in vec4 a_tex; // TEXCOORD_0, TEXCOORD_1
layout(location = 6) in vec4 a_color;
out vec4 v_tex;
out vec4 v_tangent;
out vec4 v_color;
#endif

void main()
{
    Instance inst = instances[u_instance];
#if defined(SCENE_TEXTURED)
    v_tex = a_tex;
    v_tangent = vec4(0.0);
    v_color = a_color - 1.0; // surface.glsl adds the 1 back
#endif
    gl_Position = u_view_proj * vec4(inst.pos_scale.xyz + inst.pos_scale.w * a_pos, 1.0);
}
