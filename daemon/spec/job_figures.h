#ifndef SHADEBENCH_JOB_FIGURES_H
#define SHADEBENCH_JOB_FIGURES_H

/* The headline figures of a finished job, taken from its result when it
 * finishes and kept in the store's row, so that a list of jobs (history)
 * shows them without reading any result: the median frame_ms, gpu_ms and
 * cpu_ms with their 95% interval (over the frames, or over the runs of a
 * repeated job), runs, worst SSIM, and the device's GL renderer and
 * version. GL-free; any thread. */

#include <jansson.h>

/* NULL when result is not an object. New reference. */
json_t *job_figures(const json_t *result);

#endif
