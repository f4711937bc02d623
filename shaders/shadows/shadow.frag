// Depth only; alpha-masked asset materials cast the shadow of what they
// show (surface.glsl).
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"

void main()
{
#if defined(SCENE_TEXTURED)
    surface_alpha_clip();
#endif
}
