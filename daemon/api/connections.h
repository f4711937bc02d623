#ifndef SHADEBENCH_CONNECTIONS_H
#define SHADEBENCH_CONNECTIONS_H

/* Every open HTTP connection, from accept to close, so that no client can
 * hold the daemon:
 *  - deadlines that activity cannot stretch: the request's headers must be
 *    in within header_s of the accept (or of the previous request on the
 *    connection), its body within body_s of the headers; a late connection
 *    is shut down (libmicrohttpd's own timeout restarts on every byte);
 *  - a health check has an allowance of its own: past its address's
 *    per_ip connections, the next CONNECTIONS_HEALTH_RESERVE are reserve
 *    connections, which may ask /healthz and /metrics only, must send
 *    their request within CONNECTIONS_RESERVE_HEADER_S and are closed after
 *    one answer, so that other clients of the same address (waits held
 *    open, a local load test) cannot lock a local monitor out;
 *  - an upload (PUT /v1/assets/NAME) holds one of the daemon's few upload
 *    slots, so a slow one must not keep it: each must deliver at least
 *    CONNECTIONS_UPLOAD_MIN_RATE bytes a second over every window of
 *    CONNECTIONS_UPLOAD_WINDOW_S, or it is shut down, and an address holds
 *    at most its per-address share of the slots at once;
 *  - long-polls (?wait=) hold no thread: the connection is suspended
 *    (MHD_suspend_connection) and one watcher thread resumes it when its job
 *    or sweep has finished, its time is up, its client has gone away
 *    (EPOLLRDHUP on the suspended socket) or the daemon stops.
 * The watcher is the only thread of this module. The functions are called
 * from libmicrohttpd's threads; connections_poke from any thread, and never
 * blocks (it is called under the job store's lock). */

#include <microhttpd.h>
#include <stdbool.h>
#include <stddef.h>

struct connections;
struct conn;

/* Why a suspended request was resumed. */
enum wake { WAKE_NONE, WAKE_READY, WAKE_TIMEOUT, WAKE_GONE, WAKE_STOPPING };

/* WAIT_ASSET: an upload's conversion; its id is the ticket (assets.h). */
enum wait_kind { WAIT_JOB, WAIT_SWEEP, WAIT_ASSET };

/* True when a wait on kind/id can end now (finished, or no longer there).
 * Called on the watcher thread, which holds no lock of the caller's. */
typedef bool (*wait_done_fn)(void *ctx, enum wait_kind kind, const char *id);

/* Connections an address may open past its per-IP limit for /healthz and
 * /metrics (libmicrohttpd's own per-IP limit is set to per_ip plus these). */
#define CONNECTIONS_HEALTH_RESERVE 4
#define CONNECTIONS_RESERVE_HEADER_S 2.0

/* An upload's body must bring this many bytes a second, judged over each
 * window (the first starts with its headers): a link of 256 kbit/s keeps
 * up; one byte every 5 s does not. */
#define CONNECTIONS_UPLOAD_MIN_RATE (32.0 * 1024)
#define CONNECTIONS_UPLOAD_WINDOW_S 10.0

struct connections_config {
    double header_s; /* accept (or the previous request) to complete headers */
    double body_s;   /* complete headers to complete body */
    unsigned per_ip; /* an address's connections before reserve ones (0: no limit) */
    unsigned uploads_per_ip; /* an address's uploads at once (0: no limit) */
    double upload_min_rate;  /* bytes a second (0: CONNECTIONS_UPLOAD_MIN_RATE) */
    double upload_window_s;  /* seconds (0: CONNECTIONS_UPLOAD_WINDOW_S) */
};

struct connections *connections_create(const struct connections_config *cfg, wait_done_fn done,
                                       void *ctx, char *err, size_t errlen);
/* Stops the watcher. Every connection must have been closed (after
 * MHD_stop_daemon). Accepts NULL. */
void connections_destroy(struct connections *cs);

/* MHD_OPTION_NOTIFY_CONNECTION, with cs as its closure. */
void connections_notify(void *cls, struct MHD_Connection *c, void **socket_context,
                        enum MHD_ConnectionNotificationCode code);
/* The tracked state of c; NULL if it could not be tracked (out of memory). */
struct conn *connections_of(struct MHD_Connection *c);

/* The request's headers are in: its body deadline starts. */
void connections_headers_in(struct connections *cs, struct conn *k);
/* An upload's body may take this long from now (a large asset over a slow
 * link) instead of body_s; never shorter than body_s. */
void connections_body_deadline(struct connections *cs, struct conn *k, double seconds);
/* An upload's headers are in: it takes one of its address's upload slots,
 * and its body is held to the minimum rate. false when the address has its
 * uploads_per_ip already; *retry_s then says when one may be free (the
 * soonest its uploads are judged again). */
bool connections_upload_begin(struct connections *cs, struct conn *k, double *retry_s);
/* bytes more of an upload's body have come in. */
void connections_upload_bytes(struct connections *cs, struct conn *k, size_t bytes);
/* When an upload slot may be free (the daemon's are all taken): the soonest
 * a streaming upload is judged again, or a window when none streams. */
double connections_upload_retry_s(struct connections *cs);
/* The request is complete and being answered: no deadline but libmicrohttpd's
 * idle timeout while the answer is sent. */
void connections_answering(struct connections *cs, struct conn *k);
/* The answer is sent: the next request's header deadline starts. */
void connections_request_done(struct connections *cs, struct conn *k);
/* A connection past its address's per-IP limit (see above): it serves a
 * health check and closes. */
bool connections_is_reserve(const struct conn *k);

/* The answer's status, for the request counters. */
void connections_set_status(struct conn *k, unsigned status);
unsigned connections_status(const struct conn *k);

/* Suspends the request until kind/id is done or wait_s pass; false (and not
 * suspended) while stopping. Call from the access handler, then return
 * MHD_YES without a response; it is called again once resumed. */
bool connections_suspend(struct connections *cs, struct conn *k, enum wait_kind kind,
                         const char *id, double wait_s);
/* After the resume: why (and the request is no longer waiting). */
enum wake connections_wake(const struct conn *k);

/* Something a wait may be waiting for has changed. Lock-free. */
void connections_poke(struct connections *cs);
/* Ends every wait at once (WAKE_STOPPING); later suspends are refused. Then
 * waits up to grace_s until those answers have gone out. */
void connections_stop(struct connections *cs, double grace_s);

struct connections_stats {
    size_t open, waiting, uploads;
    unsigned long long header_timeouts, body_timeouts, waits_gone, slow_uploads;
};
void connections_stats(struct connections *cs, struct connections_stats *out);

#endif
