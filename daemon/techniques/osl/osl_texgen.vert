// OSL texture generation: rasterize a model in its own UV space so each
// texel receives the object-space position and normal it stands for (and,
// in asset scenes, the material's values there: osl_texgen.frag).
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
#if defined(SCENE_TEXTURED)
layout(location = 4) in vec4 a_tex; // the material's TEXCOORD_0 (xy) and _1 (zw)
layout(location = 5) in vec4 a_tangent;
layout(location = 6) in vec4 a_color; // COLOR_0
out vec4 v_color;
out vec4 v_tex;
out vec4 v_tangent;
#endif

out vec3 v_pos;
out vec3 v_normal;

void main()
{
    v_pos = a_pos;
    v_normal = a_normal;
#if defined(SCENE_TEXTURED)
    v_tex = a_tex;
    v_color = a_color - 1.0; // surface.glsl adds the 1 back
    v_tangent = a_tangent;
#endif
    gl_Position = vec4(a_uv * 2.0 - 1.0, 0.0, 1.0);
}
