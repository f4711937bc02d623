#include "daemon/effects/taa/taa_info.h"

#include <stddef.h>

static const char *const taa_passes[] = {"resolve", NULL};
static const char *const clamps[] = {"none", "aabb", "clip", "variance", NULL};
static const char *const filters[] = {"bilinear", "catmull_rom", NULL};

static const struct opt_field taa_options_table[] = {
    {.name = "blend", .type = OPT_NUMBER, .def = 0.1, .min = 0.01, .max = 1.0,
     .summary = "the current frame's weight in the history's running mean (1: no history)",
     .offset = offsetof(struct taa_options, blend)},
    {.name = "clamp", .type = OPT_CHOICE, .def = TAA_CLAMP_VARIANCE, .choices = clamps,
     .summary = "how the reprojected history is kept to this frame's 3x3 neighbourhood in "
                "YCoCg: none, aabb (clamp into its box), clip (towards its centre), variance "
                "(clip into mean +- gamma sigma)",
     .offset = offsetof(struct taa_options, clamp)},
    {.name = "gamma", .type = OPT_NUMBER, .def = 1.0, .min = 0.25, .max = 4.0,
     .summary = "variance clipping's box, in standard deviations",
     .offset = offsetof(struct taa_options, gamma)},
    {.name = "jitter_length", .type = OPT_INT, .def = 8, .min = 0, .max = FRAME_MAX_JITTER,
     .summary = "frames before the projection's Halton (2, 3) sub-pixel jitter repeats; 0: "
                "no jitter",
     .offset = offsetof(struct taa_options, jitter_length)},
    {.name = "history", .type = OPT_INT, .def = 16, .min = 1, .max = FRAME_MAX_HISTORY,
     .summary = "frames of history before each captured frame (it starts afresh that many "
                "frames before, so that frame k is a pure function of k; captures must be "
                "further apart)",
     .offset = offsetof(struct taa_options, history)},
    {.name = "filter", .type = OPT_CHOICE, .def = TAA_FILTER_CATMULL_ROM, .choices = filters,
     .summary = "how the history is read at its reprojected position: bilinear, or a 9-tap "
                "Catmull-Rom (sharper: less blur as the history is resampled every frame)",
     .offset = offsetof(struct taa_options, filter)},
    {0},
};

static int taa_active_passes(const void *opts, const char **out)
{
    (void)opts;
    out[0] = "resolve";
    return 1;
}

static void taa_needs(const void *opts, struct frame_needs *out)
{
    const struct taa_options *o = opts;
    out->history_frames = o->history;
    out->jitter_length = o->jitter_length;
    out->motion_vectors = true;
}

const struct effect_info taa_info = {
    .name = "taa",
    .summary = "temporal anti-aliasing: the projection jittered along a Halton (2, 3) "
               "sequence, the history reprojected by the harness's motion vectors, kept to "
               "the neighbourhood (clamp, clip or variance clipping) and blended",
    .passes = taa_passes,
    .options = {.fields = taa_options_table, .size = sizeof(struct taa_options)},
    .active_passes = taa_active_passes,
    .needs = taa_needs,
    .flags = EFFECT_ANTIALIASING,
};
