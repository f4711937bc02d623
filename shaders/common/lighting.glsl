// The lighting library. One function gives one light's contribution, and
// every light loop calls it (all lights here; per tile and per cluster in
// the culling techniques), so that every technique's image agrees with
// forward's. The model is chosen by #define: LIGHTING_PHONG (the thesis's,
// the default) or LIGHTING_BLINN_PHONG (the seeds' deferred renderers).
#include "frame.glsl"
#include "scene_data.glsl"

#if !defined(LIGHTING_PHONG) && !defined(LIGHTING_BLINN_PHONG)
#define LIGHTING_PHONG 1
#endif

const float AMBIENT = 0.15;

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
// Attenuation reaches exactly 0 at the light's radius, so culling a light by
// its radius never changes the image.
vec3 light_contribution(int i, vec3 Lpos, vec3 P, vec3 N, vec3 V, vec3 albedo,
                        float specular, float shininess)
{
    vec3 Lv = Lpos - P;
    float r = lights[i].color_radius.w;
    float d2 = dot(Lv, Lv);
    if (d2 >= r * r)
        return vec3(0.0);
    float att = 1.0 - d2 / (r * r);
    att *= att;
    vec3 L = Lv * inversesqrt(d2);
    float nl = dot(N, L);
    if (nl <= 0.0)
        return vec3(0.0);
#if defined(LIGHTING_BLINN_PHONG)
    float s = pow(max(dot(N, normalize(L + V)), 0.0), shininess);
#else
    float s = pow(max(dot(reflect(-L, N), V), 0.0), shininess);
#endif
    return lights[i].color_radius.rgb * att * (albedo * nl + specular * s);
}

// Every light, for forward and OSL; m from instance_material().
vec3 shade_all_lights(vec3 P, vec3 N, Material m, int row)
{
    vec3 V = normalize(u_frame.eye.xyz - P);
    vec3 color = light_ambient(m.albedo);
    for (int i = 0; i < u_frame.counts.y; i++)
        color += light_contribution(i, light_position(i, row), P, N, V, m.albedo, m.specular,
                                    m.shininess);
    return color;
}
