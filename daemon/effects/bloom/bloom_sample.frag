// Bloom: the bright pass (BRIGHT: keeps the light above the threshold, by
// luminance, keeping its colour) and the mip chain's downsampling (HALVE:
// each pixel averages the 2x2 block of the level above it).
layout(binding = SB_TEX_POST_SRC) uniform sampler2D u_src;
layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params; // x: threshold
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
#ifdef HALVE
    ivec2 last = textureSize(u_src, 0) - 1, q = p * 2;
    vec3 c = 0.25 * (texelFetch(u_src, min(q, last), 0).rgb +
                     texelFetch(u_src, min(q + ivec2(1, 0), last), 0).rgb +
                     texelFetch(u_src, min(q + ivec2(0, 1), last), 0).rgb +
                     texelFetch(u_src, min(q + ivec2(1, 1), last), 0).rgb);
#else
    vec3 c = texelFetch(u_src, p, 0).rgb;
#endif
#ifdef BRIGHT
    float l = dot(c, vec3(0.2126, 0.7152, 0.0722));
    c *= max(l - u_params.x, 0.0) / max(l, 1e-4);
#endif
    out_color = vec4(c, 1.0);
}
