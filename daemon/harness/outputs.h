#ifndef SHADEBENCH_OUTPUTS_H
#define SHADEBENCH_OUTPUTS_H

/* What a measured run leaves behind: the captures read back in the timed
 * loop's capture bracket (the 8-bit frame, the HDR colour's non-finite
 * pixels and statistics, the heat map), and after the loop the PNG files,
 * timings.csv, the statistics and result.json. Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/harness/run.h"

/* Reads back timed frame k, which the job captures, into the run's next
 * capture slot. Stalls: only inside the capture bracket. */
bool outputs_read_capture(struct harness_run *run, int k);

/* Encodes the captures, writes timings.csv and result.json in the job's
 * directory, and returns the result (new reference), or NULL with
 * run->err. Outside every timed region. */
json_t *outputs_write(struct harness_run *run);

/* Statistics of a series of per-frame figures, as the result reports them
 * (mean, median, spread, percentiles, the median's 95% interval). */
json_t *outputs_stats_json(const double *v, size_t n);
/* A job timed in slices (accept_sliced_timing): result.sliced and every
 * timing series and pass marked "sliced": true, so that no reader takes
 * them for whole frames. */
void outputs_mark_sliced(json_t *result);

#endif
