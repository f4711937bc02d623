// The pixels a light sphere may touch, as daemon/techniques/shared/
// culling_info.c computes them on the CPU (keep the two in step): the screen
// rectangle of the sphere's silhouette (tight) or the projected box of its
// world AABB's corners (loose). The whole viewport when the sphere reaches the
// near plane; empty when it lies outside the view.
#include "frame.glsl"

const int LIGHT_RECT_TIGHT = 0;
const int LIGHT_RECT_LOOSE = 1;

// NDC range along one axis for a sphere wholly beyond the near plane: the two
// planes through the eye tangent to it (Mara and McGuire 2013).
vec2 light_tangent_range(float ca, float cz, float r, float p_scale, float p_shift)
{
    float len2 = ca * ca + cz * cz, len = sqrt(len2);
    float cos_t = sqrt(len2 - r * r) / len, sin_t = r / len;
    float v[2];
    for (int s = 0; s < 2; s++) {
        float sn = s == 1 ? -sin_t : sin_t;
        float ta = (ca * cos_t - cz * sn) * cos_t;
        float tz = (ca * sn + cz * cos_t) * cos_t;
        v[s] = (p_scale * ta + p_shift * tz) / -tz;
    }
    return vec2(min(v[0], v[1]), max(v[0], v[1]));
}

ivec4 light_rect_pixels(vec4 ndc)
{
    vec2 size = u_frame.viewport.xy;
    vec2 lo = floor((ndc.xy * 0.5 + 0.5) * size), hi = ceil((ndc.zw * 0.5 + 0.5) * size);
    return ivec4(clamp(lo, vec2(0.0), size), clamp(hi, vec2(0.0), size));
}

// [x0, y0) to [x1, y1) in window pixels; x0 >= x1 or y0 >= y1 when empty.
ivec4 light_rect(int kind, vec3 world_centre, float r)
{
    ivec4 full = ivec4(0, 0, ivec2(u_frame.viewport.xy));
    float near_z = u_frame.clip.x, far_z = u_frame.clip.y;
    vec3 c = (u_frame.view * vec4(world_centre, 1.0)).xyz;
    if (c.z - r >= -near_z || c.z + r <= -far_z)
        return ivec4(0);
    if (c.z + r > -near_z)
        return full;
    if (kind == LIGHT_RECT_LOOSE) {
        vec4 ndc = vec4(1e30, 1e30, -1e30, -1e30);
        for (int i = 0; i < 8; i++) {
            vec3 corner = world_centre + vec3((i & 1) != 0 ? r : -r, (i & 2) != 0 ? r : -r,
                                              (i & 4) != 0 ? r : -r);
            vec4 clip = u_frame.view_proj * vec4(corner, 1.0);
            if (clip.w <= 1e-6)
                return full;
            vec2 p = clip.xy / clip.w;
            ndc = vec4(min(ndc.xy, p), max(ndc.zw, p));
        }
        return light_rect_pixels(ndc);
    }
    vec2 x = light_tangent_range(c.x, c.z, r, u_frame.proj[0][0], u_frame.proj[2][0]);
    vec2 y = light_tangent_range(c.y, c.z, r, u_frame.proj[1][1], u_frame.proj[2][1]);
    return light_rect_pixels(vec4(x.x, y.x, x.y, y.y));
}
