#ifndef SHADEBENCH_HTTP_H
#define SHADEBENCH_HTTP_H

/* The HTTP API. Handlers validate, queue and answer; they never touch GL. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/jobs/queue.h"
#include "daemon/harness/runner.h"
#include "daemon/jobs/sweeps.h"

struct http_server;

/* listen is "HOST:PORT" or "[V6]:PORT"; port 0 picks a free one. */
struct http_server *http_server_create(const char *listen, struct queue *q,
                                       struct runner *r, struct sweeps *sweeps, char *err,
                                       size_t errlen);
void http_server_destroy(struct http_server *s);

/* When token is non-empty, every endpoint but /healthz needs
 * "Authorization: Bearer <token>". Safe to call while serving (SIGHUP). */
void http_server_set_token(struct http_server *s, const char *token);
int http_server_port(const struct http_server *s);

#endif
