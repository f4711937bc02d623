// The harness's resolve: the technique's HDR output to the 8-bit image that
// is read back and scored. Tone mapping "none": a clamp, as an 8-bit
// framebuffer would have done.
layout(binding = SB_TEX_HDR) uniform sampler2D u_hdr;
layout(location = 0) out vec4 out_color;

void main()
{
    vec3 c = texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb;
    out_color = vec4(clamp(c, 0.0, 1.0), 1.0);
}
