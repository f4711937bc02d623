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
#if defined(SCENE_TEXTURED)
// Asset scenes: the material's uv sets, tangent frame and vertex colour
// (surface.glsl). Location 2 is object-space shading's uv1, which no
// material reads.
layout(location = 4) in vec4 a_tex; // TEXCOORD_0 (xy), TEXCOORD_1 (zw)
layout(location = 5) in vec4 a_tangent;
layout(location = 6) in vec4 a_color; // COLOR_0
out vec4 v_tex;
out vec4 v_tangent;
out vec4 v_color;
#endif

void main()
{
    int id = u_instance_base + gl_InstanceID;
    Instance inst = instances[id];
    vec3 world = inst.pos_scale.xyz + inst.pos_scale.w * a_pos;
    v_world = world;
    v_normal = a_normal; // uniform scale, no rotation: object normal is world normal
    v_instance = id;
#if defined(SCENE_TEXTURED)
    v_tex = a_tex;
    v_tangent = a_tangent; // uniform scale, no rotation, like the normal
    v_color = a_color - 1.0; // surface.glsl adds the 1 back
#endif
    gl_Position = u_frame.view_proj * vec4(world, 1.0);
}
