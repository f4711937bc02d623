// A full-screen triangle at the window depth of one material key: the
// visibility buffer's material passes test it GL_EQUAL against the key
// each pixel's material wrote (vis_classify.frag), so that the depth test
// keeps each pass to its material's pixels before any shading runs.
layout(location = SB_LOC_VIS_KEY) uniform float u_key_depth;

void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, u_key_depth * 2.0 - 1.0, 1.0);
}
