#ifndef SHADEBENCH_CLUSTERED_FORWARD_INFO_H
#define SHADEBENCH_CLUSTERED_FORWARD_INFO_H

/* Clustered forward shading's GL-free half (seed 004): its options
 * ("clustered_forward": {"grid", "slices", "max_lights_per_cluster",
 * "overflow"}) and passes. Any thread. */

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

struct clustered_forward_options {
    struct cluster_options cluster;
};

extern const struct technique_info clustered_forward_info;

#endif
