/* SSIM as defined by Wang, Bovik, Sheikh and Simoncelli, "Image Quality
 * Assessment: From Error Visibility to Structural Similarity", IEEE TIP 2004:
 * 11x11 circular-symmetric Gaussian window with sigma 1.5 normalised to unit
 * sum, K1 = 0.01, K2 = 0.03, L = 255, population (weighted) statistics, and
 * the mean over the valid region only (no padding). This matches
 * scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
 * use_sample_covariance=False, data_range=255). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/metrics/metrics.h"

static const double K1 = 0.01, K2 = 0.03, L = 255.0, SIGMA = 1.5;
enum { R = SSIM_WINDOW / 2 };

static void gaussian_kernel(double k[SSIM_WINDOW])
{
    double w[SSIM_WINDOW], sum = 0;
    for (int i = 0; i < SSIM_WINDOW; i++) {
        double x = i - R;
        w[i] = exp(-x * x / (2.0 * SIGMA * SIGMA));
        sum += w[i];
    }
    for (int i = 0; i < SSIM_WINDOW; i++)
        k[i] = w[i] / sum;
}

/* Vectorisable kernels: x runs innermost everywhere. Built for AVX2 and
 * FMA as well as the baseline, picked at load time (GCC target_clones). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SSIM_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SSIM_CLONES
#endif

/* Five weighted sums over a column of 11 rows, for every x of a row. */
SSIM_CLONES static void vertical_pass(const float *x, const float *y, int w, const double *k,
                                      double *restrict vx, double *restrict vy,
                                      double *restrict vxx, double *restrict vyy,
                                      double *restrict vxy)
{
    for (int i = 0; i < w; i++)
        vx[i] = vy[i] = vxx[i] = vyy[i] = vxy[i] = 0.0;
    for (int t = 0; t < SSIM_WINDOW; t++) {
        const float *xr = x + (size_t)t * (size_t)w, *yr = y + (size_t)t * (size_t)w;
        const double kt = k[t];
        for (int i = 0; i < w; i++) {
            double a = xr[i], b = yr[i];
            vx[i] += kt * a;
            vy[i] += kt * b;
            vxx[i] += kt * a * a;
            vyy[i] += kt * b * b;
            vxy[i] += kt * a * b;
        }
    }
}

/* The same along the row, then the SSIM formula; returns the row's sum. */
SSIM_CLONES static double horizontal_pass(int ow, const double *k, const double *vx,
                                          const double *vy, const double *vxx,
                                          const double *vyy, const double *vxy,
                                          double *restrict acc, double *restrict out)
{
    const double c1 = (K1 * L) * (K1 * L), c2 = (K2 * L) * (K2 * L);
    double *mx = acc, *my = acc + ow, *sxx = my + ow, *syy = sxx + ow, *sxy = syy + ow;
    for (int i = 0; i < ow; i++)
        mx[i] = my[i] = sxx[i] = syy[i] = sxy[i] = 0.0;
    for (int t = 0; t < SSIM_WINDOW; t++) {
        const double kt = k[t];
        for (int i = 0; i < ow; i++) {
            mx[i] += kt * vx[i + t];
            my[i] += kt * vy[i + t];
            sxx[i] += kt * vxx[i + t];
            syy[i] += kt * vyy[i + t];
            sxy[i] += kt * vxy[i + t];
        }
    }
    double sum = 0;
    for (int i = 0; i < ow; i++) {
        double var_x = sxx[i] - mx[i] * mx[i], var_y = syy[i] - my[i] * my[i];
        double cov = sxy[i] - mx[i] * my[i];
        double ux = mx[i] + 128.0, uy = my[i] + 128.0;
        double v = ((2 * ux * uy + c1) * (2 * cov + c2)) /
                   ((ux * ux + uy * uy + c1) * (var_x + var_y + c2));
        out[i] = v;
        sum += v;
    }
    return sum;
}

