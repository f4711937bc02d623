#ifndef SHADEBENCH_HTTP_H
#define SHADEBENCH_HTTP_H

/* The HTTP API. Handlers validate, queue and answer; they never touch GL.
 * libmicrohttpd serves from a small pool of polling threads; long-polls are
 * suspended connections (see connections.h), so that no client holds a
 * thread. The functions here are called from the main thread. */

#include <stdbool.h>
#include <stddef.h>

#include <jansson.h>

#include "daemon/status/render_state.h"
#include "daemon/jobs/assets.h"
#include "daemon/jobs/queue.h"
#include "daemon/jobs/sweeps.h"
#include "daemon/techniques/catalog.h"

/* The longest bearer token accepted (a longer one is refused at load). */
#define HTTP_MAX_TOKEN_BYTES 4096

struct http_limits {
    unsigned max_connections;        /* open at once, in total */
    unsigned max_connections_per_ip; /* open at once, per client address */
    unsigned threads;                /* libmicrohttpd's polling threads */
    double header_timeout_s;         /* accept (or last answer) to complete headers */
    double body_timeout_s;           /* complete headers to complete body */
    double idle_timeout_s;           /* no byte either way (libmicrohttpd's own) */
    /* Uploads (PUT /v1/assets/NAME): an address's at once (of the daemon's
     * ASSETS_MAX_UPLOADS), and the rate each body must keep up, judged
     * over each window (connections.h). */
    unsigned uploads_per_ip;
    double upload_min_rate, upload_window_s;
};

/* An address's share of the upload slots: two of the four, so that one
 * client, however slow, leaves the others room. */
#define HTTP_UPLOADS_PER_IP 2

void http_limits_defaults(struct http_limits *l);

/* What the connections' buffers can reach at these limits (bytes): a part
 * of the memory budget. */
double http_memory_bytes(const struct http_limits *l);

/* What the API serves, handed in by its owner (main, or a unit test with a
 * render thread of its own making): everything outlives the server. */
struct http_context {
    const struct technique_catalog *catalog; /* jobs and sweeps are parsed against it */
    struct queue *queue;
    struct sweeps *sweeps;
    /* The assets (/v1/assets, a job's scene.asset); NULL: none (the asset
     * endpoints answer 503 and a job naming one is refused). */
    struct assets *assets;
    /* The Khronos reference (daemon/jobs/fidelity.h): /v1/info says
     * whether it is there, and a fidelity job is refused (503, naming what
     * is missing) when it is not. NULL: none. */
    struct fidelity *fidelity;
    /* The render thread as the API sees it, without GL: what it is doing
     * (render_state.h: whether it runs, its job and phase, its last
     * progress), for /healthz and /metrics, which must stay cheap (the
     * state is read lock-free); and its device strings (/v1/info, reports;
     * a new reference). Called from the HTTP threads. */
    void (*render_state)(void *render, struct render_state *out);
    json_t *(*device_json)(void *render);
    void *render;
    /* /healthz answers 503 when the render thread, busy with a job, has
     * made no progress for longer than this (--stall-seconds); 0: never. */
    double stall_s;
    /* The memory budget (/v1/info): in all (--memory-budget; 0: the sum of
     * its parts), and the driver's part, the daemon's resident set measured
     * at start with the GL context up. What a job may take is
     * job_cost_memory_limit(). */
    double memory_budget_bytes, driver_bytes;
};

struct http_server;

/* listen is "HOST:PORT" or "[V6]:PORT"; port 0 picks a free one. */
struct http_server *http_server_create(const char *listen, const struct http_limits *limits,
                                       const struct http_context *ctx, char *err,
                                       size_t errlen);
/* Ends every wait at once with a "stopping" answer (new waits are refused)
 * and gives those answers a moment to go out; then MHD stops. Accepts NULL. */
void http_server_destroy(struct http_server *s);

/* When token is non-empty, every endpoint but /healthz needs
 * "Authorization: Bearer <token>". Safe to call while serving (SIGHUP).
 * false (token unchanged) when it is over HTTP_MAX_TOKEN_BYTES. */
bool http_server_set_token(struct http_server *s, const char *token);
int http_server_port(const struct http_server *s);
/* HTTP connections open now (as /metrics counts them). Any thread. */
size_t http_server_open_connections(struct http_server *s);

#endif
