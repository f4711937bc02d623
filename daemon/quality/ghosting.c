#include "daemon/quality/ghosting.h"

#include <math.h>
#include <string.h>

static int inside(const float d[3], float x, float y, float grow)
{
    float dx = x - d[0], dy = y - d[1], r = d[2] + grow;
    return dx * dx + dy * dy <= r * r;
}

void ghosting_band(uint8_t *mask, int w, int h, const float (*past)[3], int count,
                   const float now[3])
{
    memset(mask, GHOSTING_REST, (size_t)w * (size_t)h);
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            float x = (float)i + 0.5f, y = (float)j + 0.5f;
            uint8_t *m = &mask[(size_t)j * (size_t)w + (size_t)i];
            if (now && inside(now, x, y, 1.0f)) {
                *m = GHOSTING_OBJECT;
                continue;
            }
            for (int k = 0; k < count; k++)
                if (inside(past[k], x, y, 0.0f)) {
                    *m = GHOSTING_BAND;
                    break;
                }
        }
}

void ghosting_init(struct ghosting_result *r)
{
    memset(r, 0, sizeof(*r));
}

static double luma(const uint8_t *p)
{
    return (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) / 255.0;
}

void ghosting_add(struct ghosting_result *r, const uint8_t *test, const uint8_t *ref,
                  const uint8_t *mask, size_t pixels, int channels)
{
    double band = 0, rest = 0;
    size_t nb = 0, nr = 0;
    for (size_t p = 0; p < pixels; p++) {
        double e = fabs(luma(test + p * (size_t)channels) - luma(ref + p * (size_t)channels));
        if (mask[p] == GHOSTING_BAND)
            band += e, nb++;
        else if (mask[p] == GHOSTING_REST)
            rest += e, nr++;
    }
    if (!nb)
        return;
    r->frames++;
    r->band_pixels += (double)nb;
    r->band_error += band / (double)nb;
    r->rest_error += nr ? rest / (double)nr : 0.0;
}
