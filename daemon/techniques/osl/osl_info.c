#include "daemon/techniques/osl/osl_info.h"

#include <stddef.h>

static const char *const passes[] = {"lighting", "raster", NULL};
static const char *const reshade_choices[] = {"touched", "all", NULL};

static const struct technique_option options[] = {
    {.name = "resolution", .type = TOPT_POW2_OR_AUTO, .def = 256, .min = 8, .max = 1024,
     .summary = "tile edge in texels for every object (256 is the thesis); \"auto\" sizes "
                "each object's tile from its size on screen",
     .offset = offsetof(struct osl_options, resolution)},
    {.name = "texel_density", .type = TOPT_NUMBER, .def = 1.0, .min = 0.0625, .max = 16.0,
     .summary = "with resolution \"auto\": texels per covered pixel",
     .offset = offsetof(struct osl_options, texel_density)},
    {.name = "reshade", .type = TOPT_CHOICE, .def = OSL_RESHADE_TOUCHED,
     .choices = reshade_choices,
     .summary = "touched reshades only objects a moving light reaches; all reshades every "
                "due object, as the thesis measured",
     .offset = offsetof(struct osl_options, reshade)},
    {0},
};

const struct technique_info osl_info = {
    .name = "osl",
    .summary = "object space lighting: texgen, compute lighting into a shared atlas, "
               "rasterization sampling it; async shading by camera distance",
    .passes = passes,
    .options = options,
    .options_size = sizeof(struct osl_options),
};
