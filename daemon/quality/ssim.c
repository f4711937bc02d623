/* SSIM as defined by Wang, Bovik, Sheikh and Simoncelli, "Image Quality
 * Assessment: From Error Visibility to Structural Similarity", IEEE TIP 2004:
 * 11x11 circular-symmetric Gaussian window with sigma 1.5 normalised to unit
 * sum, K1 = 0.01, K2 = 0.03, L = 255, population (weighted) statistics, and
 * the mean over the valid region only (no padding). This matches
 * scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
 * use_sample_covariance=False, data_range=255). */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/metrics.h"

static const double K1 = 0.01, K2 = 0.03, L = 255.0, SIGMA = 1.5;
enum { R = SSIM_WINDOW / 2 };

static void gaussian_kernel(float k[SSIM_WINDOW])
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

/* Vectorisable kernels: x runs innermost everywhere. */
/* Five weighted sums over a column of 11 rows, for every x of a row. */
METRICS_SIMD static void vertical_pass(const float *x, const float *y, int w, const float *k,
                                      float *restrict vx, float *restrict vy,
                                      float *restrict vxx, float *restrict vyy,
                                      float *restrict vxy)
{
    for (int i = 0; i < w; i++)
        vx[i] = vy[i] = vxx[i] = vyy[i] = vxy[i] = 0.0;
    for (int t = 0; t < SSIM_WINDOW; t++) {
        const float *xr = x + (size_t)t * (size_t)w, *yr = y + (size_t)t * (size_t)w;
        const float kt = k[t];
        for (int i = 0; i < w; i++) {
            float a = xr[i], b = yr[i];
            vx[i] += kt * a;
            vy[i] += kt * b;
            vxx[i] += kt * a * a;
            vyy[i] += kt * b * b;
            vxy[i] += kt * a * b;
        }
    }
}

/* The same along the row, then the SSIM formula; returns the row's sum. */
METRICS_SIMD static double horizontal_pass(int ow, const float *k, const float *vx,
                                          const float *vy, const float *vxx,
                                          const float *vyy, const float *vxy,
                                          float *restrict acc, float *restrict out)
{
    const float c1 = (K1 * L) * (K1 * L), c2 = (K2 * L) * (K2 * L);
    float *mx = acc, *my = acc + ow, *sxx = my + ow, *syy = sxx + ow, *sxy = syy + ow;
    for (int i = 0; i < ow; i++)
        mx[i] = my[i] = sxx[i] = syy[i] = sxy[i] = 0.0;
    for (int t = 0; t < SSIM_WINDOW; t++) {
        const float kt = k[t];
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
        float var_x = sxx[i] - mx[i] * mx[i], var_y = syy[i] - my[i] * my[i];
        float cov = sxy[i] - mx[i] * my[i];
        float ux = mx[i] + 128.0f, uy = my[i] + 128.0f;
        float v = ((2 * ux * uy + c1) * (2 * cov + c2)) /
                   ((ux * ux + uy * uy + c1) * (var_x + var_y + c2));
        out[i] = v;
        sum += v;
    }
    return sum;
}

/* Output rows per strip: a strip converts STRIP + 10 input rows to float,
 * so memory per plane is about 2 (STRIP + 10) w floats whatever the height. */
enum { STRIP = 64 };

/* One plane per task: 0 is luma, 1 to 3 are R, G, B. Planes are
 * independent, so they spread over the cores. */
struct plane_task {
    const struct image *a, *b;
    int plane;
    uint8_t *map; /* luma only */
    const struct metrics_stop *stop;
    double ssim, min;
    int min_x, min_y;
    bool ok, stopped;
};

/* Input rows [y0, y1) of the task's plane, minus 128: variances come from
 * E[x^2] - E[x]^2, and centred values shrink that cancellation; variance
 * and covariance do not move with the offset, the means get it back. */
static void load_rows(const struct plane_task *t, int y0, int y1, float *x, float *y)
{
    int w = t->a->width;
    for (int row = y0; row < y1; row++) {
        const uint8_t *p = t->a->rgb + (size_t)row * (size_t)w * 3;
        const uint8_t *q = t->b->rgb + (size_t)row * (size_t)w * 3;
        float *xr = x + (size_t)(row - y0) * (size_t)w, *yr = y + (size_t)(row - y0) * (size_t)w;
        for (int i = 0; i < w; i++, p += 3, q += 3) {
            if (t->plane == 0) {
                xr[i] = 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] - 128.0f;
                yr[i] = 0.299f * q[0] + 0.587f * q[1] + 0.114f * q[2] - 128.0f;
            } else {
                xr[i] = (float)p[t->plane - 1] - 128.0f;
                yr[i] = (float)q[t->plane - 1] - 128.0f;
            }
        }
    }
}

