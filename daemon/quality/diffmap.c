/* Difference images for people: the SSIM map in grey and the FLIP map on a
 * dark-to-bright ramp (black, purple, red, orange, pale yellow), which keeps
 * small errors visible the way FLIP's magma map does. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "daemon/quality/metrics.h"

static const float RAMP[][3] = {
    {0.00f, 0.00f, 0.02f}, {0.23f, 0.06f, 0.44f}, {0.55f, 0.16f, 0.51f},
    {0.87f, 0.29f, 0.41f}, {0.99f, 0.62f, 0.41f}, {0.99f, 0.99f, 0.75f},
};

bool metrics_write_ssim_map(const char *path, const struct ssim_result *s, char *err,
                            size_t errlen)
{
    struct image img = {s->map_w, s->map_h, malloc((size_t)s->map_w * (size_t)s->map_h * 3)};
    if (!img.rgb) {
        snprintf(err, errlen, "out of memory");
        return false;
    }
    for (size_t i = 0; i < (size_t)s->map_w * (size_t)s->map_h; i++) {
        float v = s->map[i] < 0 ? 0 : (s->map[i] > 1 ? 1 : s->map[i]);
        img.rgb[i * 3] = img.rgb[i * 3 + 1] = img.rgb[i * 3 + 2] = (uint8_t)lrintf(v * 255.0f);
    }
    bool ok = png_write_rgb(path, &img, err, errlen);
    free(img.rgb);
    return ok;
}

bool metrics_write_flip_map(const char *path, const struct flip_result *f, int width,
                            int height, char *err, size_t errlen)
{
    struct image img = {width, height, malloc((size_t)width * (size_t)height * 3)};
    if (!img.rgb) {
        snprintf(err, errlen, "out of memory");
        return false;
    }
    const int stops = (int)(sizeof(RAMP) / sizeof(RAMP[0])) - 1;
    for (size_t i = 0; i < (size_t)width * (size_t)height; i++) {
        float v = f->map[i] < 0 ? 0 : (f->map[i] > 1 ? 1 : f->map[i]);
        float pos = v * (float)stops;
        int k = (int)pos < stops ? (int)pos : stops - 1;
        float t = pos - (float)k;
        for (int c = 0; c < 3; c++)
            img.rgb[i * 3 + (size_t)c] =
                (uint8_t)lrintf((RAMP[k][c] + (RAMP[k + 1][c] - RAMP[k][c]) * t) * 255.0f);
    }
    bool ok = png_write_rgb(path, &img, err, errlen);
    free(img.rgb);
    return ok;
}
