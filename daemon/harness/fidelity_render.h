#ifndef SHADEBENCH_FIDELITY_RENDER_H
#define SHADEBENCH_FIDELITY_RENDER_H

/* The render thread's half of a fidelity job (fidelity_spec.h): after the
 * measured run, outside every timed region, the job's technique draws the
 * compared frame (the last captured one) once per debug channel, the job's
 * look with look.debug set to the channel, as the reference technique is
 * drawn (frame_source: a fresh instance over the measured run's scene and
 * look stages). Each is written to DIR/fidelity/shadebench-NAME.png (the
 * lit image is the captured frame itself). What the viewer must be given
 * is taken from the same scene at the same frame: the camera's view and
 * projection matrices and eye, and every light in glTF's terms. Render
 * thread only. */

#include <jansson.h>
#include <stdbool.h>

#include "daemon/harness/run.h"

/* The job's fidelity/ folder; "view" (the frame, camera, lights, what each
 * channel gave) as a new reference, or NULL with run->err (and *status
 * JOB_CANCELLED when the job was cancelled). A channel look.debug cannot
 * draw (a build without it, an unknown name) is listed with its error and
 * the others go on. */
json_t *fidelity_render(struct harness_run *run, enum job_status *status);

#endif
