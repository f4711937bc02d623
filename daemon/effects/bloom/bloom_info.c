#define _POSIX_C_SOURCE 200809L
#include "daemon/effects/bloom/bloom_info.h"

#include <math.h>
#include <stddef.h>

static const char *const bloom_kernels[] = {"separable", "2d", NULL};
static const char *const bloom_passes[] = {"bright", "down", "blur_h", "blur_v", "blur",
                                           "up",     "composite", NULL};

static const struct opt_field bloom_options_table[] = {
    {.name = "threshold", .type = OPT_NUMBER, .def = 1.0, .min = 0.0, .max = 1e6,
     .summary = "luminance above which light blooms (1 = what the resolve clips)",
     .offset = offsetof(struct bloom_options, threshold)},
    {.name = "kernel", .type = OPT_CHOICE, .def = BLOOM_SEPARABLE, .choices = bloom_kernels,
     .summary = "separable: a horizontal then a vertical pass of 2r+1 taps; 2d: one pass of "
                "(2r+1)^2 taps (seed 001's slow version)",
     .offset = offsetof(struct bloom_options, kernel)},
    {.name = "radius", .type = OPT_INT, .def = 4, .min = 2, .max = 32,
     .summary = "Gaussian taps each side of the centre (sigma = radius / 2)",
     .offset = offsetof(struct bloom_options, radius)},
    {.name = "intensity", .type = OPT_NUMBER, .def = 1.0, .min = 0.0, .max = 1e30,
     .summary = "scale of the blurred light added back; huge values overflow a 16-bit "
                "target (look.hdr rgba16f), and chained, even a 32-bit one, on purpose: "
                "the result counts the non-finite pixels",
     .offset = offsetof(struct bloom_options, intensity)},
    {.name = "downsample", .type = OPT_INT, .def = 0, .min = 0, .max = 5,
     .summary = "0 blurs at full size; n blurs a mip chain of n halvings and adds the levels "
                "back up (wider glow for the same taps)",
     .offset = offsetof(struct bloom_options, downsample)},
    {0},
};

static int bloom_active_passes(const void *opts, const char **out)
{
    const struct bloom_options *o = opts;
    int n = 0;
    out[n++] = "bright";
    if (o->downsample > 1)
        out[n++] = "down";
    if (o->kernel == BLOOM_2D) {
        out[n++] = "blur";
    } else {
        out[n++] = "blur_h";
        out[n++] = "blur_v";
    }
    if (o->downsample > 1)
        out[n++] = "up";
    out[n++] = "composite";
    return n;
}

const struct effect_info bloom_info = {
    .name = "bloom",
    .summary = "bright pass with a threshold, Gaussian blur (separable or 2d, optionally over "
               "a mip chain), added back to the colour",
    .passes = bloom_passes,
    .options = {.fields = bloom_options_table, .size = sizeof(struct bloom_options)},
    .active_passes = bloom_active_passes,
};

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
