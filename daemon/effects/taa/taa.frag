// TAA's resolve (daemon/effects/taa/taa.c): this frame's pixel blended into
// the history, which is read where the pixel's surface was the frame
// before (the harness's motion vectors, the nearest depth's in the 3x3
// neighbourhood so that edges move with their foreground), and kept to
// what this frame shows around the pixel: its 3x3 neighbourhood in YCoCg,
// by clamping into its box (Karis 2014), clipping towards its centre
// (Pedersen 2016) or clipping into mean +- gamma sigma (Salvi 2016). All of
// it in a tone-mapped space, c / (1 + max(c)), inverted at the end, so that
// one bright sample cannot dominate the mean (Karis 2014; Lottes). A pixel
// whose history lies off screen, and every pixel of a frame that restarts
// the history, is this frame's own.
#include "post_common.glsl"
layout(binding = SB_TEX_POST_SRC) uniform sampler2D u_src;
layout(binding = SB_TEX_POST_AUX) uniform sampler2D u_history; // bilinear sampler bound
layout(binding = SB_TEX_POST_MOTION) uniform sampler2D u_motion;
layout(location = SB_LOC_POST_PARAMS) uniform vec4 u_params; // blend, gamma, restart, 0
layout(location = 0) out vec4 out_color;

vec3 tonemap(vec3 c)
{
    c = max(c, vec3(0.0));
    return c / (1.0 + max(c.r, max(c.g, c.b)));
}

vec3 untonemap(vec3 t)
{
    return t / max(1.0 - max(t.r, max(t.g, t.b)), 1e-6);
}

vec3 to_ycocg(vec3 c)
{
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b,
                -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}

vec3 from_ycocg(vec3 c)
{
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

// The history at uv: bilinear, or Catmull-Rom from 5 bilinear taps (the
// corner taps of the 4x4 weigh almost nothing).
vec3 history_at(vec2 uv)
{
#if defined(TAA_CATMULL_ROM)
    vec2 size = u_frame.viewport.xy;
    vec2 pos = uv * size;
    vec2 c1 = floor(pos - 0.5) + 0.5;
    vec2 f = pos - c1;
    vec2 w0 = f * (-0.5 + f * (1.0 - 0.5 * f));
    vec2 w1 = 1.0 + f * f * (-2.5 + 1.5 * f);
    vec2 w2 = f * (0.5 + f * (2.0 - 1.5 * f));
    vec2 w3 = f * f * (-0.5 + 0.5 * f);
    vec2 w12 = w1 + w2;
    vec2 t0 = (c1 - 1.0) * u_frame.viewport.zw;
    vec2 t3 = (c1 + 2.0) * u_frame.viewport.zw;
    vec2 t12 = (c1 + w2 / w12) * u_frame.viewport.zw;
    vec3 sum = textureLod(u_history, vec2(t12.x, t0.y), 0.0).rgb * (w12.x * w0.y) +
               textureLod(u_history, vec2(t0.x, t12.y), 0.0).rgb * (w0.x * w12.y) +
               textureLod(u_history, t12, 0.0).rgb * (w12.x * w12.y) +
               textureLod(u_history, vec2(t3.x, t12.y), 0.0).rgb * (w3.x * w12.y) +
               textureLod(u_history, vec2(t12.x, t3.y), 0.0).rgb * (w12.x * w3.y);
    float weight = w12.x * w0.y + w0.x * w12.y + w12.x * w12.y + w3.x * w12.y + w12.x * w3.y;
    return max(sum / weight, vec3(0.0));
#else
    return textureLod(u_history, uv, 0.0).rgb;
#endif
}

// q moved along the line to the box's centre until it lies in the box.
vec3 clip_box(vec3 lo, vec3 hi, vec3 q)
{
    vec3 c = 0.5 * (lo + hi), e = 0.5 * (hi - lo) + 1e-7;
    vec3 v = q - c;
    vec3 a = abs(v / e);
    float m = max(a.x, max(a.y, a.z));
    return m > 1.0 ? c + v / m : q;
}

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 now_rgb = texelFetch(u_src, p, 0).rgb;
    if (u_params.z > 0.5) {
        out_color = vec4(now_rgb, 1.0);
        return;
    }
    vec3 now = to_ycocg(tonemap(now_rgb));
    vec3 lo = now, hi = now, m1 = vec3(0.0), m2 = vec3(0.0);
    float nearest = 2.0;
    ivec2 at = p;
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            ivec2 q = post_clamp(p + ivec2(dx, dy));
            vec3 c = to_ycocg(tonemap(texelFetch(u_src, q, 0).rgb));
            lo = min(lo, c);
            hi = max(hi, c);
            m1 += c;
            m2 += c * c;
            float z = post_depth(q);
            if (z < nearest) {
                nearest = z;
                at = q;
            }
        }
    vec2 motion = texelFetch(u_motion, at, 0).rg;
    vec2 uv = (gl_FragCoord.xy - motion) * u_frame.viewport.zw;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
        out_color = vec4(now_rgb, 1.0);
        return;
    }
    vec3 history = to_ycocg(tonemap(history_at(uv)));
#if defined(TAA_CLAMP_AABB)
    history = clamp(history, lo, hi);
#elif defined(TAA_CLAMP_CLIP)
    history = clip_box(lo, hi, history);
#elif defined(TAA_CLAMP_VARIANCE)
    vec3 mean = m1 / 9.0;
    vec3 sigma = sqrt(max(m2 / 9.0 - mean * mean, vec3(0.0)));
    // The box of mean +- gamma sigma, within the neighbourhood's, and
    // always holding this frame's own sample: where the pixel stands out
    // from its neighbours (a highlight) the box would otherwise pull a
    // history equal to it towards their mean, and dim it.
    history = clip_box(min(max(mean - u_params.y * sigma, lo), now),
                       max(min(mean + u_params.y * sigma, hi), now), history);
#endif
    vec3 blended = mix(history, now, u_params.x);
    out_color = vec4(untonemap(max(from_ycocg(blended), vec3(0.0))), 1.0);
}
