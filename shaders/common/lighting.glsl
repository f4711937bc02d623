// The lighting library. One function gives one light's contribution, and
// every light loop calls it (all lights here; per tile and per cluster in
// the culling techniques), so that every technique's image agrees with
// forward's. The model is chosen by #define: LIGHTING_PHONG (the thesis's,
// the default), LIGHTING_BLINN_PHONG (the seeds' deferred renderers) or
// LIGHTING_PBR (seed 002: Cook-Torrance, GGX, Smith height-correlated,
// Schlick, metallic-roughness). Features the harness switches on add
// defines as well: LOOK_IBL (image-based ambient from the harness's probes,
// shaders/common/ibl.glsl) and LOOK_SHADOWS (omni shadow maps from the
// harness's atlas, shaders/common/shadows.glsl).
//
// Light loops call the Material forms: light_contribution(i, Lpos, P, N, V,
// m) and light_ambient(m, P, N, V). The older forms taking albedo, specular
// and shininess stay for code written before materials; under PBR they
// read shininess as roughness (Beckmann's sqrt(2 / (n + 2))) and metallic 0.
#include "frame.glsl"
#include "scene_data.glsl"
#include "light_shape.glsl"

#if !defined(LIGHTING_PHONG) && !defined(LIGHTING_BLINN_PHONG) && !defined(LIGHTING_PBR)
#define LIGHTING_PHONG 1
#endif

const float AMBIENT = 0.15;

#if defined(LIGHTING_PBR)
#include "pbr.glsl"
#endif
#if defined(LOOK_IBL)
#include "ibl.glsl"
#endif
#if defined(LOOK_SHADOWS)
#include "shadows.glsl"
#endif

vec3 light_ambient(vec3 albedo)
{
    return AMBIENT * albedo;
}

// Light i's position in row `row` (0: the frame being drawn; OSL reads older
// rows for objects whose shading is from an earlier frame).
vec3 light_position(int i, int row)
{
    return light_positions[row * u_frame.counts.y + i].xyz;
}

// Light i at Lpos on the surface point P (normal N, towards the eye V).
// Point and spot lights: attenuation reaches exactly 0 at the light's radius,
// and a spot's cone falloff exactly 0 at its outer angle, so culling a light
// by its sphere or cone never changes the image. The presets' lights fall
// off as a window (1 - d^2 / r^2)^2; glTF's (asset scenes, scene.light_rig)
// as 1 / d^2, times clamp(1 - (d / range)^4, 0, 1) with a range
// (KHR_lights_punctual), cut at the radius without one (daemon/scene/
// scene.h: enum scene_light_falloff). A directional light (Lpos unused) is
// unattenuated and lights every surface facing it, from -direction.
// How much of light i reaches P (0: none; before the surface and shadows)
// and its direction L from P.
float light_reach(int i, vec3 Lpos, vec3 P, out vec3 L)
{
    int type = light_type(i);
    if (type == LIGHT_DIRECTIONAL) {
        L = -lights[i].direction_type.xyz;
        return 1.0;
    }
    vec3 Lv = Lpos - P;
    float r = lights[i].color_radius.w;
    float d2 = dot(Lv, Lv);
    L = vec3(0.0, 0.0, 1.0);
    if (d2 >= r * r)
        return 0.0;
    float att;
    if (int(lights[i].falloff.x) == LIGHT_FALLOFF_GLTF) {
        float range = lights[i].falloff.y;
        att = 1.0 / max(d2, 1e-8);
        if (range > 0.0) {
            float q = d2 / (range * range);
            att *= clamp(1.0 - q * q, 0.0, 1.0);
        }
    } else {
        att = 1.0 - d2 / (r * r);
        att *= att;
    }
    L = Lv * inversesqrt(d2);
    if (type == LIGHT_SPOT)
        att *= max(light_spot_falloff(i, -L), 0.0);
    return att;
}

vec3 light_contribution(int i, vec3 Lpos, vec3 P, vec3 N, vec3 V, Material m)
{
    int type = light_type(i);
    vec3 L;
    float att = light_reach(i, Lpos, P, L);
    if (att <= 0.0)
        return vec3(0.0);
    float nl = dot(N, L);
    if (nl <= 0.0)
        return vec3(0.0);
#if defined(LOOK_SHADOWS)
    if (type == LIGHT_DIRECTIONAL)
        att *= shadow_sun_visibility(i, P, N);
    else
        att *= shadow_visibility(i, P, N, nl);
#endif
#if defined(LIGHTING_PBR)
    // Light colours are the irradiance a light gives a surface facing it
    // (as Phong's diffuse term reads them), so the BRDF is scaled by pi:
    // a white Lambertian surface then looks as bright as under Phong.
    return lights[i].color_radius.rgb * (att * nl) * pbr_brdf(N, V, L, nl, m);
#else
#if defined(LIGHTING_BLINN_PHONG)
    float s = pow(max(dot(N, normalize(L + V)), 0.0), m.shininess);
#else
    float s = pow(max(dot(reflect(-L, N), V), 0.0), m.shininess);
#endif
    return lights[i].color_radius.rgb * att * (m.albedo * nl + m.specular * s);
#endif
}

// The material a caller without metallic and roughness means.
Material material_from_phong(vec3 albedo, float specular, float shininess)
{
    return Material(albedo, specular, shininess, 0.0, sqrt(2.0 / (shininess + 2.0)));
}

vec3 light_contribution(int i, vec3 Lpos, vec3 P, vec3 N, vec3 V, vec3 albedo,
                        float specular, float shininess)
{
    return light_contribution(i, Lpos, P, N, V, material_from_phong(albedo, specular, shininess));
}

// Light that does not come from the scene's lights: Phong's constant
// term; under PBR a uniform environment of radiance AMBIENT, or with
// LOOK_IBL the harness's environment and probes.
vec3 light_ambient(Material m, vec3 P, vec3 N, vec3 V)
{
#if defined(LIGHTING_PBR)
#if defined(LOOK_IBL)
    return ibl_ambient(m, P, N, V);
#else
    return pbr_uniform_ambient(m, N, V, AMBIENT);
#endif
#else
    return light_ambient(m.albedo);
#endif
}

// Every light, for forward and OSL; m from instance_material().
vec3 shade_all_lights(vec3 P, vec3 N, Material m, int row)
{
    vec3 V = normalize(u_frame.eye.xyz - P);
    vec3 color = light_ambient(m, P, N, V);
    for (int i = 0; i < u_frame.counts.y; i++)
        color += light_contribution(i, light_position(i, row), P, N, V, m);
    return color;
}
