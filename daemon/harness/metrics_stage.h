#ifndef SHADEBENCH_METRICS_WORKER_H
#define SHADEBENCH_METRICS_WORKER_H

/* The metrics thread: compares a finished job's captures with its reference
 * frames, off the render thread, so a long comparison never delays the next
 * job's frames. It completes the job (queue_finish) when done. */

#include <jansson.h>

#include "daemon/jobs/queue.h"

struct metrics_worker;

struct metrics_worker *metrics_worker_create(struct queue *q);
/* Finishes the jobs handed over so far, then stops. Accepts NULL. */
void metrics_worker_destroy(struct metrics_worker *w);
/* Takes ownership of result (the job's result without metrics yet). */
void metrics_worker_submit(struct metrics_worker *w, struct job *job, json_t *result);

#endif
