// Deferred, first lighting step: every surface pixel gets its ambient term,
// background pixels black, as forward clears them; the per-light step then
// adds each light on top with additive blending, in light order.
#include "gbuffer.glsl"
#include "lighting.glsl"
#include "heat.glsl"
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
#if defined(SCENE_TEXTURED)
    // Asset materials: occlusion scales the ambient term, emissive is added
    // here, once (the per-light step adds only lights).
    out_color = gbuffer_surface(pixel, s)
                    ? vec4(s.occlusion * light_ambient(surface_material(s), s.P, s.N,
                                                       normalize(u_frame.eye.xyz - s.P)) +
                               s.emissive,
                           1.0)
                    : vec4(0.0, 0.0, 0.0, 1.0);
#else
    out_color = gbuffer_surface(pixel, s)
                    ? vec4(light_ambient(surface_material(s), s.P, s.N,
                                         normalize(u_frame.eye.xyz - s.P)), 1.0)
                    : vec4(0.0, 0.0, 0.0, 1.0);
#endif
    heat_set(pixel, 0u);
}
