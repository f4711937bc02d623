#ifndef SHADEBENCH_BLOOM_INFO_H
#define SHADEBENCH_BLOOM_INFO_H

/* Bloom's GL-free half: its options ({"bloom": {...}} in look.post), the
 * passes it runs for them, and the Gaussian weights its blur is given
 * (computed here so that they are unit-tested and the same on every
 * device). Any thread. */

#include <stdbool.h>

#include "daemon/effects/effect_info.h"

#define BLOOM_MAX_RADIUS 32

/* bloom: bright pass, Gaussian blur of what passed it, added back. */
enum bloom_kernel { BLOOM_SEPARABLE, BLOOM_2D };
struct bloom_options {
    double threshold; /* luminance above which light blooms */
    int kernel;       /* enum bloom_kernel */
    int radius;       /* taps each side: (2r+1) a row, (2r+1)^2 for 2d */
    double intensity; /* scale of the blurred light added back */
    int downsample;   /* 0: blur at full size; n: a mip chain of n halvings */
};

extern const struct effect_info bloom_info;

/* Weights w[0..radius] of a Gaussian with sigma = radius / 2, normalised so
 * that w[0] + 2 * (w[1] + ... + w[radius]) = 1: the separable taps, and
 * w[|i|] * w[|j|] the 2D ones. False when radius is out of 1..BLOOM_MAX_RADIUS. */
bool gauss_weights(int radius, float *w);

#endif
