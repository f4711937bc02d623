#ifndef SHADEBENCH_HTTP_H
#define SHADEBENCH_HTTP_H

/* The HTTP API. Handlers validate, queue and answer; they never touch GL. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/queue.h"
#include "daemon/runner.h"

struct http_server;

/* listen is "HOST:PORT" or "[V6]:PORT"; port 0 picks a free one. */
struct http_server *http_server_create(const char *listen, struct queue *q,
                                       struct runner *r, char *err, size_t errlen);
void http_server_destroy(struct http_server *s);
int http_server_port(const struct http_server *s);

#endif
