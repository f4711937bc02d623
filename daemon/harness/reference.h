#ifndef SHADEBENCH_REFERENCE_H
#define SHADEBENCH_REFERENCE_H

/* The reference render of a job: the reference technique at exactly the
 * captured frames, after the timed runs, over the measured run's scene and
 * look stages, written as reference-NNNNNN.png beside the captures. Its
 * time is in no figure. Render thread only. */

#include <stdbool.h>

#include "daemon/harness/run.h"

/* run is the job's measured first run (its technique already destroyed).
 * On false, run->err says why and *status is JOB_CANCELLED when the job was
 * cancelled. */
bool reference_render(struct harness_run *run, enum job_status *status);

#endif
