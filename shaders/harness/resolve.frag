// The harness's resolve: the HDR colour (the technique's output, or the post
// chain's) to the 8-bit image that is read back and scored, scaled by the
// look's exposure. TONEMAP_NONE: a clamp, as an 8-bit framebuffer would
// have done, no encoding (today's image, byte for byte at exposure 1).
// TONEMAP_SRGB: a clamp, then the sRGB transfer function (display-referred
// with no curve). TONEMAP_REINHARD, TONEMAP_ACES and TONEMAP_PBR_NEUTRAL
// (Khronos PBR Neutral): the curve, then the sRGB transfer function, since
// a tone-mapped image is display-referred.
// The encoding is look.transfer's: the sRGB curve, or a plain gamma (the
// glTF Sample Viewer's 2.2). daemon/lighting/tone_curves.c has the same
// curves in C, unit-tested.
layout(binding = SB_TEX_HDR) uniform sampler2D u_hdr;
layout(location = SB_LOC_EXPOSURE) uniform float u_exposure;
// look.transfer: 0 for the sRGB curve, 2.2 for the glTF Sample Viewer's gamma.
layout(location = SB_LOC_GAMMA) uniform float u_gamma;
layout(location = 0) out vec4 out_color;

vec3 srgb_encode(vec3 c)
{
    c = clamp(c, 0.0, 1.0);
    if (u_gamma > 0.0)
        return pow(c, vec3(1.0 / u_gamma));
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main()
{
    vec3 c = texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb * u_exposure;
#if defined(TONEMAP_REINHARD)
    c = max(c, 0.0);
    c = srgb_encode(c / (1.0 + c));
#elif defined(TONEMAP_ACES)
    // Narkowicz 2015, with the 0.6 exposure his fit assumes.
    c = max(c, 0.0) * 0.6;
    c = srgb_encode((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14));
#elif defined(TONEMAP_PBR_NEUTRAL)
    // Khronos PBR Neutral: shadows lose F90 = 0.04, highlights from 0.76
    // compress towards 1 and desaturate towards white.
    c = max(c, 0.0);
    const float start = 0.8 - 0.04, desaturation = 0.15;
    float x = min(c.r, min(c.g, c.b));
    c -= x < 0.08 ? x - 6.25 * x * x : 0.04;
    float peak = max(c.r, max(c.g, c.b));
    if (peak >= start) {
        const float d = 1.0 - start;
        float new_peak = 1.0 - d * d / (peak + d - start);
        c *= new_peak / peak;
        float g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
        c = mix(c, vec3(new_peak), g);
    }
    c = srgb_encode(c);
#elif defined(TONEMAP_SRGB)
    c = srgb_encode(c);
#else
    c = clamp(c, 0.0, 1.0);
#endif
    out_color = vec4(c, 1.0);
}
