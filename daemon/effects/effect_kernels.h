#ifndef SHADEBENCH_EFFECT_KERNELS_H
#define SHADEBENCH_EFFECT_KERNELS_H

/* The numbers the post effects' shaders are given, computed GL-free so that
 * they are unit-tested and the same on every device: Gaussian blur weights,
 * the SSAO hemisphere kernel and its rotation noise (from a fixed seed, so
 * frame k is a pure function of k), and the tone curves the resolve applies
 * (the GLSL in shaders/harness/resolve.frag follows these formulas). Pure
 * functions; any thread. */

#include <stdbool.h>
#include <stdint.h>

#define BLOOM_MAX_RADIUS 32
#define SSAO_MAX_SAMPLES 64
#define SSAO_NOISE_SIZE 4 /* the noise tiles the screen in 4x4 pixels */
#define SSAO_SEED 0x5eed0a0u

/* Weights w[0..radius] of a Gaussian with sigma = radius / 2, normalised so
 * that w[0] + 2 * (w[1] + ... + w[radius]) = 1: the separable taps, and
 * w[|i|] * w[|j|] the 2D ones. False when radius is out of 1..BLOOM_MAX_RADIUS. */
bool gauss_weights(int radius, float *w);

/* samples points in the unit hemisphere around +z (tangent space), spread
 * from the centre outwards (scaled by mix(0.1, 1, (i/n)^2), so that near
 * occluders weigh more), from seed. out[i] = x, y, z, 0. */
bool ssao_kernel(int samples, uint32_t seed, float (*out)[4]);

/* Rotation angles (radians) for the 4x4 noise tile, row-major, from seed. */
void ssao_noise(uint32_t seed, float angles[SSAO_NOISE_SIZE * SSAO_NOISE_SIZE]);

/* Tone curves on a linear value (after exposure), to [0, 1]. */
double tonemap_reinhard(double x);
double tonemap_aces(double x); /* Narkowicz's 2015 fit of the ACES RRT+ODT */
/* The sRGB transfer function (IEC 61966-2-1) on [0, 1]. */
double srgb_encode(double linear);

#endif
