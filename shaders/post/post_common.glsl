// Shared by the post effects: the technique's depth and normals, read per
// pixel (texelFetch, clamped to the screen), in view space.
#include "frame.glsl"

layout(binding = SB_TEX_POST_DEPTH) uniform sampler2D u_depth;

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);

ivec2 post_clamp(ivec2 p)
{
    return clamp(p, ivec2(0), ivec2(u_frame.viewport.xy) - 1);
}

float post_depth(ivec2 p)
{
    return texelFetch(u_depth, post_clamp(p), 0).r;
}

// The view-space position of pixel p at window depth d (background: the far plane).
vec3 post_view_pos(ivec2 p, float d)
{
    vec2 uv = (vec2(p) + 0.5) * u_frame.viewport.zw;
    vec4 v = u_frame.inv_proj * vec4(uv * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
    return v.xyz / v.w;
}

// Distance along the view axis (positive), for relative depth tests.
float post_view_depth(ivec2 p)
{
    return -post_view_pos(p, post_depth(p)).z;
}

#ifdef HAVE_NORMAL_TEX
layout(binding = SB_TEX_POST_NORMAL) uniform sampler2D u_normals;

vec3 post_oct_decode(vec2 e)
{
    vec3 v = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0)
        v.xy = (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
    return v;
}

// The technique's world-space normal, in view space.
vec3 post_view_normal(ivec2 p)
{
    vec4 t = texelFetch(u_normals, post_clamp(p), 0);
#ifdef NORMAL_OCTAHEDRAL
    vec3 n = post_oct_decode(t.xy);
#else
    vec3 n = t.xyz;
#endif
    n = mat3(u_frame.view) * n;
    float len = length(n);
    return len > 1e-6 ? n / len : vec3(0.0, 0.0, 1.0);
}
#else
// Rebuilt from depth: on each axis the one-sided difference with the smaller
// depth step, so that a silhouette does not bend the normal of the surface
// in front of it. c is the pixel's view position, l r b t its neighbours'.
vec3 post_normal_from(vec3 c, vec3 l, vec3 r, vec3 b, vec3 t)
{
    vec3 dx = abs(r.z - c.z) < abs(c.z - l.z) ? r - c : c - l;
    vec3 dy = abs(t.z - c.z) < abs(c.z - b.z) ? t - c : c - b;
    vec3 n = cross(dx, dy);
    float len = length(n);
    return len > 1e-12 ? n / len : vec3(0.0, 0.0, 1.0);
}

vec3 post_view_normal(ivec2 p)
{
    float d = post_depth(p);
    if (d >= 1.0)
        return vec3(0.0, 0.0, 1.0);
    ivec2 ex = ivec2(1, 0), ey = ivec2(0, 1);
    return post_normal_from(post_view_pos(p, d),
                            post_view_pos(p - ex, post_depth(p - ex)),
                            post_view_pos(p + ex, post_depth(p + ex)),
                            post_view_pos(p - ey, post_depth(p - ey)),
                            post_view_pos(p + ey, post_depth(p + ey)));
}
#endif