static void *plane_worker(void *arg)
{
    struct plane_task *t = arg;
    int w = t->a->width, h = t->a->height;
    const int ow = w - 2 * R, oh = h - 2 * R;
    size_t strip_floats = (size_t)(STRIP + 2 * R) * (size_t)w;
    float *x = malloc(strip_floats * sizeof(float)), *y = malloc(strip_floats * sizeof(float));
    float *scratch = malloc((5 * (size_t)w + 6 * (size_t)ow) * sizeof(float));
    float k[SSIM_WINDOW];
    t->ok = x && y && scratch;
    double sum = 0, min = INFINITY;
    int mx = 0, my = 0;
    gaussian_kernel(k);
    float *vx = scratch, *vy = vx + w, *vxx = vy + w, *vyy = vxx + w, *vxy = vyy + w;
    float *acc = vxy + w, *row = acc + 5 * (size_t)ow;
    for (int s0 = 0; t->ok && s0 < oh; s0 += STRIP) {
        if (t->stop && t->stop->requested && t->stop->requested(t->stop->ctx)) {
            t->ok = false;
            t->stopped = true;
            break;
        }
        int s1 = s0 + STRIP < oh ? s0 + STRIP : oh;
        load_rows(t, s0, s1 + 2 * R, x, y);
        for (int oy = s0; oy < s1; oy++) {
            size_t off = (size_t)(oy - s0) * (size_t)w;
            vertical_pass(x + off, y + off, w, k, vx, vy, vxx, vyy, vxy);
            sum += horizontal_pass(ow, k, vx, vy, vxx, vyy, vxy, acc, row);
            for (int ox = 0; ox < ow; ox++) {
                if (t->map) {
                    float v = row[ox] < 0 ? 0 : (row[ox] > 1 ? 1 : row[ox]);
                    t->map[(size_t)oy * (size_t)ow + (size_t)ox] = (uint8_t)lrintf(v * 255.0f);
                }
                if (row[ox] < min) {
                    min = row[ox];
                    mx = ox;
                    my = oy;
                }
            }
        }
    }
    if (t->ok) {
        t->ssim = sum / ((double)ow * oh);
        t->min = min;
        t->min_x = mx + R;
        t->min_y = my + R;
    }
    free(x);
    free(y);
    free(scratch);
    return NULL;
}

bool ssim_compute(const struct image *a, const struct image *b, bool keep_map,
                  const struct metrics_stop *stop, struct ssim_result *out, char *err,
                  size_t errlen)
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
    uint8_t *map = keep_map ? malloc((size_t)(w - 2 * R) * (size_t)(h - 2 * R)) : NULL;
    if (keep_map && !map) {
        snprintf(err, errlen, "ssim: out of memory");
        return false;
    }
    struct plane_task tasks[4];
    pthread_t threads[4];
    bool started[4] = {false};
    for (int p = 0; p < 4; p++) {
        tasks[p] = (struct plane_task){.a = a, .b = b, .plane = p, .map = p == 0 ? map : NULL,
                                       .stop = stop};
        /* Planes 1-3 on threads of their own; luma on the calling thread. */
        if (p > 0)
            started[p] = pthread_create(&threads[p], NULL, plane_worker, &tasks[p]) == 0;
    }
    plane_worker(&tasks[0]);
    bool ok = tasks[0].ok, stopped = tasks[0].stopped;
    for (int p = 1; p < 4; p++) {
        if (started[p])
            pthread_join(threads[p], NULL);
        else
            plane_worker(&tasks[p]);
        ok = ok && tasks[p].ok;
        stopped = stopped || tasks[p].stopped;
    }
    if (!ok) {
        free(map);
        snprintf(err, errlen, stopped ? "stopped" : "ssim: out of memory");
        return false;
    }
    out->luma = tasks[0].ssim;
    out->min = tasks[0].min;
    out->min_x = tasks[0].min_x;
    out->min_y = tasks[0].min_y;
    for (int c = 0; c < 3; c++)
        out->channel[c] = tasks[c + 1].ssim;
    out->rgb = (out->channel[0] + out->channel[1] + out->channel[2]) / 3.0;
    if (keep_map) {
        out->map = map;
        out->map_w = w - 2 * R;
        out->map_h = h - 2 * R;
    }
    return true;
}

size_t ssim_memory_bytes(int width, int height)
{
    size_t w = (size_t)width;
    size_t per_plane = (2 * (size_t)(STRIP + 2 * R) * w + 5 * w + 6 * w) * sizeof(float);
    size_t map = height > 2 * R && width > 2 * R ? (w - 2 * R) * (size_t)(height - 2 * R) : 0;
    return 4 * per_plane + map;
}
