#define _POSIX_C_SOURCE 200809L
#include "daemon/quality/flicker.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

static double luma(const uint8_t *p)
{
    return (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) / 255.0;
}

double flicker_pair(const uint8_t *test_prev, const uint8_t *test, const uint8_t *ref_prev,
                    const uint8_t *ref, size_t pixels, int channels)
{
    if (!pixels)
        return 0.0;
    double sum = 0.0;
    for (size_t i = 0; i < pixels; i++) {
        size_t o = i * (size_t)channels;
        double dt = luma(test + o) - luma(test_prev + o);
        double dr = luma(ref + o) - luma(ref_prev + o);
        sum += fabs(dt - dr);
    }
    return sum / (double)pixels;
}

void flicker_init(struct flicker_result *r)
{
    memset(r, 0, sizeof(*r));
}

void flicker_add(struct flicker_result *r, double e)
{
    if (r->pairs == 0 || e > r->max) {
        r->max = e;
        r->max_pair = r->pairs;
    }
    r->pairs++;
    r->sum += e;
    r->mean = r->sum / r->pairs;
}

/* The sRGB decode of every byte, and the midpoints between neighbours'
 * linear values, so that encoding is a search for the nearest byte. */
static double srgb_linear[256], srgb_mid[255];
static pthread_once_t srgb_once = PTHREAD_ONCE_INIT;

static void srgb_tables(void)
{
    for (int b = 0; b < 256; b++) {
        double c = b / 255.0;
        srgb_linear[b] = c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
    }
    for (int b = 0; b < 255; b++)
        srgb_mid[b] = 0.5 * (srgb_linear[b] + srgb_linear[b + 1]);
}

static uint8_t srgb_nearest(double v)
{
    int lo = 0, hi = 255; /* the answer: how many midpoints lie below v */
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (srgb_mid[mid] < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (uint8_t)lo;
}

void flicker_box_downsample(const uint8_t *src, int sw, int sh, int n, int channels,
                            uint8_t *dst)
{
    if (n <= 1) {
        memcpy(dst, src, (size_t)sw * (size_t)sh * (size_t)channels);
        return;
    }
    pthread_once(&srgb_once, srgb_tables);
    int dw = sw / n, dh = sh / n;
    double inv = 1.0 / ((double)n * n);
    for (int y = 0; y < dh; y++)
        for (int x = 0; x < dw; x++) {
            double acc[4] = {0, 0, 0, 0};
            for (int j = 0; j < n; j++) {
                const uint8_t *row = src + ((size_t)(y * n + j) * (size_t)sw + (size_t)x * n) *
                                               (size_t)channels;
                for (int i = 0; i < n; i++)
                    for (int c = 0; c < channels; c++)
                        acc[c] += c < 3 ? srgb_linear[row[i * channels + c]]
                                        : row[i * channels + c];
            }
            uint8_t *out = dst + ((size_t)y * (size_t)dw + (size_t)x) * (size_t)channels;
            for (int c = 0; c < channels; c++)
                out[c] = c < 3 ? srgb_nearest(acc[c] * inv)
                               : (uint8_t)lround(acc[c] * inv);
        }
}
