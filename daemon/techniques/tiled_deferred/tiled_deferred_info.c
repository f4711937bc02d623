#include "daemon/techniques/tiled_deferred/tiled_deferred_info.h"

#include <stddef.h>

static const char *const passes[] = {"gbuffer", "edges", "binning", "lighting", NULL};

static const struct opt_field options[] = {
    {.name = "tile_size", .type = OPT_INT, .def = 16, .min = 8, .max = 128,
     .summary = "tile edge in pixels (seed 003 swept 20 to 100)",
     .offset = offsetof(struct tiled_deferred_options, tile_size)},
    {.name = "binning", .type = OPT_CHOICE, .def = LIGHT_BINNING_GPU,
     .choices = light_binning_choices,
     .summary = "gpu: per-tile depth bounds and light lists in compute passes; cpu: seed 003's "
                "light grid built on the CPU from screen rectangles and uploaded every frame, "
                "inside the timed region",
     .offset = offsetof(struct tiled_deferred_options, binning)},
    GBUFFER_OPTION_ROWS(struct tiled_deferred_options, gbuffer),
    {0},
};

/* What job_cost charges: its g-buffer and the heat map. */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    const struct tiled_deferred_options *o = options;
    return gbuffer_planes_bpp(&o->gbuffer, look, textured, samples) + HEAT_MAP_BPP;
}

const struct technique_info tiled_deferred_info = {
    .name = "tiled_deferred",
    .summary = "g-buffer, per-tile depth bounds and light lists, one lighting pass looping "
               "over each tile's lights (seed 003)",
    .passes = passes,
    .options = {.fields = options, .size = sizeof(struct tiled_deferred_options)},
    .flags = TECHNIQUE_BOUNDED_LIGHT_LISTS,
    .planes_bpp = planes_bpp,
};
