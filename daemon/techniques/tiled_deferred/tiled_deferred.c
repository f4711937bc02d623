/* Tiled deferred shading (seed 003): the g-buffer, then per-tile depth
 * bounds and light lists, then one full-screen lighting pass in which each
 * pixel loops over its tile's lights. binning "cpu" builds the lists on the
 * CPU every frame as the seed did (screen rectangles only) and uploads them
 * inside the timed region, to show what that costs. The work is shared with
 * the other culling techniques (daemon/techniques/shared/culled.c). */
#include "daemon/techniques/shared/culled.h"
#include "daemon/techniques/tiled_deferred/tiled_deferred_info.h"

static bool tiled_deferred_create(const struct technique_env *env, void **state, char *err,
                                  size_t errlen)
{
    const struct tiled_deferred_options *o = env->options;
    struct culled_config cfg = {
        .deferred = true,
        .grid = {.kind = LIGHT_GRID_TILES, .tile_size = o->tile_size, .binning = o->binning,
                 .technique = "tiled_deferred"},
        .gbuffer = o->gbuffer,
    };
    return culled_create(env, &cfg, state, err, errlen);
}

const struct technique technique_tiled_deferred = {
    .info = &tiled_deferred_info,
    .create = tiled_deferred_create,
    .render = culled_render,
    .verify = culled_verify,
    .describe = culled_describe,
    .destroy = culled_destroy,
};
