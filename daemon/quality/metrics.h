#ifndef SHADEBENCH_METRICS_H
#define SHADEBENCH_METRICS_H

/* Image-quality metrics on 8-bit RGB frames: SSIM (Wang et al. 2004),
 * PerceptualDiff (Yee 2004), PSNR and LDR-FLIP (Andersson et al. 2020).
 * GL-free and thread-safe: the daemon runs them on its metrics thread,
 * shadebench-compare runs them on PNG files.
 *
 * Working memory is bounded: SSIM works in strips of rows, PerceptualDiff
 * and FLIP in square tiles with a halo as wide as their filters, so that
 * beyond the two images only FLIP's error map (4 bytes a pixel, needed
 * whole for its weighted percentiles) and SSIM's 8-bit map grow with the
 * image. metrics_memory_bytes states the bound; images over
 * IMAGE_MAX_PIXELS are refused. Results are the same, bit for bit, as
 * computing each metric over the whole image at once. */

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

/* Asked between tiles or strips (milliseconds of work apart): when it returns
 * true the metric stops and fails with err "stopped". NULL: never stop. */
struct metrics_stop {
    bool (*requested)(void *ctx);
    void *ctx;
};

struct ssim_result {
    double luma;          /* on Y = 0.299 R + 0.587 G + 0.114 B, unrounded */
    double channel[3];    /* R, G, B */
    double rgb;           /* mean of the three channels */
    double min;           /* smallest local (luma) SSIM */
    int min_x, min_y;     /* centre pixel of that window */
    uint8_t *map;         /* luma SSIM map as grey (clamped to [0, 1], times 255),
                             map_w x map_h (the valid region), or NULL */
    int map_w, map_h;
};

/* keep_map: also return the luma map (free with free()). */
bool ssim_compute(const struct image *a, const struct image *b, bool keep_map,
                  const struct metrics_stop *stop, struct ssim_result *out, char *err,
                  size_t errlen);

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
                   const struct pdiff_options *o, const struct metrics_stop *stop,
                   struct pdiff_result *out, char *err, size_t errlen);
/* The same, and where failing_mask is not NULL (width x height bytes, zeroed by the
 * caller) sets the failing pixels to 1: the mask the dashboard shows. */
bool pdiff_compute_mask(const struct image *a, const struct image *b,
                        const struct pdiff_options *o, const struct metrics_stop *stop,
                        struct pdiff_result *out, uint8_t *failing_mask, char *err, size_t errlen);

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
                  bool keep_map, const struct metrics_stop *stop, struct flip_result *out,
                  char *err, size_t errlen);

/* Computes the chosen metrics of test against ref and returns them as JSON
 * (see README, "metrics"); writes the SSIM and FLIP maps where a path is
 * given. NULL on failure with err filled. An image with alpha
 * (shadebench-compare's translucent PNGs) is judged premultiplied:
 * PerceptualDiff premultiplies in float before its gamma, as perceptualdiff
 * does, and SSIM, PSNR and FLIP see each pixel's colour times its alpha,
 * rounded to 8 bits (the image composited over black). */
json_t *metrics_compare(const struct image *ref, const struct image *test,
                        const struct metrics_options *o, const char *ssim_map_path,
                        const char *flip_map_path, const struct metrics_stop *stop, char *err,
                        size_t errlen);

/* The most memory metrics_compare uses on width x height images with the
 * given FLIP pixels per degree, the two images included. */
double metrics_memory_bytes(int width, int height, double flip_ppd);

/* What translucent images add to metrics_memory_bytes: their alpha planes
 * and the premultiplied copies SSIM, PSNR and FLIP read. */
double metrics_alpha_memory_bytes(int width, int height);

/* Each metric's share of metrics_memory_bytes (images excluded). */
size_t ssim_memory_bytes(int width, int height);
size_t pdiff_memory_bytes(int width, int height);
size_t flip_memory_bytes(int width, int height, double ppd);

/* True (after filling err) when a stop was requested. */
bool metrics_stopped(const struct metrics_stop *stop, char *err, size_t errlen);

/* Difference images: the SSIM map in grey (white = 1, black = 0 or less) and
 * the FLIP map through a magma-like ramp. */
bool metrics_write_ssim_map(const char *path, const struct ssim_result *s, char *err,
                            size_t errlen);
bool metrics_write_flip_map(const char *path, const struct flip_result *f, int width,
                            int height, char *err, size_t errlen);

/* The FLIP map's ramp: its stops (r, g, b in 0..1, from 0 to 1 evenly);
 * returns their count. /v1/info serves it, so that a page can read values
 * back from the map. */
int metrics_flip_ramp(const float (**stops)[3]);
/* The colour of FLIP value v (0 to 1), as the map writes it. */
void metrics_flip_ramp_colour(float v, uint8_t rgb[3]);
/* The value a colour of the map stands for: the nearest point of the ramp. */
float metrics_flip_ramp_value(const uint8_t rgb[3]);

/* Difference views for people, with contrast (the reports): a FLIP map
 * (ramp colours) with its values times gain, cut at 1; an SSIM map (grey,
 * white = 1) with its shortfall from 1 times gain; |a - b| per channel
 * times gain into out (malloc'ed; image_finish it), with the count of
 * pixels that differ at all. */
void metrics_stretch_flip_map(struct image *map, float gain);
void metrics_stretch_ssim_map(struct image *map, float gain);
bool metrics_abs_difference(const struct image *a, const struct image *b, float gain,
                            struct image *out, long *differing);

#endif
