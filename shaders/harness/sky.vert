// One triangle over the viewport at the far plane (window depth 1), so that
// with GL_LEQUAL it covers exactly the pixels no geometry wrote.
void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 1.0, 1.0);
}
