/* Forward+: a depth pre-pass, per-tile depth bounds and light lists in
 * compute passes, then the objects drawn again, each fragment looping over
 * its tile's lights. The work is shared with the other culling techniques
 * (daemon/techniques/shared/culled.c). */
#include "daemon/techniques/forward_plus/forward_plus_info.h"
#include "daemon/techniques/shared/culled.h"

static bool forward_plus_create(const struct technique_env *env, void **state, char *err,
                                size_t errlen)
{
    const struct forward_plus_options *o = env->options;
    struct culled_config cfg = {
        .grid = {.kind = LIGHT_GRID_TILES, .tile_size = o->tile_size,
                 .binning = LIGHT_BINNING_GPU, .technique = "forward_plus"},
    };
    return culled_create(env, &cfg, state, err, errlen);
}

const struct technique technique_forward_plus = {
    .info = &forward_plus_info,
    .create = forward_plus_create,
    .render = culled_render,
    .verify = culled_verify,
    .describe = culled_describe,
    .destroy = culled_destroy,
};
