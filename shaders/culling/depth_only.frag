// The depth pre-pass: depth only, no colour; alpha-masked asset materials
// discard below their cutoff here as in every pass (surface.glsl).
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"

void main()
{
#if defined(SCENE_TEXTURED)
    surface_alpha_clip();
#endif
}
