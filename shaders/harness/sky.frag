// The harness's sky pass: the environment seen through every pixel the
// technique left empty, in the frame block's camera (the frame's, or a light
// probe's face during capture).
#include "frame.glsl"
#include "environment.glsl"
layout(location = 0) out vec4 out_color;

void main()
{
    vec2 ndc = gl_FragCoord.xy * u_frame.viewport.zw * 2.0 - 1.0;
    vec4 far = u_frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
#if defined(ENV_MAP)
    // The pixel's width as an angle: the direction one pixel to the right.
    vec4 next = u_frame.inv_view_proj * vec4(ndc.x + 2.0 * u_frame.viewport.z, ndc.y, 1.0, 1.0);
    vec3 d = normalize(far.xyz / far.w - u_frame.eye.xyz);
    vec3 dn = normalize(next.xyz / next.w - u_frame.eye.xyz);
    out_color = vec4(environment_map(d, acos(clamp(dot(d, dn), -1.0, 1.0))), 1.0);
#else
    out_color = vec4(environment_radiance(far.xyz / far.w - u_frame.eye.xyz), 1.0);
#endif
}
