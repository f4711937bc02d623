/* The stop request every metric loop polls between tiles (metrics.h): a
 * leaf, so that the metrics and compare.c, which runs them, do not depend
 * on each other. */
#include <stdio.h>

#include "daemon/quality/metrics.h"

bool metrics_stopped(const struct metrics_stop *stop, char *err, size_t errlen)
{
    if (!stop || !stop->requested || !stop->requested(stop->ctx))
        return false;
    snprintf(err, errlen, "stopped");
    return true;
}
