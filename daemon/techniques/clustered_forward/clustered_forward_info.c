#include "daemon/techniques/clustered_forward/clustered_forward_info.h"

#include <stddef.h>

static const char *const passes[] = {"binning", "depth_prepass", "shading", NULL};

static const struct technique_option options[] = {
    CLUSTER_OPTION_ROWS(struct clustered_forward_options, cluster),
    {0},
};

static bool check(const void *opts, struct job_error *err)
{
    return cluster_grid_check(((const struct clustered_forward_options *)opts)->cluster.grid,
                              "clustered_forward.grid", err);
}

const struct technique_info clustered_forward_info = {
    .name = "clustered_forward",
    .summary = "froxel light lists (compute), depth pre-pass, forward shading over each cluster's lights (seed 004)",
    .passes = passes,
    .options = options,
    .options_size = sizeof(struct clustered_forward_options),
    .check = check,
};
