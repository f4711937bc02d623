/* Difference images for people: the SSIM map in grey and the FLIP map on a
 * dark-to-bright ramp (black, purple, red, orange, pale yellow), which keeps
 * small errors visible the way FLIP's magma map does. Written a row at a
 * time, so no RGB copy of the map is ever made. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
