#include "daemon/techniques/forward_plus/forward_plus_info.h"

#include <stddef.h>

static const char *const passes[] = {"depth_prepass", "binning", "shading", NULL};

static const struct opt_field options[] = {
    {.name = "tile_size", .type = OPT_INT, .def = 16, .min = 8, .max = 128,
     .summary = "tile edge in pixels",
     .offset = offsetof(struct forward_plus_options, tile_size)},
    {0},
};

/* What job_cost charges: the heat map (the depth pre-pass writes the harness's depth). */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    (void)options, (void)look, (void)textured, (void)samples;
    return HEAT_MAP_BPP;
}

const struct technique_info forward_plus_info = {
    .name = "forward_plus",
    .summary = "depth pre-pass, per-tile light lists with depth bounds (compute), forward "
               "shading over each tile's lights",
    .passes = passes,
    .options = {.fields = options, .size = sizeof(struct forward_plus_options)},
    .flags = TECHNIQUE_BOUNDED_LIGHT_LISTS,
    .planes_bpp = planes_bpp,
};
