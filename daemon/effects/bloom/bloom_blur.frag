// Bloom: Gaussian blur of RADIUS taps each side. BLUR_2D reads the full
// (2r+1)^2 square in one pass (seed 001's slow version); otherwise one row
// (DIR_X) or one column per pass, 2r+1 taps. Every tap is its own texel
// fetch (no bilinear pairing), so the two kernels' costs compare as their
// tap counts: (2r+1)^2 against 2(2r+1).
layout(binding = SB_TEX_POST_AUX) uniform sampler2D u_in;
layout(location = SB_LOC_POST_WEIGHTS) uniform float u_weights[33];
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy), last = textureSize(u_in, 0) - 1;
    vec3 sum = vec3(0.0);
#ifdef BLUR_2D
    for (int j = -RADIUS; j <= RADIUS; j++) {
        float wj = u_weights[abs(j)];
        for (int i = -RADIUS; i <= RADIUS; i++)
            sum += (wj * u_weights[abs(i)]) *
                   texelFetch(u_in, clamp(p + ivec2(i, j), ivec2(0), last), 0).rgb;
    }
#else
#ifdef DIR_X
    const ivec2 dir = ivec2(1, 0);
#else
    const ivec2 dir = ivec2(0, 1);
#endif
    for (int i = -RADIUS; i <= RADIUS; i++)
        sum += u_weights[abs(i)] * texelFetch(u_in, clamp(p + dir * i, ivec2(0), last), 0).rgb;
#endif
    out_color = vec4(sum, 1.0);
}
