#ifndef SHADEBENCH_API_SERVER_H
#define SHADEBENCH_API_SERVER_H

/* The HTTP server's insides, shared by its files and by nothing outside
 * daemon/api/: http.c (framing, limits, auth, the responders, waits, the
 * server's lifetime) and one file per resource, each answering its routes:
 * job_handlers.c (/v1/jobs), sweep_handlers.c (/v1/sweeps),
 * asset_handlers.c (/v1/assets), status_handlers.c (/healthz, /v1/info,
 * /metrics), ui_handlers.c (the dashboard's files at / and /ui/).
 *
 * Threads: the handlers run on libmicrohttpd's polling threads; nothing
 * here touches GL. */

#include <microhttpd.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include <jansson.h>

#include "daemon/api/connections.h"
#include "daemon/api/http.h"
#include "daemon/api/routes.h"

#ifndef MHD_HTTP_CONTENT_TOO_LARGE
#define MHD_HTTP_CONTENT_TOO_LARGE 413
#endif
#ifndef MHD_HTTP_UNPROCESSABLE_CONTENT
#define MHD_HTTP_UNPROCESSABLE_CONTENT 422
#endif
#ifndef MHD_HTTP_REQUEST_HEADER_FIELDS_TOO_LARGE
#define MHD_HTTP_REQUEST_HEADER_FIELDS_TOO_LARGE 431
#endif

enum {
    MAX_WAIT_S = 3600,
    /* Headers beyond this are answered 431 here, as JSON; beyond
     * CONNECTION_MEMORY (libmicrohttpd's per-connection pool) it answers
     * 431 itself, as HTML. */
    MAX_HEADER_BYTES = 8192,
    CONNECTION_MEMORY = 32 * 1024,
    /* A DELETE of a running job waits this long for the job to stop, so
     * that the answer usually shows its final state. */
    CANCEL_WAIT_S = 5,
    /* SIGTERM: how long the "stopping" answers of ended waits may take. */
    STOP_GRACE_S = 2,
};

/* The status codes the request counters of /metrics keep apart (http.c),
 * the last one standing for any other. */
enum { NCODES = 17 };
extern const unsigned COUNTED_CODES[NCODES];

struct http_server {
    struct MHD_Daemon *mhd;
    struct connections *conns;
    struct http_context ctx;
    struct queue *queue; /* ctx.queue and ctx.sweeps, the handlers' most used */
    struct sweeps *sweeps;
    struct http_limits limits;
    int port;
    pthread_mutex_t token_lock;
    char *token;
    atomic_ullong requests[ROUTE_COUNT][NCODES];
};

/* One request: the route, its body, and what a resumed wait answers. */
struct request {
    struct conn *conn;
    struct route route;
    char *body;
    size_t len;
    bool started;         /* the access handler has seen its headers */
    bool too_large;
    bool waiting;         /* suspended; the next call is the resume */
    unsigned wait_status; /* 200 for ?wait=, 202 for a DELETE that waits */
    /* What the raw request target showed (on_uri): a refusal to answer
     * once the headers are in, and the query's size. */
    const char *target_field, *target_rule;
    size_t query_args;
    /* PUT /v1/assets/NAME: the body streams into the upload; once it is in,
     * the request waits (suspended) on the conversion's ticket. */
    struct asset_upload *upload;
    uint64_t ticket;
};

/* Responders (http.c). Each queues the answer and returns libmicrohttpd's
 * result; respond_text and respond_json take ownership of text and body. */
enum MHD_Result respond_text(struct MHD_Connection *c, unsigned status,
                             char *text, size_t len, const char *type);
enum MHD_Result respond_json(struct MHD_Connection *c, unsigned status, json_t *body);
enum MHD_Result respond_error(struct MHD_Connection *c, unsigned status,
                              const char *field, const char *message);
/* 429 with Retry-After: retry_s (every other 429 says 5 s). */
enum MHD_Result respond_retry(struct MHD_Connection *c, const char *field, const char *message,
                              double retry_s);
