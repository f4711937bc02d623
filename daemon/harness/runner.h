#ifndef SHADEBENCH_RUNNER_H
#define SHADEBENCH_RUNNER_H

/* The render thread: the only thread that makes the GL context current. It
 * takes jobs from the queue and runs them: warm-up, timed frames, captures
 * (outside the timed region), statistics, files. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/device_names.h"
#include "daemon/status/render_state.h"
#include "daemon/jobs/queue.h"

struct runner;

/* The fidelity worker fidelity jobs are handed to (daemon/reference/
 * fidelity.h); call before runner_create. */
struct fidelity;
void runner_use_fidelity(struct fidelity *f);

/* Starts the render thread and waits until its context is up on the
 * device that device names (egl.h), or failed. */
struct runner *runner_create(struct queue *q, const struct device_spec *device, bool gl_debug,
                             char *err, size_t errlen);
/* Stops the queue and waits up to wait_s for the render thread to end: the
 * running job stops at once and is put back in the queue, but what the GPU
 * still has of its frame drains first. False when the thread has not ended
 * by then (the owner may exit without it: the job's state is on disk). */
bool runner_stop(struct runner *r, double wait_s);
/* Stops the queue, lets the running job see it, joins. Accepts NULL. */
void runner_destroy(struct runner *r);

bool runner_alive(struct runner *r);
/* What the render thread is doing (render_state.h), alive included; cheap
 * and lock-free, for /healthz. Any thread. */
void runner_state(struct runner *r, struct render_state *out);
/* Device and driver strings, as reported in every result. New reference. */
json_t *runner_device_json(struct runner *r);

#endif
