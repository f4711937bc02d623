#include "daemon/techniques/clustered_deferred/clustered_deferred_info.h"

#include <stddef.h>

static const char *const passes[] = {"binning", "gbuffer", "edges", "lighting", NULL};

static const struct opt_field options[] = {
    CLUSTER_OPTION_ROWS(struct clustered_deferred_options, cluster),
    GBUFFER_OPTION_ROWS(struct clustered_deferred_options, gbuffer),
    {0},
};

static bool check(void *opts, const char *prefix, struct job_error *err)
{
    const struct clustered_deferred_options *o = opts;
    return cluster_grid_check(o->cluster.grid, prefix, err);
}

/* What job_cost charges: its g-buffer and the heat map. */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    const struct clustered_deferred_options *o = options;
    return gbuffer_planes_bpp(&o->gbuffer, look, textured, samples) + HEAT_MAP_BPP;
}

const struct technique_info clustered_deferred_info = {
    .name = "clustered_deferred",
    .summary = "froxel light lists (compute), g-buffer, one lighting pass over each "
               "cluster's lights (seed 004)",
    .passes = passes,
    .options = {.fields = options,
                .size = sizeof(struct clustered_deferred_options),
                .check = check},
    .flags = TECHNIQUE_BOUNDED_LIGHT_LISTS,
    .planes_bpp = planes_bpp,
};
