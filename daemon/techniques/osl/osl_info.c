#include "daemon/techniques/osl/osl_info.h"

#include <stddef.h>

#include "daemon/techniques/osl/osl_atlas.h"

static const char *const passes[] = {"lighting", "raster", NULL};
static const char *const reshade_choices[] = {"touched", "all", NULL};
static const char *const visibility_choices[] = {"all", "seen", NULL};

static const struct opt_field options[] = {
    {.name = "resolution", .type = OPT_POW2_OR_AUTO, .def = 256, .min = OSL_TILE_MIN,
     .max = OSL_TILE_MAX,
     .summary = "tile edge in texels for every object (256 is the thesis); \"auto\" sizes "
                "each object's tile from its size on screen",
     .offset = offsetof(struct osl_options, resolution)},
    {.name = "texel_density", .type = OPT_NUMBER, .def = 1.0, .min = 0.0625, .max = 16.0,
     .summary = "with resolution \"auto\": texels per covered pixel",
     .offset = offsetof(struct osl_options, texel_density)},
    {.name = "reshade", .type = OPT_CHOICE, .def = OSL_RESHADE_TOUCHED,
     .choices = reshade_choices,
     .summary = "touched reshades only the objects a moving light reaches, as the thesis "
                "did (3.1.2.3: objects go to the lighting shader only if a dynamic light "
                "affects them); all reshades every due object, lit by a moving light or not",
     .offset = offsetof(struct osl_options, reshade)},
    {.name = "async_distance", .type = OPT_NUMBER, .def = 0.0, .min = 0.0, .max = 1e6,
     .summary = "async shading (thesis 3.1.2.3): an object at camera distance r is reshaded "
                "every floor(r / async_distance) + 1 frames; 0 reshades every frame. The "
                "job's top-level async_distance is an alias",
     .offset = offsetof(struct osl_options, async_distance)},
    {.name = "visibility", .type = OPT_CHOICE, .def = OSL_VISIBILITY_ALL,
     .choices = visibility_choices,
     .summary = "all shades whole tiles, as the thesis did; seen shades only the 8x8 atlas "
                "blocks the raster pass sampled in the frame before, or next to one (the "
                "margin for motion), each when its shading is not the one its object's "
                "schedule asks for: reshading follows what the camera sees. A block the "
                "raster pass reads while it holds other shading is counted (stale_blocks)",
     .offset = offsetof(struct osl_options, visibility)},
    {0},
};

const struct technique_info osl_info = {
    .name = "osl",
    .summary = "object space lighting: texgen, compute lighting into a shared atlas, "
               "rasterization sampling it; async shading by camera distance",
    .passes = passes,
    .options = {.fields = options, .size = sizeof(struct osl_options)},
};
