// SSAO: the fraction of SAMPLES points of a hemisphere around the surface
// normal (radius in world units) that lie behind the depth buffer, from the
// fixed kernel and the 4x4 tile of rotations the C side computed, so frame k
// depends on frame k's depth alone. Writes the unoccluded fraction (1 = open).
#include "post_common.glsl"

layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params; // x: radius, y: bias
layout(location = SB_LOC_SSAO_NOISE) uniform float u_noise[16];
layout(location = SB_LOC_SSAO_KERNEL) uniform vec4 u_kernel[SAMPLES];
layout(location = 0) out vec4 out_ao;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d = post_depth(p);
    if (d >= 1.0) {
        out_ao = vec4(1.0);
        return;
    }
    vec3 pos = post_view_pos(p, d), n = post_view_normal(p);
    float a = u_noise[(p.x & 3) + 4 * (p.y & 3)];
    vec3 r = vec3(cos(a), sin(a), 0.0);
    vec3 t = r - n * dot(r, n);
    if (dot(t, t) < 1e-6) // the rotation lies along the normal: any tangent will do
        t = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) - n * n.x : vec3(0.0, 1.0, 0.0) - n * n.y;
    t = normalize(t);
    mat3 tbn = mat3(t, cross(n, t), n);
    float radius = u_params.x, bias = u_params.y, occluded = 0.0;
    for (int i = 0; i < SAMPLES; i++) {
        vec3 s = pos + tbn * u_kernel[i].xyz * radius;
        vec4 clip = u_frame.proj * vec4(s, 1.0);
        vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0))))
            continue; // off screen: nothing known, count it open
        ivec2 q = ivec2(uv * u_frame.viewport.xy);
        float scene_z = post_view_pos(q, post_depth(q)).z;
        // Occluders far in front of the point (another object's silhouette)
        // fade out instead of darkening a halo around it.
        float range = smoothstep(0.0, 1.0, radius / max(abs(pos.z - scene_z), 1e-4));
        occluded += (scene_z >= s.z + bias ? 1.0 : 0.0) * range;
    }
    out_ao = vec4(1.0 - occluded / float(SAMPLES));
}
