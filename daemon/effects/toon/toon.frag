// Toon shading: the colour's luminance stepped to LEVELS of a ramp (hue
// kept), and outlines where the depth (and, with Sobel, the normals) change
// sharply. EDGES_SOBEL: the Sobel operator on relative view depth and on
// view normals (seed 001); EDGES_DEPTH_DIFF: the largest relative depth
// difference to the 4 neighbours (seed 003). Samples sit THICKNESS pixels
// from the centre, so thicker lines need no extra taps. Normals are rebuilt
// from depth on every technique (daemon/effects/toon.c says why).
#include "post_common.glsl"

layout(binding = SB_TEX_POST_SRC) uniform sampler2D u_src;
// x: depth threshold (relative), y: normal threshold
layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params;
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 c = texelFetch(u_src, p, 0).rgb;
    // The ramp's steps are even in perceived brightness (square root of
    // luminance), rounded up, so dim surfaces keep a shade instead of
    // falling to black.
    float l = dot(c, LUMA);
    float step_up = ceil(sqrt(max(l, 0.0)) * float(LEVELS)) / float(LEVELS);
    vec3 ramp = l > 0.0 ? c * (step_up * step_up / l) : c;

    float edge = 0.0;
#if defined(EDGES_SOBEL)
    float z[9];
    vec3 n[9];
#if THICKNESS == 1
    // One-pixel taps rebuilding normals from depth: read the 5x5 block once
    // (21 of its depths are used) instead of 5 depths for each of 9 taps.
    vec3 v[25];
    float d[25];
    for (int j = 0; j < 5; j++)
        for (int i = 0; i < 5; i++) {
            d[j * 5 + i] = post_depth(p + ivec2(i - 2, j - 2));
            v[j * 5 + i] = post_view_pos(p + ivec2(i - 2, j - 2), d[j * 5 + i]);
        }
    float zc = -v[12].z;
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            int k = (j + 1) * 5 + (i + 1);
            z[j * 3 + i] = -v[k].z / zc;
            n[j * 3 + i] = d[k] >= 1.0 ? vec3(0.0, 0.0, 1.0)
                                       : post_normal_from(v[k], v[k - 1], v[k + 1], v[k - 5], v[k + 5]);
        }
#else
    float zc = post_view_depth(p);
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            ivec2 q = p + ivec2(i - 1, j - 1) * THICKNESS;
            z[j * 3 + i] = post_view_depth(q) / zc;
            n[j * 3 + i] = post_view_normal(q);
        }
#endif
    float gx = (z[2] + 2.0 * z[5] + z[8]) - (z[0] + 2.0 * z[3] + z[6]);
    float gy = (z[6] + 2.0 * z[7] + z[8]) - (z[0] + 2.0 * z[1] + z[2]);
    vec3 nx = (n[2] + 2.0 * n[5] + n[8]) - (n[0] + 2.0 * n[3] + n[6]);
    vec3 ny = (n[6] + 2.0 * n[7] + n[8]) - (n[0] + 2.0 * n[1] + n[2]);
    // A step of relative size s gives a Sobel response of 4s.
    float depth_edge = sqrt(gx * gx + gy * gy) * 0.25;
    float normal_edge = sqrt(dot(nx, nx) + dot(ny, ny)) * 0.25;
    edge = depth_edge > u_params.x || normal_edge > u_params.y ? 1.0 : 0.0;
#elif defined(EDGES_DEPTH_DIFF)
    float zc = post_view_depth(p);
    float d = 0.0;
    d = max(d, abs(post_view_depth(p + ivec2(THICKNESS, 0)) - zc));
    d = max(d, abs(post_view_depth(p - ivec2(THICKNESS, 0)) - zc));
    d = max(d, abs(post_view_depth(p + ivec2(0, THICKNESS)) - zc));
    d = max(d, abs(post_view_depth(p - ivec2(0, THICKNESS)) - zc));
    edge = d / zc > u_params.x ? 1.0 : 0.0;
#endif
    out_color = vec4(ramp * (1.0 - edge), 1.0);
}
