// Prefiltered specular map texel (Karis 2013): the source convolved with
// GGX at the level's roughness, with N = V = R, by importance sampling; each
// sample reads the source level whose texels span the sample's solid angle
// (filtered importance sampling), which keeps a bright sun from speckling.
#include "scene_data.glsl"
#include "pbr.glsl"
#include "ibl_filter.glsl"

void main()
{
    vec3 n = texel_direction();
    float roughness = u_params.x;
    if (roughness <= 0.0) {
        out_color = vec4(textureLod(u_source, n, 0.0).rgb, 1.0);
        return;
    }
    vec3 t, b;
    tangent_frame(n, t, b);
    float a = pbr_alpha(roughness);
    uint count = uint(u_params.z);
    float texel_solid = 4.0 * PBR_PI / (6.0 * u_params.w * u_params.w);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < count; i++) {
        vec2 xi = hammersley(i, count);
        float phi = 6.28318530718 * xi.x;
        float cos_t = sqrt((1.0 - xi.y) / (1.0 + (a * a - 1.0) * xi.y));
        float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
        vec3 h = t * (sin_t * cos(phi)) + b * (sin_t * sin(phi)) + n * cos_t;
        vec3 l = 2.0 * dot(n, h) * h - n;
        float nol = dot(n, l);
        if (nol <= 0.0)
            continue;
        float pdf = pbr_d_ggx(cos_t, a) * 0.25; // D (n.h) / (4 v.h) with v = n
        float sample_solid = 1.0 / (float(count) * pdf + 1e-6);
        float lod = max(0.5 * log2(sample_solid / texel_solid) + 1.0, 0.0);
        sum += textureLod(u_source, l, lod).rgb * nol;
        weight += nol;
    }
    out_color = vec4(sum / max(weight, 1e-6), 1.0);
}
