#include "daemon/effects/toon/toon_info.h"

#include <stddef.h>

static const char *const toon_edge_choices[] = {"sobel", "depth_diff", "none", NULL};
static const char *const toon_passes[] = {"shade", NULL};

static const struct opt_field toon_options_table[] = {
    {.name = "levels", .type = OPT_INT, .def = 4, .min = 2, .max = 32,
     .summary = "steps of the luminance ramp",
     .offset = offsetof(struct toon_options, levels)},
    {.name = "edges", .type = OPT_CHOICE, .def = TOON_EDGES_SOBEL, .choices = toon_edge_choices,
     .summary = "sobel: Sobel operator on view depth and normals (seed 001); depth_diff: the "
                "largest depth difference to 4 neighbours (seed 003); none: ramp only",
     .offset = offsetof(struct toon_options, edges)},
    {.name = "threshold", .type = OPT_NUMBER, .def = 0.1, .min = 0.001, .max = 100.0,
     .summary = "relative view-depth difference (|dz| / z) that makes an outline",
     .offset = offsetof(struct toon_options, threshold)},
    {.name = "normal_threshold", .type = OPT_NUMBER, .def = 1.0, .min = 0.01, .max = 16.0,
     .summary = "sobel: gradient of the view normals that makes an outline",
     .offset = offsetof(struct toon_options, normal_threshold)},
    {.name = "thickness", .type = OPT_INT, .def = 1, .min = 1, .max = 8,
     .summary = "pixels between the centre and the samples the edge test compares",
     .offset = offsetof(struct toon_options, thickness)},
    {0},
};

static int toon_active_passes(const void *opts, const char **out)
{
    (void)opts;
    out[0] = "shade";
    return 1;
}

const struct effect_info toon_info = {
    .name = "toon",
    .summary = "colour ramp of a few levels plus outlines from depth (and normals) edges",
    .passes = toon_passes,
    .options = {.fields = toon_options_table, .size = sizeof(struct toon_options)},
    .active_passes = toon_active_passes,
};
