#ifndef SHADEBENCH_METRICS_WORKER_H
#define SHADEBENCH_METRICS_WORKER_H

/* The metrics thread: compares a finished job's captures with its reference
 * frames, off the render thread, and completes the job (queue_finish) when
 * done. The render thread waits for it to be idle before it times the next
 * job (metrics_worker_wait_idle), so a comparison never shares the CPU with
 * a timed run. Create, destroy and submit: the render thread's owner and the
 * render thread; wait_idle: the render thread. */

#include <jansson.h>

#include "daemon/jobs/queue.h"

struct metrics_worker;

struct metrics_worker *metrics_worker_create(struct queue *q);
/* Finishes the jobs handed over so far, then stops. Accepts NULL. */
void metrics_worker_destroy(struct metrics_worker *w);
/* Takes ownership of result (the job's result without metrics yet). */
void metrics_worker_submit(struct metrics_worker *w, struct job *job, json_t *result);
/* Blocks until every job handed over has been scored, written and finished
 * (queue_finish returned): nothing of the metrics stage runs afterwards
 * until the next submit. */
void metrics_worker_wait_idle(struct metrics_worker *w);

#endif
