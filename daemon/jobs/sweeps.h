#ifndef SHADEBENCH_SWEEPS_H
#define SHADEBENCH_SWEEPS_H

/* Running sweeps: a thread of their own submits each point as an ordinary
 * job (so points show up in /v1/jobs too), waits for it, and fills the
 * sweep's table; find sweeps bisect. GL-free.
 *
 * Sweeps are records of the store (store.h), as jobs are: a row holding the
 * sweep's state and table, written on every change with no lock held, and
 * STATE_DIR/sweeps/ID/spec.json. Only queued and running sweeps live in
 * memory. On start, finished sweeps are served as before; a sweep stopped
 * by SIGTERM was put back in the queue and resumes (after the points it
 * has, waiting for its requeued point job rather than running it twice);
 * one that was running when the daemon was killed is marked interrupted,
 * its points kept. A state directory of an earlier version (sweep.json) is
 * imported. Retention follows the jobs' settings, and keeps the point jobs
 * of queued and running sweeps. Any thread, except create and destroy (the
 * main thread). */

#include <jansson.h>
#include <stdbool.h>

#include "daemon/jobs/queue.h"
#include "daemon/spec/sweep_spec.h"

#define SWEEPS_MAX_WAITING 16

struct sweeps;

/* Loads the sweeps from the queue's store (after queue_load, so that a
 * resumed sweep finds its point job), then starts the thread. */
struct sweeps *sweeps_create(struct queue *q, const struct technique_catalog *techniques);
/* Stops: the running sweep goes back to the queue, persisted, to resume on
 * the next start. Before the runner stops the job queue. Accepts NULL. */
void sweeps_destroy(struct sweeps *s);

/* Takes ownership of spec on QUEUE_OK. QUEUE_FULL when too many are
 * waiting, QUEUE_IO_ERROR when it cannot be stored (nothing is accepted;
 * queue_submit_error says why). */
enum queue_submit_result sweeps_submit(struct sweeps *s, struct sweep_spec *spec,
                                       const json_t *body, char id_out[24]);
json_t *sweeps_json(struct sweeps *s, const char *id, double wait_s);
/* One page of the sweep list, {"sweeps": [...]}, without tables; next gets
 * the cursor of the next page, "" after the last. NULL with err on a store
 * error. */
json_t *sweeps_list_page(struct sweeps *s, const struct store_query *query,
                         char next[RECORD_ID_LEN], char *err, size_t errlen);
enum queue_cancel_result sweeps_cancel(struct sweeps *s, const char *id);

#endif
