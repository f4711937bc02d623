#include "daemon/techniques/osl/osl_info.h"

#include <stddef.h>
#include <stdio.h>

#include "common/json_fields.h"

#include "daemon/techniques/osl/osl_atlas.h"

static const char *const passes[] = {"lighting", "raster", NULL};
static const char *const reshade_choices[] = {"touched", "all", NULL};
static const char *const visibility_choices[] = {"all", "seen", NULL};

static const struct opt_field options[] = {
    {.name = "resolution", .type = OPT_POW2_OR_AUTO, .def = 0, .min = OSL_TILE_MIN,
     .max = OSL_TILE_MAX,
     .summary = "tile edge in texels for every object (256 is the thesis's); \"auto\" "
                "(the default) sizes each object's tile from its size on screen",
     .offset = offsetof(struct osl_options, resolution)},
    {.name = "texel_density", .type = OPT_NUMBER, .def = 0.0, .min = 0.0, .max = 16.0,
     .summary = "with resolution \"auto\": texels per covered pixel (along each axis) at the "
                "level each pixel reads, 0.0625 to 16 (a pixel reads 1 to 2 times this); 0 (the "
                "default): 1, or 2 under PBR lighting, whose GGX highlights bilinear filtering "
                "of one texel a pixel flattens, or 0.5 in asset scenes under Phong and "
                "Blinn-Phong, where the base colour and the normal are applied per pixel",
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
    {.name = "visibility", .type = OPT_CHOICE, .def = OSL_VISIBILITY_SEEN,
     .choices = visibility_choices,
     .summary = "all shades whole tiles, as the thesis did; seen (the default) shades only "
                "the 8x8 atlas blocks the raster pass sampled in the frame before, or next "
                "to one (the "
                "margin for motion), each when its shading is not the one its object's "
                "schedule asks for: reshading follows what the camera sees. A block the "
                "raster pass reads while it holds other shading is counted (stale_blocks)",
     .offset = offsetof(struct osl_options, visibility)},
    {.name = "budget_texels", .type = OPT_INT, .def = 0, .min = 0, .max = 1 << 30,
     .summary = "with visibility seen: at most this many texels shaded a frame, in whole "
                "8x8 blocks chosen by priority (frames behind schedule, read or only in "
                "the margin), the rest left for later frames; blocks never shaded are "
                "shaded whatever the budget (a frame where they alone overrun it is "
                "counted); 0: no limit",
     .offset = offsetof(struct osl_options, budget_texels)},
    {.name = "change_threshold", .type = OPT_NUMBER, .def = 0.0, .min = 0.0, .max = 1.0,
     .summary = "with visibility seen: an object due for reshading keeps the shading it "
                "has while a bound on how much its lights' motion since then can change "
                "its radiance (per channel, 1 is white) stays at or below this; 0 "
                "reshades whenever the schedule says",
     .offset = offsetof(struct osl_options, change_threshold)},
    {0},
};

/* The dispatcher and change detection work on the blocks "seen" lists. */
static bool check(void *opts, const char *prefix, struct job_error *err)
{
    const struct osl_options *o = opts;
    char field[96];
    if (o->texel_density != 0 && o->texel_density < 0.0625) {
        snprintf(field, sizeof(field), "%s.texel_density", prefix);
        return job_error_set(err, field, "must be 0 (auto) or 0.0625 to 16");
    }
    if (o->visibility == OSL_VISIBILITY_SEEN)
        return true;
    if (o->budget_texels > 0) {
        snprintf(field, sizeof(field), "%s.budget_texels", prefix);
        return job_error_set(err, field, "needs visibility \"seen\" (whole tiles have no "
                             "block list to cut)");
    }
    if (o->change_threshold > 0) {
        snprintf(field, sizeof(field), "%s.change_threshold", prefix);
        return job_error_set(err, field, "needs visibility \"seen\"");
    }
    return true;
}

const struct technique_info osl_info = {
    .name = "osl",
    .summary = "object space lighting: texgen, compute lighting into a shared atlas, "
               "rasterization sampling it; async shading by camera distance",
    .passes = passes,
    .options = {.fields = options, .size = sizeof(struct osl_options), .check = check},
};
