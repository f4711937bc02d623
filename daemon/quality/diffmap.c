/* Difference images for people: the SSIM map in grey and the FLIP map on a
 * dark-to-bright ramp (black, purple, red, orange, pale yellow), which keeps
 * small errors visible the way FLIP's magma map does. Written a row at a
 * time, so no RGB copy of the map is ever made. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/metrics.h"

static const float RAMP[][3] = {
    {0.00f, 0.00f, 0.02f}, {0.23f, 0.06f, 0.44f}, {0.55f, 0.16f, 0.51f},
    {0.87f, 0.29f, 0.41f}, {0.99f, 0.62f, 0.41f}, {0.99f, 0.99f, 0.75f},
};

static void ssim_row(void *ctx, int y, uint8_t *rgb)
{
    const struct ssim_result *s = ctx;
    const uint8_t *grey = s->map + (size_t)y * (size_t)s->map_w;
    for (int x = 0; x < s->map_w; x++)
        rgb[x * 3] = rgb[x * 3 + 1] = rgb[x * 3 + 2] = grey[x];
}

bool metrics_write_ssim_map(const char *path, const struct ssim_result *s, char *err,
                            size_t errlen)
{
    return png_write_by_rows(path, s->map_w, s->map_h, ssim_row, (void *)s, err, errlen);
}

struct flip_rows {
    const float *map;
    int width;
};

static void flip_row(void *ctx, int y, uint8_t *rgb)
{
    const struct flip_rows *f = ctx;
    const int stops = (int)(sizeof(RAMP) / sizeof(RAMP[0])) - 1;
    const float *row = f->map + (size_t)y * (size_t)f->width;
    for (int x = 0; x < f->width; x++) {
        float v = row[x] < 0 ? 0 : (row[x] > 1 ? 1 : row[x]);
        float pos = v * (float)stops;
        int k = (int)pos < stops ? (int)pos : stops - 1;
        float t = pos - (float)k;
        for (int c = 0; c < 3; c++)
            rgb[x * 3 + c] = (uint8_t)lrintf((RAMP[k][c] + (RAMP[k + 1][c] - RAMP[k][c]) * t) * 255.0f);
    }
}

bool metrics_write_flip_map(const char *path, const struct flip_result *f, int width,
                            int height, char *err, size_t errlen)
{
    struct flip_rows rows = {f->map, width};
    return png_write_by_rows(path, width, height, flip_row, &rows, err, errlen);
}

int metrics_flip_ramp(const float (**stops)[3])
{
    *stops = RAMP;
    return (int)(sizeof(RAMP) / sizeof(RAMP[0]));
}

void metrics_flip_ramp_colour(float v, uint8_t rgb[3])
{
    struct flip_rows one = {&v, 1};
    flip_row(&one, 0, rgb);
}

/* The ramp's inverse: the point of the ramp nearest the colour, each
 * segment tried (the ramp is a polyline through RGB). */
float metrics_flip_ramp_value(const uint8_t rgb[3])
{
    const int stops = (int)(sizeof(RAMP) / sizeof(RAMP[0])) - 1;
    float c[3] = {rgb[0] / 255.0f, rgb[1] / 255.0f, rgb[2] / 255.0f}, best = 0, best_d = INFINITY;
    for (int k = 0; k < stops; k++) {
        float d[3], w[3], dd = 0, dw = 0;
        for (int i = 0; i < 3; i++) {
            d[i] = RAMP[k + 1][i] - RAMP[k][i];
            w[i] = c[i] - RAMP[k][i];
            dd += d[i] * d[i];
            dw += d[i] * w[i];
        }
        float t = dd > 0 ? fminf(1.0f, fmaxf(0.0f, dw / dd)) : 0.0f, err = 0;
        for (int i = 0; i < 3; i++)
            err += (w[i] - t * d[i]) * (w[i] - t * d[i]);
        if (err < best_d)
            best_d = err, best = ((float)k + t) / (float)stops;
    }
    return best;
}

void metrics_stretch_flip_map(struct image *map, float gain)
{
    size_t n = (size_t)map->width * (size_t)map->height;
    for (size_t i = 0; i < n; i++) {
        float v = metrics_flip_ramp_value(map->rgb + 3 * i) * gain;
        metrics_flip_ramp_colour(v > 1 ? 1 : v, map->rgb + 3 * i);
    }
}

void metrics_stretch_ssim_map(struct image *map, float gain)
{
    size_t n = (size_t)map->width * (size_t)map->height * 3;
    for (size_t i = 0; i < n; i++) {
        float shortfall = (255.0f - map->rgb[i]) * gain;
        map->rgb[i] = (uint8_t)(shortfall >= 255.0f ? 0 : lrintf(255.0f - shortfall));
    }
}

bool metrics_abs_difference(const struct image *a, const struct image *b, float gain,
                            struct image *out, long *differing)
{
    if (a->width != b->width || a->height != b->height)
        return false;
    size_t n = (size_t)a->width * (size_t)a->height;
    out->width = a->width;
    out->height = a->height;
    out->rgb = malloc(n * 3 + 1);
    if (!out->rgb)
        return false;
    *differing = 0;
    for (size_t i = 0; i < n; i++) {
        bool differs = false;
        for (int c = 0; c < 3; c++) {
            int d = abs((int)a->rgb[3 * i + c] - (int)b->rgb[3 * i + c]);
            float v = (float)d * gain;
            out->rgb[3 * i + c] = (uint8_t)(v >= 255.0f ? 255 : lrintf(v));
            differs = differs || d;
        }
        *differing += differs;
    }
    return true;
}
