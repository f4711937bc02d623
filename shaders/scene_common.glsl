// Scene data shared by every technique: instances, lights and Phong shading.
// Light positions are computed on the CPU per frame (daemon/scene.c) so that
// every technique lights a frame with bit-identical light positions.

struct Instance {
    vec4 pos_scale;   // world position, uniform scale
    vec4 albedo_mesh; // albedo, mesh index
};
layout(std430, binding = 0) readonly buffer InstanceBuffer { Instance instances[]; };

struct Light {
    vec4 color_radius; // colour, influence radius (attenuation is 0 beyond it)
};
layout(std430, binding = 1) readonly buffer LightBuffer { Light lights[]; };

// Rows of u_light_count positions; row 0 is the frame being drawn, OSL uses
// further rows for objects whose shading is from an earlier frame.
layout(std430, binding = 2) readonly buffer LightPositionBuffer { vec4 light_positions[]; };

uniform int u_light_count;
uniform vec3 u_eye;

const float AMBIENT = 0.15;
const float SPECULAR = 0.5;
const float SHININESS = 32.0;

vec3 phong(vec3 P, vec3 N, vec3 albedo, int row)
{
    vec3 V = normalize(u_eye - P);
    vec3 color = AMBIENT * albedo;
    int base = row * u_light_count;
    for (int i = 0; i < u_light_count; i++) {
        vec3 Lv = light_positions[base + i].xyz - P;
        float r = lights[i].color_radius.w;
        float d2 = dot(Lv, Lv);
        if (d2 >= r * r)
            continue;
        float att = 1.0 - d2 / (r * r);
        att *= att;
        vec3 L = Lv * inversesqrt(d2);
        float nl = dot(N, L);
        if (nl <= 0.0)
            continue;
        float s = pow(max(dot(reflect(-L, N), V), 0.0), SHININESS);
        color += lights[i].color_radius.rgb * att * (albedo * nl + SPECULAR * s);
    }
    return color;
}
