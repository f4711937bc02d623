// Counts the pixels of the HDR colour the resolve reads that are NaN or
// infinite in any of R, G, B, and (HALF_TARGET) those holding the largest
// 16-bit float, 65504: where a driver clamps an overflowing write (llvmpipe
// does) instead of writing infinity, that value is the overflow's trace.
// The tests read the bits, not isnan/isinf, which a compiler allowed to
// assume finite floats may fold away.
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = SB_TEX_HDR) uniform sampler2D u_hdr;
layout(std430, binding = SB_SSBO_NONFINITE) buffer NonFinite {
    uint nan_pixels;
    uint inf_pixels;
    uint overflow_pixels;
};

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, textureSize(u_hdr, 0))))
        return;
    vec3 c = texelFetch(u_hdr, p, 0).rgb;
    uvec3 bits = floatBitsToUint(c);
    bvec3 special = equal(bits & 0x7f800000u, uvec3(0x7f800000u));
    bvec3 mantissa = notEqual(bits & 0x007fffffu, uvec3(0u));
    bool nan = any(bvec3(special.x && mantissa.x, special.y && mantissa.y,
                         special.z && mantissa.z));
    if (nan)
        atomicAdd(nan_pixels, 1u);
    else if (any(special))
        atomicAdd(inf_pixels, 1u);
#ifdef HALF_TARGET
    else if (any(equal(abs(c), vec3(65504.0))))
        atomicAdd(overflow_pixels, 1u);
#endif
}
