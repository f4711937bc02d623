// MSAA g-buffer, the edge pass: marks (in the stencil of the edge target:
// the fragments it keeps) the pixels whose samples hold more than one
// surface, which lighting then shades per sample, and counts them.
#include "gbuffer.glsl"
layout(std430, binding = SB_SSBO_EDGE_STATS) buffer EdgeStats {
    uint edge_pixels; // this frame
    uint frames, max_pixels, last_pixels, sum_lo, sum_hi;
};

void main()
{
    if (!gbuffer_edge(ivec2(gl_FragCoord.xy)))
        discard;
    atomicAdd(edge_pixels, 1u);
}
