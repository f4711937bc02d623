in vec3 v_pos;
in vec3 v_normal;
layout(location = 0) out vec4 out_position; // w = 1 marks a covered texel
layout(location = 1) out vec4 out_normal;

void main()
{
    out_position = vec4(v_pos, 1.0);
    out_normal = vec4(v_normal, 0.0);
}
