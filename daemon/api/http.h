#ifndef SHADEBENCH_HTTP_H
#define SHADEBENCH_HTTP_H

/* The HTTP API. Handlers validate, queue and answer; they never touch GL.
 * libmicrohttpd serves from a small pool of polling threads; long-polls are
 * suspended connections (see connections.h), so that no client holds a
 * thread. The functions here are called from the main thread. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/harness/runner.h"
#include "daemon/jobs/queue.h"
#include "daemon/jobs/sweeps.h"

/* The longest bearer token accepted (a longer one is refused at load). */
#define HTTP_MAX_TOKEN_BYTES 4096

struct http_limits {
    unsigned max_connections;        /* open at once, in total */
    unsigned max_connections_per_ip; /* open at once, per client address */
    unsigned threads;                /* libmicrohttpd's polling threads */
    double header_timeout_s;         /* accept (or last answer) to complete headers */
    double body_timeout_s;           /* complete headers to complete body */
    double idle_timeout_s;           /* no byte either way (libmicrohttpd's own) */
};

void http_limits_defaults(struct http_limits *l);

struct http_server;

/* listen is "HOST:PORT" or "[V6]:PORT"; port 0 picks a free one. */
struct http_server *http_server_create(const char *listen, const struct http_limits *limits,
                                       struct queue *q, struct runner *r,
                                       struct sweeps *sweeps, char *err, size_t errlen);
/* Ends every wait at once with a "stopping" answer (new waits are refused)
 * and gives those answers a moment to go out; then MHD stops. Accepts NULL. */
void http_server_destroy(struct http_server *s);
/* Only the first half of destroy: waits end, serving goes on. Accepts NULL. */
void http_server_stop_waits(struct http_server *s);

/* When token is non-empty, every endpoint but /healthz needs
 * "Authorization: Bearer <token>". Safe to call while serving (SIGHUP).
 * false (token unchanged) when it is over HTTP_MAX_TOKEN_BYTES. */
bool http_server_set_token(struct http_server *s, const char *token);
int http_server_port(const struct http_server *s);

#endif
