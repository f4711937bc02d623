#ifndef SHADEBENCH_SSAO_INFO_H
#define SHADEBENCH_SSAO_INFO_H

/* SSAO's GL-free half: its options ({"ssao": {...}} in look.post), the
 * passes it runs for them, and the hemisphere kernel and rotation noise
 * its shader is given (from a fixed seed, so that frame k is a pure
 * function of k, and unit-tested). Any thread. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/effects/effect_info.h"

#define SSAO_MAX_SAMPLES 64
#define SSAO_NOISE_SIZE 4 /* the noise tiles the screen in 4x4 pixels */
#define SSAO_SEED 0x5eed0a0u

/* ssao: hemisphere ambient occlusion, blurred, multiplied into the colour. */
struct ssao_options {
    int samples;      /* hemisphere samples per pixel */
    double radius;    /* world units */
    double bias;      /* depth bias against self-occlusion, world units */
    bool blur;        /* 4x4 blur over the noise tile (seed 002's "blurry SSAO") */
    double intensity; /* exponent on the occlusion term: 0 none, 1 as computed */
};

extern const struct effect_info ssao_info;

/* samples points in the unit hemisphere around +z (tangent space), spread
 * from the centre outwards (scaled by mix(0.1, 1, (i/n)^2), so that near
 * occluders weigh more), from seed. out[i] = x, y, z, 0. */
bool ssao_kernel(int samples, uint32_t seed, float (*out)[4]);

/* Rotation angles (radians) for the 4x4 noise tile, row-major, from seed. */
void ssao_noise(uint32_t seed, float angles[SSAO_NOISE_SIZE * SSAO_NOISE_SIZE]);

#endif
