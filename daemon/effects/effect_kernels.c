#include "daemon/effects/effect_kernels.h"

#include <math.h>

bool gauss_weights(int radius, float *w)
{
    if (radius < 1 || radius > BLOOM_MAX_RADIUS)
        return false;
    double sigma = radius / 2.0, raw[BLOOM_MAX_RADIUS + 1], sum = 0;
    for (int i = 0; i <= radius; i++) {
        raw[i] = exp(-(double)(i * i) / (2.0 * sigma * sigma));
        sum += i ? 2.0 * raw[i] : raw[i];
    }
    for (int i = 0; i <= radius; i++)
        w[i] = (float)(raw[i] / sum);
    return true;
}

/* xorshift32: tiny, portable and the same everywhere. */
static uint32_t next(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *s = x;
}

static double unit(uint32_t *s) { return (next(s) >> 8) * (1.0 / 16777216.0); }

bool ssao_kernel(int samples, uint32_t seed, float (*out)[4])
{
    if (samples < 1 || samples > SSAO_MAX_SAMPLES)
        return false;
    uint32_t s = seed ? seed : 1;
    for (int i = 0; i < samples; i++) {
        double v[3], len;
        /* Rejection keeps the directions uniform over the hemisphere; the
         * lower bound on z keeps samples off the tangent plane, where depth
         * precision makes them flicker between occluded and not. */
        do {
            v[0] = unit(&s) * 2.0 - 1.0;
            v[1] = unit(&s) * 2.0 - 1.0;
            v[2] = unit(&s);
            len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        } while (len > 1.0 || len < 1e-3 || v[2] / len < 0.15);
        double t = (double)i / samples, scale = 0.1 + 0.9 * t * t;
        double r = unit(&s) * 0.5 + 0.5; /* inside the sphere, not on it */
        for (int c = 0; c < 3; c++)
            out[i][c] = (float)(v[c] / len * r * scale);
        out[i][3] = 0.0f;
    }
    return true;
}

void ssao_noise(uint32_t seed, float angles[SSAO_NOISE_SIZE * SSAO_NOISE_SIZE])
{
    /* A shuffled even spread of 16 angles: every rotation appears once per
     * tile, so the 4x4 blur averages the full set. */
    const double two_pi = 6.283185307179586;
    int order[SSAO_NOISE_SIZE * SSAO_NOISE_SIZE];
    uint32_t s = seed ^ 0x9e3779b9u;
    for (int i = 0; i < SSAO_NOISE_SIZE * SSAO_NOISE_SIZE; i++)
        order[i] = i;
    for (int i = SSAO_NOISE_SIZE * SSAO_NOISE_SIZE - 1; i > 0; i--) {
        int j = (int)(next(&s) % (uint32_t)(i + 1)), t = order[i];
        order[i] = order[j];
        order[j] = t;
    }
    for (int i = 0; i < SSAO_NOISE_SIZE * SSAO_NOISE_SIZE; i++)
        angles[i] = (float)(two_pi * (order[i] + 0.5) / (SSAO_NOISE_SIZE * SSAO_NOISE_SIZE));
}

double tonemap_reinhard(double x) { return x > 0 ? x / (1.0 + x) : 0.0; }

double tonemap_aces(double x)
{
    if (x <= 0)
        return 0.0;
    x *= 0.6; /* Narkowicz's fit takes the exposure the RRT assumes */
    double y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return y < 0 ? 0 : y > 1 ? 1 : y;
}

double srgb_encode(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
