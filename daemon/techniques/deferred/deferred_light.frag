// Deferred, per-light step: light v_light on the surface this pixel holds,
// added to the output by blending (GL_ONE, GL_ONE).
#include "gbuffer.glsl"
#include "lighting.glsl"
#include "heat.glsl"
flat in int v_light;
layout(location = 0) out vec4 out_color;
#ifdef SB_MSAA_SAMPLES
// At MSAA the stencil keeps each lighting run (per pixel, per sample) to its
// pixels: test it before the shader, which the heat map's image writes
// would otherwise put after it, every pixel then paying for both runs.
layout(early_fragment_tests) in;
#endif

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
