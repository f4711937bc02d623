// MSAA g-buffer: folds the frame's edge-pixel count into the run's figures
// (frames, largest, last, a 64-bit sum) and zeroes it for the next frame,
// so that the figures are read back once, after the run.
layout(local_size_x = 1) in;
layout(std430, binding = SB_SSBO_EDGE_STATS) buffer EdgeStats {
    uint edge_pixels;
    uint frames, max_pixels, last_pixels, sum_lo, sum_hi;
};

void main()
{
    uint n = edge_pixels;
    frames += 1u;
    max_pixels = max(max_pixels, n);
    last_pixels = n;
    uint lo = sum_lo + n;
    sum_hi += lo < sum_lo ? 1u : 0u;
    sum_lo = lo;
    edge_pixels = 0u;
}
