// Bloom: a smaller blurred level, read bilinearly, added (blending on) into
// the level above it; and, with COMPOSITE, the bloom added to the colour.
layout(binding = SB_TEX_POST_AUX) uniform sampler2D u_bloom;
#ifdef COMPOSITE
layout(binding = SB_TEX_POST_SRC) uniform sampler2D u_src;
layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params; // x: intensity
#endif
in vec2 v_uv;
layout(location = 0) out vec4 out_color;

void main()
{
    vec3 b = texture(u_bloom, v_uv).rgb;
#ifdef COMPOSITE
    vec3 c = texelFetch(u_src, ivec2(gl_FragCoord.xy), 0).rgb;
    out_color = vec4(c + u_params.x * b, 1.0);
#else
    out_color = vec4(b, 1.0);
#endif
}
