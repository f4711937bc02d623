// Deferred, first lighting step: every surface pixel gets its ambient term,
// background pixels black, as forward clears them; the per-light step then
// adds each light on top with additive blending, in light order.
#include "gbuffer.glsl"
#include "lighting.glsl"
#include "heat.glsl"
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    Surface s;
    out_color = gbuffer_surface(pixel, s)
                    ? vec4(light_ambient(surface_material(s), s.P, s.N,
                                         normalize(u_frame.eye.xyz - s.P)), 1.0)
                    : vec4(0.0, 0.0, 0.0, 1.0);
    heat_set(pixel, 0u);
}
