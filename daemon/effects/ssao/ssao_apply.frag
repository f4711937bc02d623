// SSAO: the occlusion (BLUR: averaged over the 4x4 noise tile, seed 002's
// "blurry SSAO", which cancels the rotation pattern) raised to the
// intensity and multiplied into the colour.
layout(binding = SB_TEX_POST_SRC) uniform sampler2D u_src;
layout(binding = SB_TEX_POST_AUX) uniform sampler2D u_ao;
layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params; // x: intensity
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
#ifdef BLUR
    ivec2 last = textureSize(u_ao, 0) - 1;
    float ao = 0.0;
    for (int j = -2; j < 2; j++)
        for (int i = -2; i < 2; i++)
            ao += texelFetch(u_ao, clamp(p + ivec2(i, j), ivec2(0), last), 0).r;
    ao *= 1.0 / 16.0;
#else
    float ao = texelFetch(u_ao, p, 0).r;
#endif
    vec3 c = texelFetch(u_src, p, 0).rgb;
    out_color = vec4(c * exp2(u_params.x * log2(max(ao, 1e-4))), 1.0);
}
