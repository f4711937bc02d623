// Image-based lighting for the lighting library (LOOK_IBL, under
// LIGHTING_PBR): the split sum (Karis 2013) over the harness's environment
// and light probes (daemon/harness/ibl.c). Layer 0 of the cube map arrays is
// the environment alone; the probes chosen for this frame (the block below,
// seed 002's most important `blend`) are weighted by their falloff at the
// shaded point, and the environment takes what they leave.
#include "pbr.glsl"

layout(binding = SB_TEX_IBL_IRRADIANCE) uniform samplerCubeArray u_ibl_irradiance;
layout(binding = SB_TEX_IBL_PREFILTERED) uniform samplerCubeArray u_ibl_prefiltered;
layout(binding = SB_TEX_IBL_BRDF) uniform sampler2D u_ibl_brdf;

// daemon/harness/ibl.c, struct ibl_block (std140).
layout(std140, binding = SB_UBO_IBL) uniform IblBlock {
    ivec4 count;                // x: probes this frame, y: prefiltered levels - 1
    vec4 probe[IBL_MAX_BLEND];  // centre, radius
    ivec4 layer[IBL_MAX_BLEND]; // x: the probe's layer
} u_ibl;

vec3 ibl_ambient(Material m, vec3 P, vec3 N, vec3 V)
{
    float nov = pbr_nov(N, V);
    float rough = clamp(m.roughness, PBR_MIN_ROUGHNESS, 1.0);
    float lod = rough * float(u_ibl.count.y);
    vec3 R = reflect(-V, N);
    vec3 irr = vec3(0.0), pre = vec3(0.0);
    float total = 0.0;
    for (int i = 0; i < u_ibl.count.x; i++) {
        float w = clamp(1.0 - length(P - u_ibl.probe[i].xyz) / u_ibl.probe[i].w, 0.0, 1.0);
        w = w * w * (3.0 - 2.0 * w);
        if (w <= 0.0)
            continue;
        float layer = float(u_ibl.layer[i].x);
        irr += w * textureLod(u_ibl_irradiance, vec4(N, layer), 0.0).rgb;
        pre += w * textureLod(u_ibl_prefiltered, vec4(R, layer), lod).rgb;
        total += w;
    }
    if (total > 1.0) {
        irr /= total;
        pre /= total;
        total = 1.0;
    }
    float env = 1.0 - total;
    irr += env * textureLod(u_ibl_irradiance, vec4(N, 0.0), 0.0).rgb;
    pre += env * textureLod(u_ibl_prefiltered, vec4(R, 0.0), lod).rgb;
    vec2 ab = textureLod(u_ibl_brdf, vec2(nov, rough), 0.0).rg;
    return pbr_ambient_mix(m, ab, irr, pre);
}
