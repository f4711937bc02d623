// Deferred, per-light step: light v_light on the surface this pixel holds,
// added to the output by blending (GL_ONE, GL_ONE).
#include "gbuffer.glsl"
#include "lighting.glsl"
#include "heat.glsl"
flat in int v_light;
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    Surface s;
    if (!gbuffer_surface(pixel, s))
        discard;
    vec3 V = normalize(u_frame.eye.xyz - s.P);
    out_color = vec4(light_contribution(v_light, light_position(v_light, 0), s.P, s.N, V,
                                        surface_material(s)), 0.0);
    heat_add(pixel, 1u);
}
