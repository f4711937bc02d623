#ifndef SHADEBENCH_SWEEPS_H
#define SHADEBENCH_SWEEPS_H

/* Running sweeps: a thread of their own submits each point as an ordinary
 * job (so points show up in /v1/jobs too), waits for it, and fills the
 * sweep's table; find sweeps bisect. GL-free. */

#include <jansson.h>
#include <stdbool.h>

#include "daemon/jobs/queue.h"
#include "daemon/jobs/sweep_spec.h"

#define SWEEPS_MAX_WAITING 16

struct sweeps;

struct sweeps *sweeps_create(struct queue *q, const struct technique_catalog *techniques);
/* Cancels the running sweep and stops. Accepts NULL. */
void sweeps_destroy(struct sweeps *s);

/* Takes ownership of spec (on success). false when too many are waiting. */
bool sweeps_submit(struct sweeps *s, struct sweep_spec *spec, const json_t *body, char id_out[24]);
json_t *sweeps_json(struct sweeps *s, const char *id, double wait_s);
json_t *sweeps_list_json(struct sweeps *s);
enum queue_cancel_result sweeps_cancel(struct sweeps *s, const char *id);

#endif
