#ifndef SHADEBENCH_MEASURE_H
#define SHADEBENCH_MEASURE_H

/* The timed loop of a prepared run (run.h): warm-up frames, then the timed
 * frames with at most RUN_FRAMES_IN_FLIGHT in flight, each frame's CPU
 * submission time, frame interval and GPU passes recorded, captured frames
 * read back in a bracket that is subtracted from every figure. Nothing else
 * happens in here: no allocation, no file I/O, no lock (progress is an
 * atomic store). Render thread only. */

#include <stdbool.h>

#include "daemon/harness/run.h"

/* Renders the run's frames; run_index places it in the job's progress and
 * in messages. On false, run->err says why and *status is JOB_CANCELLED
 * when the job was cancelled (else left as it was). */
bool measure_run(struct harness_run *run, int run_index, enum job_status *status);

#endif
