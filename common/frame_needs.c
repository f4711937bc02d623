#include "common/frame_needs.h"

void frame_needs_merge(struct frame_needs *into, const struct frame_needs *n)
{
    if (n->history_frames > into->history_frames)
        into->history_frames = n->history_frames;
    if (n->jitter_length > into->jitter_length)
        into->jitter_length = n->jitter_length;
    into->motion_vectors = into->motion_vectors || n->motion_vectors;
}

double frame_halton(int64_t index, int base)
{
    double f = 1.0, r = 0.0;
    while (index > 0) {
        f /= base;
        r += f * (double)(index % base);
        index /= base;
    }
    return r;
}

void frame_jitter(int length, int64_t frame, float out[2])
{
    out[0] = out[1] = 0.0f;
    if (length <= 0)
        return;
    int64_t i = frame % length;
    if (i < 0)
        i += length;
    out[0] = (float)(frame_halton(i + 1, 2) - 0.5);
    out[1] = (float)(frame_halton(i + 1, 3) - 0.5);
}