enum MHD_Result respond_file(struct MHD_Connection *c, const char *path,
                             const char *type);
enum MHD_Result respond_html(struct MHD_Connection *c, char *html, size_t len);
enum MHD_Result respond_chart(struct MHD_Connection *c, const json_t *subject,
                              const struct route *r, bool is_sweep, const json_t *device);
/* ?wait=SECONDS: false when it is not a number from 0 to MAX_WAIT_S. */
bool parse_wait(struct MHD_Connection *c, double *wait);
/* Holds the request without a thread until the job or sweep finishes or
 * wait_s pass (answered once resumed). */
enum MHD_Result suspend_request(struct http_server *s, struct MHD_Connection *c,
                                struct request *req, enum wait_kind kind, double wait_s,
                                unsigned status);

/* /v1/jobs (job_handlers.c). */
enum MHD_Result submit_job(struct http_server *s, struct MHD_Connection *c,
                           struct request *req);
/* POST /v1/assets/NAME/fidelity (job_handlers.c). */
enum MHD_Result post_fidelity(struct http_server *s, struct MHD_Connection *c,
                              struct request *req);
enum MHD_Result job_resource(struct http_server *s, struct MHD_Connection *c,
                             const char *method, struct request *req);
/* GET /v1/jobs and GET /v1/sweeps: a page, with the link to the next one. */
enum MHD_Result respond_list(struct http_server *s, struct MHD_Connection *c,
                             enum route_kind route);
/* A job or sweep as the API serves it: the stored JSON plus its URLs. */
json_t *served_job(struct http_server *s, const char *id);
/* GET /v1/jobs/ID/pdiff/K.png of a done job whose files are in dir
 * (pdiff_mask.c). */
enum MHD_Result respond_pdiff_mask(struct http_server *s, struct MHD_Connection *c,
                                   const struct route *r, const char *dir);

/* /v1/sweeps (sweep_handlers.c). */
enum MHD_Result post_sweep(struct http_server *s, struct MHD_Connection *c,
                           struct request *req);
enum MHD_Result sweep_resource(struct http_server *s, struct MHD_Connection *c,
                               const char *method, struct request *req);
json_t *served_sweep(struct http_server *s, const char *id);
/* Whether a sweep's JSON shows it finished (a wait on it may end). */
bool sweep_json_finished(const json_t *sw);

/* /v1/assets (asset_handlers.c). */
enum MHD_Result respond_asset_error(struct MHD_Connection *c, const struct assets_error *e);
enum MHD_Result asset_resource(struct http_server *s, struct MHD_Connection *c,
                               const char *method, struct request *req);
enum MHD_Result finish_upload(struct http_server *s, struct MHD_Connection *c,
                              struct request *req);
/* PUT /v1/assets/NAME, its headers in: begins the upload that its body
 * streams into; true when it answered (*ret) instead. */
bool begin_upload(struct http_server *s, struct MHD_Connection *c, struct request *req,
                  const char *content_length, enum MHD_Result *ret);
/* A resumed upload: the conversion's answer, or why there is none. */
enum MHD_Result answer_upload(struct http_server *s, struct MHD_Connection *c,
                              struct request *req, enum wake why);

/* GET /v1/jobs/ID/history (history_handlers.c). */
enum MHD_Result respond_history(struct http_server *s, struct MHD_Connection *c,
                                const struct route *r);

/* / and /ui/...: the dashboard's embedded files (ui_handlers.c). */
enum MHD_Result respond_ui(struct MHD_Connection *c, const struct route *r);

/* /healthz, /v1/info, /metrics (status_handlers.c). */
enum MHD_Result respond_healthz(struct http_server *s, struct MHD_Connection *c);
json_t *info_json(struct http_server *s);
enum MHD_Result respond_metrics(struct http_server *s, struct MHD_Connection *c);

#endif
