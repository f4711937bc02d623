// Lighting models over the scene data (scene_data.glsl comes first).

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
