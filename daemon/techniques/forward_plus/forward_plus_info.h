#ifndef SHADEBENCH_FORWARD_PLUS_INFO_H
#define SHADEBENCH_FORWARD_PLUS_INFO_H

/* Forward+'s GL-free half: its options ("forward_plus": {"tile_size"}) and
 * passes. Any thread. */

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

struct forward_plus_options {
    int tile_size; /* pixels */
};

extern const struct technique_info forward_plus_info;

#endif
