// The harness's transparent pass (daemon/harness/transparent.c): a blended
// asset material, forward-shaded over every light, its alpha for the
// blend; the same for every technique.
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
in vec3 v_world;
in vec3 v_normal;
flat in int v_instance;
layout(location = 0) out vec4 out_color;

void main()
{
#if defined(SCENE_TEXTURED) && defined(LOOK_DEBUG)
    // look.debug: the channel, opaque, as the sample viewer draws it.
    out_color = vec4(surface_debug_here(normalize(v_normal)), 1.0);
#elif defined(SCENE_TEXTURED)
    TexturedSurface s = surface_here(normalize(v_normal));
    out_color = vec4(surface_shade_all_lights(v_world, s), s.alpha);
#else
    out_color = vec4(0.0);
#endif
}
