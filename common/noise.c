#include "common/noise.h"

#include <math.h>

double noise_cpu_left_change(double share, double reference)
{
    /* The CPU other processes left over, relative to the reference's: what
     * a CPU-bound renderer's speed follows when the machine is shared. */
    return (1.0 - share) / fmax(1.0 - reference, 0.01) - 1.0;
}

bool noise_exceeds(double share, double reference, double tolerance)
{
    return fabs(noise_cpu_left_change(share, reference)) > tolerance;
}

bool noise_interference_noisy(const json_t *interference)
{
    json_t *share = json_object_get(interference, "other_cpu_share");
    return json_is_number(share) ? noise_exceeds(json_number_value(share), 0.0, NOISE_TOLERANCE)
                                 : json_is_true(json_object_get(interference, "noisy"));
}
