#ifndef SHADEBENCH_METRICS_H
#define SHADEBENCH_METRICS_H

/* Image-quality metrics on 8-bit RGB frames: SSIM (Wang et al. 2004),
 * PerceptualDiff (Yee 2004), PSNR and LDR-FLIP (Andersson et al. 2020).
 * GL-free and thread-safe: the daemon runs them on its metrics thread,
 * shadebench-compare runs them on PNG files. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/png_io.h"

/* Hot filter loops are also built for AVX2/FMA and picked at load time
 * (GCC target_clones), so one binary runs everywhere and fast where it can. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define METRICS_SIMD __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define METRICS_SIMD
#endif

/* SSIM's window: 11x11 Gaussian, sigma 1.5 (Wang et al. 2004, section III-C). */
#define SSIM_WINDOW 11

struct ssim_result {
    double luma;          /* on Y = 0.299 R + 0.587 G + 0.114 B, unrounded */
    double channel[3];    /* R, G, B */
    double rgb;           /* mean of the three channels */
    double min;           /* smallest local (luma) SSIM */
    int min_x, min_y;     /* centre pixel of that window */
    float *map;           /* luma SSIM map, map_w x map_h (valid region), or NULL */
    int map_w, map_h;
};

/* keep_map: also return the luma map (free with free()). */
bool ssim_compute(const struct image *a, const struct image *b, bool keep_map,
                  struct ssim_result *out, char *err, size_t errlen);

struct psnr_result {
    bool identical;      /* PSNR is infinite: reported as null */
    double channel[3];   /* dB, R G B; INFINITY where that channel is identical */
    double overall;      /* dB over all channels */
    double mse;
};

bool psnr_compute(const struct image *a, const struct image *b, struct psnr_result *out,
                  char *err, size_t errlen);

struct pdiff_options {
    double fov;            /* degrees of field of view of the image width */
    long threshold_pixels; /* fail when this many pixels or more fail */
    double gamma;
    double luminance;      /* cd/m^2 of the display's white */
    double color_factor;
    bool luminance_only;
};

struct pdiff_result {
    bool pass;
    long failing_pixels;
    bool identical;
};

void pdiff_defaults(struct pdiff_options *o);
bool pdiff_compute(const struct image *a, const struct image *b,
                   const struct pdiff_options *o, struct pdiff_result *out, char *err,
                   size_t errlen);

enum metric_kind { METRIC_SSIM = 1, METRIC_PDIFF = 2, METRIC_PSNR = 4, METRIC_FLIP = 8 };
#define METRIC_ALL (METRIC_SSIM | METRIC_PDIFF | METRIC_PSNR | METRIC_FLIP)

/* Which metrics to compute, with their parameters. */
struct metrics_options {
    unsigned which; /* METRIC_* bits */
    struct pdiff_options pdiff;
    double flip_ppd;
};

void metrics_options_defaults(struct metrics_options *o);

struct flip_result {
    double mean, weighted_median, weighted_q1, weighted_q3, min, max;
    float *map; /* per-pixel FLIP in [0, 1], width x height, or NULL */
};

/* The paper's default observer: a 0.7 m wide 4K monitor seen from 0.7 m. */
double flip_default_ppd(void);
bool flip_compute(const struct image *ref, const struct image *test, double ppd,
                  bool keep_map, struct flip_result *out, char *err, size_t errlen);

/* Computes the chosen metrics of test against ref and returns them as JSON
 * (see README, "metrics"); writes the SSIM and FLIP maps where a path is
 * given. NULL on failure with err filled. */
json_t *metrics_compare(const struct image *ref, const struct image *test,
                        const struct metrics_options *o, const char *ssim_map_path,
                        const char *flip_map_path, char *err, size_t errlen);

/* Difference images: the SSIM map in grey (white = 1, black = 0 or less) and
 * the FLIP map through a magma-like ramp. */
bool metrics_write_ssim_map(const char *path, const struct ssim_result *s, char *err,
                            size_t errlen);
bool metrics_write_flip_map(const char *path, const struct flip_result *f, int width,
                            int height, char *err, size_t errlen);

#endif
