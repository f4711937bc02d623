// The moving instances' motion in pixels, this frame minus the one before.
#include "frame.glsl"
in vec4 v_now;
in vec4 v_before;
layout(location = 0) out vec2 out_motion;

void main()
{
    out_motion = v_before.w > 0.0
                     ? (v_now.xy / v_now.w - v_before.xy / v_before.w) * 0.5 * u_frame.viewport.xy
                     : vec2(0.0);
}
