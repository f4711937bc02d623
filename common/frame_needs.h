#ifndef SHADEBENCH_FRAME_NEEDS_H
#define SHADEBENCH_FRAME_NEEDS_H

/* What a stage of a frame (a technique, a post effect) needs of time, in
 * the frame contract's GL-free half: how many frames of history it keeps,
 * whether the projection is jittered for it and how long the jitter
 * sequence is, and whether it reads the harness's motion vectors. The
 * harness merges the needs of a run's technique and post chain, and keeps
 * frame k a pure function of k by starting every history afresh
 * history_frames frames before each captured frame (and rendering those
 * frames first wherever a captured frame is drawn alone: the reference,
 * the temporal frames). The jitter is a pure function of the frame index.
 * Any thread. */

#include <stdbool.h>
#include <stdint.h>

/* The most history frames a stage may ask for. */
#define FRAME_MAX_HISTORY 64
/* The longest jitter sequence. */
#define FRAME_MAX_JITTER 256

struct frame_needs {
    int history_frames;  /* 0: no history; else frames before a captured frame it reaches */
    int jitter_length;   /* 0: no jitter; else Halton (2, 3) offsets repeating every N frames */
    bool motion_vectors; /* it reads the harness's motion-vector target */
};

/* into takes the larger history and jitter length and either's motion
 * vectors. */
void frame_needs_merge(struct frame_needs *into, const struct frame_needs *n);

/* The radical inverse of index in base (the Halton sequence's element
 * index, 1-based: index 0 is 0). */
double frame_halton(int64_t index, int base);

/* The projection's sub-pixel offset at frame (any integer, warm-up frames'
 * negative ones included) for a sequence of length N: the Halton (2, 3)
 * point at 1 + (frame mod N), centred on the pixel, each coordinate in
 * (-0.5, 0.5). Zero when length is 0. */
void frame_jitter(int length, int64_t frame, float out[2]);

#endif
