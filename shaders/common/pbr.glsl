// Physically based shading, seed 002's model: Cook-Torrance with the GGX
// distribution, the height-correlated Smith visibility term and Schlick's
// Fresnel, in the metallic-roughness parameterisation (Karis 2013, "Real
// Shading in Unreal Engine 4"; Heitz 2014 and Lagarde & de Rousiers 2014 for
// the correlated visibility). daemon/lighting/pbr_math.c computes the same
// terms in C for the unit tests and the split-sum lookup table.
//
// PBR_MIN_ROUGHNESS comes from the harness (pbr_math.h). Below it GGX's peak,
// 1 / (pi alpha^2), outgrows a half float under bright lights, and at
// roughness 0 the distribution is 0/0 where N = H: the clamp keeps every
// value finite. The harness reports how many materials it clamped.
#ifndef PBR_MIN_ROUGHNESS
#define PBR_MIN_ROUGHNESS 0.089
#endif

const float PBR_PI = 3.14159265358979;

float pbr_alpha(float roughness)
{
    float r = clamp(roughness, PBR_MIN_ROUGHNESS, 1.0);
    return r * r;
}

float pbr_d_ggx(float NoH, float a)
{
    float a2 = a * a;
    float f = (NoH * a2 - NoH) * NoH + 1.0;
    return a2 / (PBR_PI * f * f);
}

// G / (4 NoL NoV), height-correlated (Heitz 2014, eq. 99).
float pbr_v_smith(float NoV, float NoL, float a)
{
    float a2 = a * a;
    float gv = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    float gl = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

vec3 pbr_f_schlick(vec3 f0, float VoH)
{
    float x = 1.0 - VoH, x2 = x * x;
    return f0 + (1.0 - f0) * (x2 * x2 * x);
}

vec3 pbr_f0(Material m)
{
    return mix(vec3(0.04), m.albedo, m.metallic);
}

// Back-facing views (interpolated normals at silhouettes) would divide by 0.
float pbr_nov(vec3 N, vec3 V)
{
    return max(dot(N, V), 1e-4);
}

// pi times the BRDF for light from L (NoL > 0).
vec3 pbr_brdf(vec3 N, vec3 V, vec3 L, float NoL, Material m)
{
    vec3 h = L + V;
    vec3 H = h * inversesqrt(max(dot(h, h), 1e-12));
    float NoV = pbr_nov(N, V);
    float NoH = clamp(dot(N, H), 0.0, 1.0);
    float VoH = clamp(dot(V, H), 0.0, 1.0);
    float a = pbr_alpha(m.roughness);
    vec3 F = pbr_f_schlick(pbr_f0(m), VoH);
    vec3 spec = pbr_d_ggx(NoH, a) * pbr_v_smith(NoV, NoL, a) * F;
    vec3 diffuse = (1.0 - F) * (1.0 - m.metallic) * m.albedo * (1.0 / PBR_PI);
    return PBR_PI * (diffuse + spec);
}

// The split-sum's environment BRDF (scale A and bias B of F0) without a
// lookup table: Karis's fit for mobile ("Physically Based Shading on
// Mobile", 2014).
vec2 pbr_env_brdf_approx(float roughness, float NoV)
{
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = clamp(roughness, PBR_MIN_ROUGHNESS, 1.0) * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * NoV)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

// Diffuse and specular of one environment: the specular albedo Es = F0 A + B
// is what the split sum reflects; the rest (1 - Es) is left to the diffuse
// lobe, so a white dielectric under a uniform environment reflects exactly
// that environment (the white furnace).
vec3 pbr_ambient_mix(Material m, vec2 ab, vec3 irradiance, vec3 prefiltered)
{
    vec3 es = pbr_f0(m) * ab.x + ab.y;
    return (1.0 - es) * (1.0 - m.metallic) * m.albedo * irradiance + es * prefiltered;
}

// A uniform environment of radiance L (the ambient term without IBL).
vec3 pbr_uniform_ambient(Material m, vec3 N, vec3 V, float L)
{
    vec2 ab = pbr_env_brdf_approx(m.roughness, pbr_nov(N, V));
    return pbr_ambient_mix(m, ab, vec3(L), vec3(L));
}
