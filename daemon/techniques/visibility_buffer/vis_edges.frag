// MSAA: marks (in the stencil) the pixels whose samples hold more than one
// triangle, so that shading runs once a sample there and once a pixel
// elsewhere.
#include "vis_fetch.glsl"

void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    uvec2 first = vis_raw(p, 0);
    for (int k = 1; k < SB_MSAA_SAMPLES; k++)
        if (vis_raw(p, k) != first)
            return;
    discard;
}
