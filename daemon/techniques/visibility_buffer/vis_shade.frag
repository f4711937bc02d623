// The visibility buffer's shading: each pixel's triangle fetched and its
// attributes rebuilt (vis_fetch.glsl), then lit as forward lights it: every
// light (shade_all_lights, surface_shade_all_lights) or the pixel's
// cluster's (light_grid.glsl), with the same material functions
// (scene_data.glsl's instance material; surface.glsl's material_surface_grad
// with the rebuilt derivatives in asset scenes, where each material's
// textures are bound for the pass that draws its pixels). VIS_PER_SAMPLE:
// once a sample (MSAA edge pixels), each sample's triangle still evaluated
// at the pixel's centre, as forward shades it.
#define SURFACE_NO_VARYINGS 1 // attributes come from the fetch, not the vertex stage
#include "vis_fetch.glsl"
#include "surface.glsl"
#if defined(VIS_CLUSTERED)
#include "light_grid.glsl"
#endif
layout(early_fragment_tests) in;
layout(location = 0) out vec4 out_color;

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
#if defined(VIS_PER_SAMPLE)
    int which = gl_SampleID;
#else
    int which = 0;
#endif
    VisSurface v;
    if (!vis_surface(p, which, v)) {
        out_color = vec4(0.0, 0.0, 0.0, 1.0); // the background, as forward clears it
        return;
    }
#if defined(VIS_CLUSTERED)
    uint evaluations;
    int cell = grid_cell(vec2(p) + 0.5, -(u_frame.view * vec4(v.P, 1.0)).z);
#endif
#if defined(SCENE_TEXTURED)
    TexturedSurface s = material_surface_grad(vis_meshes[v.mesh].z, v.tex, v.dtex_dx, v.dtex_dy,
                                              v.N, v.tangent, v.front, v.color);
#if defined(VIS_CLUSTERED)
    vec3 color = shade_cell(cell, v.P, s.N, s.m, s.occlusion, evaluations) + s.emissive;
#else
    vec3 color = surface_shade_all_lights(v.P, s);
#endif
#else
    Material m = instance_material(v.instance);
#if defined(VIS_CLUSTERED)
    vec3 color = shade_cell(cell, v.P, v.N, m, evaluations);
#else
    vec3 color = shade_all_lights(v.P, v.N, m, 0);
#endif
#endif
    out_color = vec4(color, 1.0);
}
