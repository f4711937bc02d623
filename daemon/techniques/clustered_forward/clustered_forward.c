/* Clustered forward shading (seed 004): lights binned into a froxel grid
 * (tiles cut into depth slices) on the GPU, a depth pre-pass, then the
 * objects drawn again, each fragment looping over its cluster's lights.
 * A cluster holds at most max_lights_per_cluster lights; one that overflows
 * is counted and, by option, shades with every light or fails the job. The
 * work is shared with the other culling techniques
 * (daemon/techniques/shared/culled.c). */
#include "daemon/techniques/clustered_forward/clustered_forward_info.h"
#include "daemon/techniques/shared/culled.h"

static bool clustered_forward_create(const struct technique_env *env, void **state, char *err,
                        size_t errlen)
{
    const struct clustered_forward_options *o = env->options;
    const struct cluster_options *c = &o->cluster;
    struct culled_config cfg = {
        .deferred = false,
        .grid = {.kind = LIGHT_GRID_CLUSTERS,
                 .grid = {c->grid[0], c->grid[1], c->grid[2]},
                 .slices = c->slices,
                 .max_per_cell = c->max_lights_per_cluster,
                 .overflow = c->overflow,
                 .binning = LIGHT_BINNING_GPU,
                 .technique = "clustered_forward"},
    };
    return culled_create(env, &cfg, state, err, errlen);
}

const struct technique technique_clustered_forward = {
    .info = &clustered_forward_info,
    .create = clustered_forward_create,
    .render = culled_render,
    .verify = culled_verify,
    .describe = culled_describe,
    .destroy = culled_destroy,
};
