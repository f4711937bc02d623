#ifndef SHADEBENCH_TOON_INFO_H
#define SHADEBENCH_TOON_INFO_H

/* Toon's GL-free half: its options ({"toon": {...}} in look.post) and the
 * pass it runs. Any thread. */

#include "daemon/effects/effect_info.h"

/* toon: colour ramp and outlines. */
enum toon_edges { TOON_EDGES_SOBEL, TOON_EDGES_DEPTH_DIFF, TOON_EDGES_NONE };
struct toon_options {
    int levels;              /* steps of the luminance ramp */
    int edges;               /* enum toon_edges */
    double threshold;        /* relative view-depth difference that makes an edge */
    double normal_threshold; /* sobel: normal gradient that makes an edge */
    int thickness;           /* pixels between the samples the edge test compares */
};

extern const struct effect_info toon_info;

#endif
