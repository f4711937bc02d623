#include "daemon/techniques/clustered_deferred/clustered_deferred_info.h"

#include <stddef.h>

static const char *const passes[] = {"binning", "gbuffer", "lighting", NULL};

static const struct technique_option options[] = {
    CLUSTER_OPTION_ROWS(struct clustered_deferred_options, cluster),
    GBUFFER_OPTION_ROWS(struct clustered_deferred_options, gbuffer),
    {0},
};

static bool check(const void *opts, struct job_error *err)
{
    return cluster_grid_check(((const struct clustered_deferred_options *)opts)->cluster.grid,
                              "clustered_deferred.grid", err);
}

const struct technique_info clustered_deferred_info = {
    .name = "clustered_deferred",
    .summary = "froxel light lists (compute), g-buffer, one lighting pass over each cluster's lights (seed 004)",
    .passes = passes,
    .options = options,
    .options_size = sizeof(struct clustered_deferred_options),
    .check = check,
};
