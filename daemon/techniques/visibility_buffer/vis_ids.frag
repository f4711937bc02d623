// The visibility pass: each pixel's instance and triangle (Burns and Hunt
// 2013), nothing else; depth goes to the output's depth texture as every
// technique's does. Alpha-masked asset materials discard below their cutoff
// here as in every pass (surface.glsl). gl_PrimitiveID counts a draw's
// triangles from 0 again at each instance: it is the mesh's own triangle.
#define SURFACE_VERTEX_COLOR 1 // the vertex stage passes COLOR_0
#include "surface.glsl"
flat in int v_instance;
#if defined(VIS_WIDE)
layout(location = 0) out uvec2 out_id;
#else
layout(location = 0) out uint out_id;
#endif

void main()
{
#if defined(SCENE_TEXTURED)
    surface_alpha_clip();
#endif
#if defined(VIS_WIDE)
    out_id = uvec2(uint(v_instance + 1), uint(gl_PrimitiveID));
#else
    out_id = (uint(v_instance + 1) << VIS_TRIANGLE_BITS) | uint(gl_PrimitiveID);
#endif
}
