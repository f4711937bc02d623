#ifndef SHADEBENCH_DEFERRED_INFO_H
#define SHADEBENCH_DEFERRED_INFO_H

/* Deferred shading's GL-free half (seed 001): its options ("deferred":
 * {"light_bounds", "gbuffer": {"normal", "albedo"}}) and passes. Any thread. */

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

struct deferred_options {
    int light_bounds; /* enum light_bounds */
    struct gbuffer_options gbuffer;
};

extern const struct technique_info deferred_info;

#endif
