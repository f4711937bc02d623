#ifndef SHADEBENCH_TAA_INFO_H
#define SHADEBENCH_TAA_INFO_H

/* TAA's GL-free half: its options ({"taa": {...}} in look.post), the pass
 * it runs and what it needs of the frame contract (its history, the
 * projection's jitter and the harness's motion vectors). Any thread. */

#include "daemon/effects/effect_info.h"

/* How the reprojected history is kept near what this frame shows. */
enum taa_clamp {
    TAA_CLAMP_NONE,     /* the history as reprojected: ghosts wherever it is stale */
    TAA_CLAMP_AABB,     /* clamped into the 3x3 neighbourhood's box (YCoCg), Karis 2014 */
    TAA_CLAMP_CLIP,     /* clipped towards the box's centre, Pedersen 2016 (INSIDE) */
    TAA_CLAMP_VARIANCE, /* clipped into mean +- gamma sigma of the neighbourhood, Salvi 2016 */
};
/* How the history is read at its reprojected position. */
enum taa_filter { TAA_FILTER_BILINEAR, TAA_FILTER_CATMULL_ROM };

/* taa: temporal anti-aliasing. */
struct taa_options {
    double blend;      /* the current frame's weight in the running mean */
    int clamp;         /* enum taa_clamp */
    double gamma;      /* variance clipping's box: mean +- gamma sigma */
    int jitter_length; /* Halton (2, 3) offsets, repeating every N frames; 0: no jitter */
    int history;       /* frames before a captured frame the history starts afresh */
    int filter;        /* enum taa_filter */
};

extern const struct effect_info taa_info;

#endif
