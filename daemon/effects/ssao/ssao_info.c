#include "daemon/effects/ssao/ssao_info.h"

#include <math.h>
#include <stddef.h>

static const char *const ssao_passes[] = {"ao", "blur", "apply", NULL};

static const struct opt_field ssao_options_table[] = {
    {.name = "samples", .type = OPT_INT, .def = 16, .min = 4, .max = 64,
     .summary = "hemisphere samples per pixel (a fixed kernel: frame k is a function of k)",
     .offset = offsetof(struct ssao_options, samples)},
    {.name = "radius", .type = OPT_NUMBER, .def = 1.0, .min = 0.01, .max = 100.0,
     .summary = "hemisphere radius in world units",
     .offset = offsetof(struct ssao_options, radius)},
    {.name = "bias", .type = OPT_NUMBER, .def = 0.025, .min = 0.0, .max = 10.0,
     .summary = "depth bias against self-occlusion, world units",
     .offset = offsetof(struct ssao_options, bias)},
    {.name = "blur", .type = OPT_BOOL, .def = 1,
     .summary = "blur the occlusion over the 4x4 noise tile before applying it (seed 002)",
     .offset = offsetof(struct ssao_options, blur)},
    {.name = "intensity", .type = OPT_NUMBER, .def = 1.0, .min = 0.0, .max = 8.0,
     .summary = "exponent on the occlusion term: 0 leaves the image, 1 as computed",
     .offset = offsetof(struct ssao_options, intensity)},
    {0},
};

static int ssao_active_passes(const void *opts, const char **out)
{
    const struct ssao_options *o = opts;
    out[0] = "ao";
    out[1] = o->blur ? "blur" : "apply";
    return 2;
}

const struct effect_info ssao_info = {
    .name = "ssao",
    .summary = "screen-space ambient occlusion: hemisphere samples against the depth "
               "texture, normals from the technique's g-buffer or rebuilt from depth",
    .passes = ssao_passes,
    .options = {.fields = ssao_options_table, .size = sizeof(struct ssao_options)},
    .active_passes = ssao_active_passes,
};

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
