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
    out_color = vec4(environment_radiance(far.xyz / far.w - u_frame.eye.xyz), 1.0);
}
