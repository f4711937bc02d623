// OSL texture generation: rasterize a model in its own UV space so each
// texel receives the object-space position and normal it stands for.
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;

out vec3 v_pos;
out vec3 v_normal;

void main()
{
    v_pos = a_pos;
    v_normal = a_normal;
    gl_Position = vec4(a_uv * 2.0 - 1.0, 0.0, 1.0);
}
