#ifndef SHADEBENCH_TEMPORAL_H
#define SHADEBENCH_TEMPORAL_H

/* temporal.frames: at each capture k, frames k to k+K-1 of the technique
 * and of the reference (supersampled as the job's reference is), drawn
 * after the timed runs and the reference render (frame k is a pure
 * function of k, so they are the frames the timed run showed), and the
 * flicker between them (quality/flicker.h) added to each capture as
 * captures[].temporal and to the result as result.temporal. The metrics
 * stage reports the worst as quality.worst_flicker. No figure includes
 * its time. Render thread only. */

#include <jansson.h>
#include <stdbool.h>

#include "daemon/harness/run.h"

/* run is the job's measured first run (its technique destroyed); result
 * is outputs_write's. On false, run->err says why and *status is
 * JOB_CANCELLED when the job was cancelled. */
bool temporal_measure(struct harness_run *run, json_t *result, enum job_status *status);

#endif
