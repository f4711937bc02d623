// OSL rasterization pass: draw every object, shading comes from its atlas tile.
#include "frame.glsl"
#include "scene_data.glsl"
layout(location = 0) in vec3 a_pos;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in vec4 a_chart;
#if defined(SCENE_TEXTURED)
layout(location = 4) in vec4 a_tex; // the material's TEXCOORD_0 (xy) and _1 (zw)
layout(location = 5) in vec4 a_tangent;
layout(location = 6) in vec4 a_color; // COLOR_0
layout(location = 1) in vec3 a_normal;
out vec4 v_color;
out vec3 v_normal;  // the pixel's normal (normal-mapped in osl_draw.frag), as forward's
out vec4 v_tex;     // surface.glsl's inputs, for the alpha mask
out vec4 v_tangent;
#endif

layout(std430, binding = SB_SSBO_OSL_TILES) readonly buffer TileBuffer { ivec4 tiles[]; };

uniform int u_instance_base;

out vec2 v_uv;
flat out vec4 v_chart;
flat out ivec4 v_tile;

void main()
{
    int id = u_instance_base + gl_InstanceID;
    Instance inst = instances[id];
    v_uv = a_uv;
#if defined(SCENE_TEXTURED)
    v_tex = a_tex;
    v_color = a_color - 1.0; // surface.glsl adds the 1 back
    v_tangent = a_tangent;
    v_normal = a_normal; // uniform scale, no rotation: object normal is world normal
#endif
    v_chart = a_chart;
    v_tile = tiles[id];
    gl_Position = u_frame.view_proj * vec4(inst.pos_scale.xyz + inst.pos_scale.w * a_pos, 1.0);
}
