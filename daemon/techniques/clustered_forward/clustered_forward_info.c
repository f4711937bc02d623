#include "daemon/techniques/clustered_forward/clustered_forward_info.h"

#include <stddef.h>

static const char *const passes[] = {"binning", "depth_prepass", "shading", NULL};

static const struct opt_field options[] = {
    CLUSTER_OPTION_ROWS(struct clustered_forward_options, cluster),
    {0},
};

static bool check(void *opts, const char *prefix, struct job_error *err)
{
    const struct clustered_forward_options *o = opts;
    return cluster_grid_check(o->cluster.grid, prefix, err);
}

/* What job_cost charges: the heat map (the depth pre-pass writes the harness's depth). */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    (void)options, (void)look, (void)textured, (void)samples;
    return HEAT_MAP_BPP;
}

const struct technique_info clustered_forward_info = {
    .name = "clustered_forward",
    .summary = "froxel light lists (compute), depth pre-pass, forward shading over each "
               "cluster's lights (seed 004)",
    .passes = passes,
    .options = {.fields = options,
                .size = sizeof(struct clustered_forward_options),
                .check = check},
    .flags = TECHNIQUE_BOUNDED_LIGHT_LISTS,
    .planes_bpp = planes_bpp,
};
