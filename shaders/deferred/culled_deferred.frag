// Tiled and clustered deferred lighting: one full-screen pass, each surface
// pixel looping over its cell's lights (light_grid.glsl).
#include "gbuffer.glsl"
#include "light_grid.glsl"
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
    uint evaluations = 0u;
    vec3 color = vec3(0.0);
    if (gbuffer_surface(pixel, s)) {
        float d = -(u_frame.view * vec4(s.P, 1.0)).z;
#if defined(SCENE_TEXTURED)
        color = shade_cell(grid_cell(gl_FragCoord.xy, d), s.P, s.N, surface_material(s),
                           s.occlusion, evaluations) +
                s.emissive;
#else
        color = shade_cell(grid_cell(gl_FragCoord.xy, d), s.P, s.N, surface_material(s),
                           evaluations);
#endif
    }
#ifdef GBUFFER_PER_SAMPLE
    heat_add(pixel, evaluations); // each sample's, over a cleared map
#else
    heat_set(pixel, evaluations);
#endif
    out_color = vec4(color, 1.0);
}
