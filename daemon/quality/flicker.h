#ifndef SHADEBENCH_FLICKER_H
#define SHADEBENCH_FLICKER_H

/* Temporal stability against a reference, and the reference's box filter.
 * GL-free and thread-safe; the harness calls them on the render thread
 * after the timed run (temporal.c), the unit tests on synthetic frames.
 *
 * Flicker is a temporal-difference error: for consecutive frames t-1, t of
 * the test T and the reference R, drawn with the same camera and lights,
 *     e_t = mean over pixels |(T_t - T_{t-1}) - (R_t - R_{t-1})|
 * on luma (Y = 0.299 R + 0.587 G + 0.114 B, scaled to [0, 1]). It is the
 * pixel-space form of Chu et al. 2020's tLP (TecoGAN, "Learning Temporal
 * Coherence via Self-Supervision for GAN-based Video Generation", ACM TOG
 * 39(4)), which compares the change between a generated sequence's frames
 * with the ground truth's change, and of Lai et al. 2018's temporal
 * warping error with the warp the identity: both sequences share the
 * camera, so no optical flow is needed. A technique that follows the
 * reference's change frame by frame scores 0 whatever its static error
 * (SSIM's and FLIP's business); one that holds its shading and then jumps
 * (a pop) scores the change it missed and the jump it made. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* e_t for one pair of frames. Each image is `pixels` pixels of `channels`
 * (3 or 4, the first three R, G, B) 8-bit values. */
double flicker_pair(const uint8_t *test_prev, const uint8_t *test, const uint8_t *ref_prev,
                    const uint8_t *ref, size_t pixels, int channels);

/* Over the pairs of one capture point's run of frames. */
struct flicker_result {
    int pairs;
    double sum;      /* of e_t */
    double mean;     /* sum / pairs: the run's flicker */
    double max;      /* the worst pair's e_t */
    int max_pair;    /* its index: frames max_pair and max_pair + 1 of the run */
};

void flicker_init(struct flicker_result *r);
void flicker_add(struct flicker_result *r, double e);

/* The box filter a supersampled reference goes through: each n x n block
 * of src (sw x sh, both multiples of n) becomes one pixel of dst
 * (sw/n x sh/n), averaged in linear light. The bytes are decoded with the
 * sRGB transfer function, as a display shows them, averaged, and encoded
 * back to the byte whose linear value is nearest: the eye integrates the
 * light a pixel's footprint emits, and averaging the encoded values instead
 * would darken every edge between bright and dark (the classic
 * gamma-incorrect antialiasing). A block of one colour stays that colour
 * exactly; n == 1 copies. Alpha (channels == 4) is averaged as is. */
void flicker_box_downsample(const uint8_t *src, int sw, int sh, int n, int channels,
                            uint8_t *dst);

#endif
