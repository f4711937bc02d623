#ifndef SHADEBENCH_CLUSTERED_DEFERRED_INFO_H
#define SHADEBENCH_CLUSTERED_DEFERRED_INFO_H

/* Clustered deferred shading's GL-free half (seed 004): its options
 * ("clustered_deferred": {"grid", "slices", "max_lights_per_cluster",
 * "overflow", "gbuffer": {...}}) and passes. Any thread. */

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

struct clustered_deferred_options {
    struct cluster_options cluster;
    struct gbuffer_options gbuffer;
};

extern const struct technique_info clustered_deferred_info;

#endif
