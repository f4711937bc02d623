// Depth only; alpha-masked asset materials cast the shadow of what they
// show (surface.glsl).
#include "surface.glsl"

void main()
{
#if defined(SCENE_TEXTURED)
    surface_alpha_clip();
#endif
}