/* One plane's SSIM over the valid region. x and y hold samples minus 128:
 * variances come from E[x^2] - E[x]^2, and centred values shrink that
 * cancellation; variance and covariance do not move with the offset, the
 * means get it back. */
static double ssim_plane(const float *x, const float *y, int w, int h, const double *k,
                         float *map, double *min_out, int *min_x, int *min_y, double *scratch)
{
    const int ow = w - 2 * R, oh = h - 2 * R;
    double *vx = scratch, *vy = vx + w, *vxx = vy + w, *vyy = vxx + w, *vxy = vyy + w;
    double *acc = vxy + w, *row = acc + 5 * (size_t)ow;
    double sum = 0, min = INFINITY;
    int mx = 0, my = 0;
    for (int oy = 0; oy < oh; oy++) {
        vertical_pass(x + (size_t)oy * (size_t)w, y + (size_t)oy * (size_t)w, w, k, vx, vy, vxx,
                      vyy, vxy);
        sum += horizontal_pass(ow, k, vx, vy, vxx, vyy, vxy, acc, row);
        for (int ox = 0; ox < ow; ox++) {
            if (map)
                map[(size_t)oy * (size_t)ow + (size_t)ox] = (float)row[ox];
            if (row[ox] < min) {
                min = row[ox];
                mx = ox;
                my = oy;
            }
        }
    }
    if (min_out) {
        *min_out = min;
        *min_x = mx + R;
        *min_y = my + R;
    }
    return sum / ((double)ow * oh);
}

bool ssim_compute(const struct image *a, const struct image *b, bool keep_map,
                  struct ssim_result *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    if (a->width != b->width || a->height != b->height) {
        snprintf(err, errlen, "ssim: image sizes differ (%dx%d and %dx%d)", a->width,
                 a->height, b->width, b->height);
        return false;
    }
    int w = a->width, h = a->height;
    if (w < SSIM_WINDOW || h < SSIM_WINDOW) {
        snprintf(err, errlen, "ssim: images of %dx%d are smaller than the %dx%d window",
                 w, h, SSIM_WINDOW, SSIM_WINDOW);
        return false;
    }
    size_t n = (size_t)w * (size_t)h;
    float *x = malloc(n * sizeof(float)), *y = malloc(n * sizeof(float));
    double *scratch = malloc((5 * (size_t)w + 6 * (size_t)w) * sizeof(double));
    float *map = keep_map ? malloc((size_t)(w - 2 * R) * (size_t)(h - 2 * R) * sizeof(float)) : NULL;
    bool ok = x && y && scratch && (!keep_map || map);
    if (!ok) {
        snprintf(err, errlen, "ssim: out of memory");
        goto out;
    }
    double k[SSIM_WINDOW];
    gaussian_kernel(k);
    for (size_t i = 0; i < n; i++) {
        const uint8_t *p = a->rgb + i * 3, *q = b->rgb + i * 3;
        x[i] = (float)(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] - 128.0);
        y[i] = (float)(0.299 * q[0] + 0.587 * q[1] + 0.114 * q[2] - 128.0);
    }
    out->luma = ssim_plane(x, y, w, h, k, map, &out->min, &out->min_x, &out->min_y, scratch);
    for (int c = 0; c < 3; c++) {
        for (size_t i = 0; i < n; i++) {
            x[i] = (float)a->rgb[i * 3 + c] - 128.0f;
            y[i] = (float)b->rgb[i * 3 + c] - 128.0f;
        }
        out->channel[c] = ssim_plane(x, y, w, h, k, NULL, NULL, NULL, NULL, scratch);
    }
    out->rgb = (out->channel[0] + out->channel[1] + out->channel[2]) / 3.0;
    if (keep_map) {
        out->map = map;
        out->map_w = w - 2 * R;
        out->map_h = h - 2 * R;
        map = NULL;
    }
out:
    free(x);
    free(y);
    free(scratch);
    free(map);
    return ok;
}
