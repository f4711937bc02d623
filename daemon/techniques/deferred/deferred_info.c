#include "daemon/techniques/deferred/deferred_info.h"

#include <stddef.h>

static const char *const passes[] = {"gbuffer", "edges", "lighting", NULL};

static const struct opt_field options[] = {
    {.name = "light_bounds", .type = OPT_CHOICE, .def = LIGHT_BOUNDS_SCISSOR_TIGHT,
     .choices = light_bounds_choices,
     .summary = "pixels each light shades: scissor_tight (its sphere's silhouette rectangle, "
                "seed 001's fix), scissor_loose (the projected box of its AABB corners, seed "
                "001's first version), volume (its sphere rasterised) or fullscreen",
     .offset = offsetof(struct deferred_options, light_bounds)},
    GBUFFER_OPTION_ROWS(struct deferred_options, gbuffer),
    {0},
};

/* What job_cost charges: its g-buffer and the heat map. */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    const struct deferred_options *o = options;
    return gbuffer_planes_bpp(&o->gbuffer, look, textured, samples) + HEAT_MAP_BPP;
}

const struct technique_info deferred_info = {
    .name = "deferred",
    .summary = "g-buffer, then each light added over the pixels its bound covers (seed 001)",
    .passes = passes,
    .options = {.fields = options, .size = sizeof(struct deferred_options)},
    .planes_bpp = planes_bpp,
};
