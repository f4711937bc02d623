// Asset scenes: each pixel's (each sample's, at MSAA) material key as its
// depth in the technique's key target, so that each material's shading
// pass covers its own pixels by an early GL_EQUAL depth test. Pixels with
// no surface keep the cleared 1, which no key equals.
#include "vis_fetch.glsl"

void main()
{
#if defined(SB_MSAA_SAMPLES)
    int which = gl_SampleID;
#else
    int which = 0;
#endif
    int instance, triangle;
    if (!vis_ids(ivec2(gl_FragCoord.xy), which, instance, triangle))
        discard;
    gl_FragDepth = float(vis_meshes[int(instances[instance].albedo_mesh.w)].w) / 65536.0;
}
