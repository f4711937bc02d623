#ifndef SHADEBENCH_TILED_DEFERRED_INFO_H
#define SHADEBENCH_TILED_DEFERRED_INFO_H

/* Tiled deferred shading's GL-free half (seed 003): its options
 * ("tiled_deferred": {"tile_size", "binning", "gbuffer": {...}}) and passes.
 * Any thread. */

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

struct tiled_deferred_options {
    int tile_size; /* pixels */
    int binning;   /* enum light_binning */
    struct gbuffer_options gbuffer;
};

extern const struct technique_info tiled_deferred_info;

#endif
