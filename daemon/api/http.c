#define _POSIX_C_SOURCE 200809L
#include "daemon/api/http.h"

#include <errno.h>
#include <fcntl.h>
#include <microhttpd.h>
#include <netdb.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"
#include "daemon/api/server.h"
#include "daemon/reports/charts.h"
#include "daemon/spec/job_spec.h"
#include "common/result_keys.h"

/* The status codes the request counters of /metrics keep apart. */
const unsigned COUNTED_CODES[NCODES] = {200, 201, 202, 400, 401, 403, 404, 405, 409, 413,
                                        422, 429, 431, 500, 503, 507, 0 /* other */};

void http_limits_defaults(struct http_limits *l)
{
    l->max_connections = 4096;
    l->max_connections_per_ip = 64;
    l->threads = 4;
    l->header_timeout_s = 10;
    l->body_timeout_s = 30;
    l->idle_timeout_s = 30;
    l->uploads_per_ip = HTTP_UPLOADS_PER_IP;
    l->upload_min_rate = CONNECTIONS_UPLOAD_MIN_RATE;
    l->upload_window_s = CONNECTIONS_UPLOAD_WINDOW_S;
}

/* Compares in time that depends on the expected token's length only, never
 * on where the first differing byte is. */
static bool token_matches(const char *given, const char *expected)
{
    size_t given_len = strlen(given), expected_len = strlen(expected);
    unsigned char diff = given_len != expected_len;
    for (size_t i = 0; i < expected_len; i++)
        diff |= (unsigned char)(expected[i] ^ (i < given_len ? given[i] : 0));
    return diff == 0;
}

static bool authorized(struct http_server *s, struct MHD_Connection *c)
{
    pthread_mutex_lock(&s->token_lock);
    bool ok = !s->token || s->token[0] == '\0';
    if (!ok) {
        /* RFC 9110: the scheme is case-insensitive ("bearer" too), and one
         * or more spaces part it from the token. */
        const char *auth = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Authorization");
        ok = auth && strncasecmp(auth, "Bearer ", 7) == 0;
        if (ok) {
            auth += 7;
            while (*auth == ' ')
                auth++;
            ok = token_matches(auth, s->token);
        }
    }
    pthread_mutex_unlock(&s->token_lock);
    return ok;
}

bool http_server_set_token(struct http_server *s, const char *token)
{
    if (token && strlen(token) > HTTP_MAX_TOKEN_BYTES)
        return false;
    char *copy = strdup(token ? token : "");
    if (!copy)
        return false;
    pthread_mutex_lock(&s->token_lock);
    free(s->token);
    s->token = copy;
    pthread_mutex_unlock(&s->token_lock);
    return true;
}

/* Set by answer_waited just before it closes the connection of a client
 * that hung up, and read by on_mhd_log, which libmicrohttpd calls at once
 * on the same thread: its "internal error" line is then the expected end
 * of a wait, not an error (2,000 waits hung up made 2,000 warnings). */
static _Thread_local bool closing_gone_client;

/* The next 429's Retry-After on this thread (respond_retry), else
 * RETRY_AFTER_DEFAULT_S. */
static _Thread_local double next_retry_s;
#define RETRY_AFTER_DEFAULT_S 5

enum MHD_Result respond_retry(struct MHD_Connection *c, const char *field, const char *message,
                              double retry_s)
{
    next_retry_s = retry_s;
    return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, field, message);
}

enum MHD_Result respond_text(struct MHD_Connection *c, unsigned status,
                             char *text, size_t len, const char *type)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, text, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(text);
        return MHD_NO;
    }
    MHD_add_response_header(resp, "Content-Type", type);
    MHD_add_response_header(resp, "Cache-Control", "no-store");
    if (connections_is_reserve(connections_of(c)))
        MHD_add_response_header(resp, "Connection", "close"); /* gives the reserve slot back */
    if (status == MHD_HTTP_UNAUTHORIZED)
        MHD_add_response_header(resp, "WWW-Authenticate", "Bearer realm=\"shadebench\"");
    if (status == MHD_HTTP_TOO_MANY_REQUESTS) {
        /* RFC 9110: when to come back, in whole seconds. */
        char after[24];
        double wait = next_retry_s > 0 ? next_retry_s : RETRY_AFTER_DEFAULT_S;
        snprintf(after, sizeof(after), "%.0f", wait < 1 ? 1 : wait + 0.5);
        MHD_add_response_header(resp, "Retry-After", after);
    }
    next_retry_s = 0;
    connections_set_status(connections_of(c), status);
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

/* Takes ownership of body. A body that cannot be built or printed still
 * gets an answer: a fixed 500. */
enum MHD_Result respond_json(struct MHD_Connection *c, unsigned status, json_t *body)
{
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body);
    if (!text) {
        static const char fallback[] =
            "{\"error\":{\"field\":\"body\",\"message\":\"the answer could not be built\"}}\n";
        text = strdup(fallback);
        status = MHD_HTTP_INTERNAL_SERVER_ERROR;
        if (!text)
            return MHD_NO;
    }
    size_t len = strlen(text);
    char *with_nl = realloc(text, len + 2);
    if (!with_nl) {
        free(text);
        return MHD_NO;
    }
    with_nl[len] = '\n';
    with_nl[len + 1] = '\0';
    return respond_text(c, status, with_nl, len + 1, "application/json");
}

enum MHD_Result respond_error(struct MHD_Connection *c, unsigned status,
                              const char *field, const char *message)
{
    struct job_error e;
    snprintf(e.field, sizeof(e.field), "%s", field);
    snprintf(e.message, sizeof(e.message), "%s", message);
    return respond_json(c, status, job_error_to_json(&e));
}

static enum MHD_Result respond_405(struct MHD_Connection *c, const char *allow, const char *rule)
{
    struct job_error e;
    snprintf(e.field, sizeof(e.field), "method");
    snprintf(e.message, sizeof(e.message), "%s", rule);
    json_t *body = job_error_to_json(&e);
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body);
    struct MHD_Response *resp =
        text ? MHD_create_response_from_buffer(strlen(text), text, MHD_RESPMEM_MUST_FREE) : NULL;
    if (!resp) {
        free(text);
        return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", rule);
    }
    MHD_add_response_header(resp, "Content-Type", "application/json");
    MHD_add_response_header(resp, "Allow", allow);
    if (connections_is_reserve(connections_of(c)))
        MHD_add_response_header(resp, "Connection", "close");
    connections_set_status(connections_of(c), MHD_HTTP_METHOD_NOT_ALLOWED);
    enum MHD_Result ret = MHD_queue_response(c, MHD_HTTP_METHOD_NOT_ALLOWED, resp);
    MHD_destroy_response(resp);
    return ret;
}

enum MHD_Result respond_file(struct MHD_Connection *c, const char *path,
                             const char *type)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        if (fd >= 0)
            close(fd);
        return respond_error(c, MHD_HTTP_NOT_FOUND, "url", "no such file");
    }
    struct MHD_Response *resp = MHD_create_response_from_fd((uint64_t)st.st_size, fd);
    if (!resp) {
        close(fd);
        return MHD_NO;
    }
    MHD_add_response_header(resp, "Content-Type", type);
    connections_set_status(connections_of(c), MHD_HTTP_OK);
    enum MHD_Result ret = MHD_queue_response(c, MHD_HTTP_OK, resp);
    MHD_destroy_response(resp);
    return ret;
}

bool parse_wait(struct MHD_Connection *c, double *wait)
{
    const char *v = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "wait");
    *wait = 0;
    if (!v)
        return true;
    char *end;
    errno = 0;
    double d = strtod(v, &end);
    if (errno || end == v || *end || !(d >= 0 && d <= MAX_WAIT_S))
        return false;
    *wait = d;
    return true;
}

enum MHD_Result respond_chart(struct MHD_Connection *c, const json_t *subject,
                              const struct route *r, bool is_sweep, const json_t *device)
{
    enum chart_format format = r->chart_png ? CHART_PNG : CHART_SVG;
    struct chart_options o = {.device = device};
    o.series = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "series");
    if (o.series && strcmp(o.series, RK_FRAME_MS) && strcmp(o.series, RK_GPU_MS) && strcmp(o.series, RK_CPU_MS))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "series", "must be frame_ms, gpu_ms or cpu_ms");
    const char *y = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "y");
    if (y && strcmp(y, "ssim") && strcmp(y, "flip"))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "y", "must be ssim or flip");
    o.flip = y && strcmp(y, "flip") == 0;
    char err[256];
    size_t len = 0;
    char *data = is_sweep ? charts_sweep(subject, r->chart, format, &o, &len, err, sizeof(err))
                          : charts_job(subject, r->chart, format, &o, &len, err, sizeof(err));
    if (!data)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "chart", err);
    return respond_text(c, MHD_HTTP_OK, data, len, r->chart_png ? "image/png" : "image/svg+xml");
}

enum MHD_Result respond_html(struct MHD_Connection *c, char *html, size_t len)
{
    if (!html)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "report", "out of memory");
    return respond_text(c, MHD_HTTP_OK, html, len, "text/html; charset=utf-8");
}

/* The watcher's question: may a wait on kind/id end now? */
static bool wait_done(void *ctx, enum wait_kind kind, const char *id)
{
    struct http_server *s = ctx;
    if (kind == WAIT_ASSET)
        return !s->ctx.assets || assets_ticket_done(s->ctx.assets, strtoull(id, NULL, 10));
    if (kind == WAIT_JOB) {
        char dir[PATH_MAX];
        enum job_status st;
        return !queue_job_dir(s->queue, id, dir, sizeof(dir), &st) || job_status_finished(st);
    }
    json_t *sw = sweeps_json(s->sweeps, id, 0);
    bool done = sweep_json_finished(sw);
    json_decref(sw);
    return done;
}

static void on_queue_change(void *ctx)
{
    connections_poke(ctx);
}

/* Holds the request without a thread until the job or sweep finishes or
 * wait_s pass (answered by answer_waited once resumed). */
enum MHD_Result suspend_request(struct http_server *s, struct MHD_Connection *c,
                                struct request *req, enum wait_kind kind, double wait_s,
                                unsigned status)
{
    if (!connections_suspend(s->conns, req->conn, kind, req->route.id, wait_s))
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "wait",
                             "the daemon is stopping; ask again once it is back");
    req->waiting = true;
    req->wait_status = status;
    return MHD_YES;
}

static enum MHD_Result answer_waited(struct http_server *s, struct MHD_Connection *c,
                                     struct request *req)
{
    req->waiting = false;
    enum wake why = connections_wake(req->conn);
    if (why == WAKE_GONE) {
        /* Nobody to answer: close. Counted in /metrics
         * (shadebench_http_waits_abandoned_total), logged at debug. */
        closing_gone_client = true;
        return MHD_NO;
    }
    if (req->ticket)
        return answer_upload(s, c, req, why);
    if (why == WAKE_STOPPING && req->wait_status == MHD_HTTP_OK)
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "wait",
                             "the daemon is stopping: the wait ended early; ask again once it "
                             "is back");
    bool sweep = req->route.kind == ROUTE_SWEEP;
    json_t *body = sweep ? served_sweep(s, req->route.id) : served_job(s, req->route.id);
    if (!body)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", sweep ? "no such sweep" : "no such job");
    return respond_json(c, req->wait_status, body);
}

static enum MHD_Result dispatch(struct http_server *s, struct MHD_Connection *c,
                                const char *method, struct request *req)
{
    bool post = strcmp(method, "POST") == 0;
    switch (req->route.kind) {
    case ROUTE_HEALTHZ:
        return respond_healthz(s, c);
    case ROUTE_INFO:
        return respond_json(c, MHD_HTTP_OK, info_json(s));
    case ROUTE_METRICS:
        return respond_metrics(s, c);
    case ROUTE_UI:
        return respond_ui(c, &req->route);
    case ROUTE_JOB_HISTORY:
        return respond_history(s, c, &req->route);
    case ROUTE_JOBS:
        if (post) {
            if (req->too_large)
                return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                                     "the job must be at most 65536 bytes");
            return submit_job(s, c, req);
        }
        /* The route allows only POST, GET and HEAD here. */
        return respond_list(s, c, ROUTE_JOBS);
    case ROUTE_SWEEPS:
        if (post) {
            if (req->too_large)
                return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                                     "the sweep must be at most 65536 bytes");
            return post_sweep(s, c, req);
        }
        return respond_list(s, c, ROUTE_SWEEPS);
    case ROUTE_ASSETS:
    case ROUTE_ASSET:
        return asset_resource(s, c, method, req);
    case ROUTE_ASSET_FIDELITY:
        return post_fidelity(s, c, req);
    case ROUTE_JOB:
    case ROUTE_JOB_REPORT:
    case ROUTE_JOB_CHART:
    case ROUTE_JOB_TIMINGS:
    case ROUTE_JOB_IMAGE:
    case ROUTE_JOB_PDIFF:
    case ROUTE_JOB_FIDELITY:
        return job_resource(s, c, method, req);
    case ROUTE_SWEEP:
    case ROUTE_SWEEP_CHART:
    case ROUTE_SWEEP_REPORT:
    case ROUTE_SWEEP_VERDICT:
        return sweep_resource(s, c, method, req);
    default:
        return respond_error(c, MHD_HTTP_NOT_FOUND, req->route.field ? req->route.field : "url",
                             req->route.message ? req->route.message : "no such route");
    }
}

struct header_scan {
    size_t bytes;
    int content_length, transfer_encoding, host;
};

static enum MHD_Result scan_header(void *cls, enum MHD_ValueKind kind, const char *key,
                                   size_t key_size, const char *value, size_t value_size)
{
    (void)kind;
    struct header_scan *h = cls;
    h->bytes += key_size + value_size + 4; /* ": " and CRLF */
    if (strcasecmp(key, "Content-Length") == 0)
        h->content_length++;
    else if (strcasecmp(key, "Transfer-Encoding") == 0)
        h->transfer_encoding++;
    else if (strcasecmp(key, "Host") == 0)
        h->host++;
    (void)value;
    return MHD_YES;
}

/* Checks made as soon as the headers are in, before any body is read:
 * answers the request (returns true) when it must be refused. */
static bool refuse_early(struct http_server *s, struct MHD_Connection *c, const char *method,
                         const char *version, struct request *req, enum MHD_Result *ret)
{
    struct header_scan h = {0};
    MHD_get_connection_values_n(c, MHD_HEADER_KIND, scan_header, &h);
    const char *te = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Transfer-Encoding");
    if (h.bytes > MAX_HEADER_BYTES) {
        *ret = respond_error(c, MHD_HTTP_REQUEST_HEADER_FIELDS_TOO_LARGE, "headers",
                             "the request's headers must be at most 8192 bytes in all");
        return true;
    }
    /* Two lengths, or a length and chunks, leave the body's end ambiguous:
     * the classic way to smuggle a second request past a proxy. */
    if (h.content_length > 1) {
        *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, "Content-Length",
                             "must appear at most once");
        return true;
    }
    if (h.transfer_encoding > 1 || (h.transfer_encoding && h.content_length) ||
        (te && strcasecmp(te, "chunked") != 0)) {
        *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, "Transfer-Encoding",
                             "must be \"chunked\" alone, once, and without Content-Length");
        return true;
    }
    /* RFC 9112: a request with more than one Host is a 400 (which one a
     * proxy routed by is anyone's guess). */
    if (h.host > 1) {
        *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, "Host", "must appear at most once");
        return true;
    }
    /* RFC 9112: an HTTP/1.1 request without Host is a 400 (a proxy's
     * host-based rules cannot apply to it). */
    if (strcmp(version, MHD_HTTP_VERSION_1_1) == 0 &&
        !MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST)) {
        *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, "Host",
                             "an HTTP/1.1 request must have a Host header");
        return true;
    }
    if (req->target_field) {
        char rule[200] = "";
        if (strcmp(req->target_field, "query") == 0)
            snprintf(rule, sizeof(rule), "%s; this one has %zu", req->target_rule,
                     req->query_args);
        else
            snprintf(rule, sizeof(rule), "%s", req->target_rule);
        *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, req->target_field, rule);
        return true;
    }
    if (connections_is_reserve(req->conn) && req->route.kind != ROUTE_HEALTHZ &&
        req->route.kind != ROUTE_METRICS) {
        char rule[200];
        snprintf(rule, sizeof(rule), "this address has its %u connections open "
                 "(--max-connections-per-ip); the %d beyond them serve /healthz and /metrics only",
                 s->limits.max_connections_per_ip, CONNECTIONS_HEALTH_RESERVE);
        *ret = respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "connections", rule);
        return true;
    }
    /* The dashboard's files hold no data: the page asks for the token. */
    if (req->route.kind != ROUTE_HEALTHZ && req->route.kind != ROUTE_UI && !authorized(s, c)) {
        *ret = respond_error(c, MHD_HTTP_UNAUTHORIZED, "Authorization",
                             "this daemon needs \"Authorization: Bearer <token>\"");
        return true;
    }
    if (req->route.kind == ROUTE_NONE) {
        *ret = dispatch(s, c, method, req);
        return true;
    }
    const char *allow, *rule;
    if (!route_method_ok(req->route.kind, method, &allow, &rule)) {
        *ret = respond_405(c, allow, rule);
        return true;
    }
    const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
    if (req->route.kind == ROUTE_ASSET && strcmp(method, "PUT") == 0)
        return begin_upload(s, c, req, cl, ret); /* the file streams to disk: its own limit */
    if (cl && strtoull(cl, NULL, 10) > JOB_MAX_BODY_BYTES) {
        /* libmicrohttpd closes the connection after this answer. */
        req->too_large = true;
        *ret = respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                             "the body must be at most 65536 bytes");
        return true;
    }
    return false;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    struct http_server *s = cls;
    struct request *req = *con_cls;
    closing_gone_client = false; /* a close that logged nothing */
    if (!req || !req->started) {
        /* The headers are in; nothing of the body has been read. */
        if (!req && !(req = calloc(1, sizeof(*req))))
            return MHD_NO;
        *con_cls = req;
        req->started = true;
        req->conn = connections_of(c);
        connections_headers_in(s->conns, req->conn);
        route_parse(url, &req->route);
        enum MHD_Result ret;
        if (refuse_early(s, c, method, version, req, &ret)) {
            connections_answering(s->conns, req->conn);
            return ret;
        }
        return MHD_YES;
    }
    if (*upload_data_size && req->upload) {
        connections_upload_bytes(s->conns, req->conn, *upload_data_size);
        assets_upload_write(req->upload, upload_data, *upload_data_size);
        *upload_data_size = 0;
        /* Past the limit (a chunked body, whose length was not known), the
         * rest is read and dropped, then answered 413: libmicrohttpd takes
         * no answer in the middle of a body. Its body deadline bounds it. */
        return MHD_YES;
    }
    if (*upload_data_size) {
        if (!req->too_large && req->len + *upload_data_size <= JOB_MAX_BODY_BYTES) {
            char *body = realloc(req->body, req->len + *upload_data_size + 1);
            if (!body)
                return MHD_NO;
            memcpy(body + req->len, upload_data, *upload_data_size);
            req->body = body;
            req->len += *upload_data_size;
            req->body[req->len] = '\0';
        } else {
            req->too_large = true;
        }
        *upload_data_size = 0;
        return MHD_YES;
    }
    if (req->waiting)
        return answer_waited(s, c, req);
    connections_answering(s->conns, req->conn);
    if (req->upload)
        return finish_upload(s, c, req);
    /* Jansson reads a NUL byte as the end of the text, so that what follows
     * it would go unread: a body is JSON text, which has none. */
    const char *nul = req->body ? memchr(req->body, '\0', req->len) : NULL;
    if (nul) {
        char rule[96];
        snprintf(rule, sizeof(rule), "must be JSON text, which has no NUL byte (one at byte %zu)",
                 (size_t)(nul - req->body));
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "body", rule);
    }
    return dispatch(s, c, method, req);
}

/* MHD_OPTION_URI_LOG_CALLBACK: the request target exactly as sent, before
 * libmicrohttpd splits off the query, stores the arguments in the
 * connection's pool and decodes them (route_check_target says why that
 * matters). What it returns is the request's *con_cls. */
static void *on_uri(void *cls, const char *uri, struct MHD_Connection *c)
{
    (void)cls, (void)c;
    struct request *req = calloc(1, sizeof(*req));
    if (!req)
        return NULL; /* on_request allocates it then, without these checks */
    route_check_target(uri, &req->query_args, &req->target_field, &req->target_rule);
    if (req->query_args > ROUTE_MAX_QUERY_ARGS) {
        /* Refused anyway: keep libmicrohttpd from filling the pool with the
         * arguments (it then answered nothing). The target is its own
         * writable read buffer, which it cuts at the '?' right after this
         * call and parses the arguments from the byte after; ending the
         * query there leaves it none to parse (libmicrohttpd 0.9.75 to
         * 1.0). */
        char *query = strchr((char *)uri, '?');
        query[1] = '\0';
    }
    return req;
}

static size_t code_index(unsigned status)
{
    for (size_t i = 0; i + 1 < NCODES; i++)
        if (COUNTED_CODES[i] == status)
            return i;
    return NCODES - 1;
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode code)
{
    (void)code;
    struct http_server *s = cls;
    struct request *req = *con_cls;
    struct conn *k = connections_of(c);
    if (req) {
        unsigned status = connections_status(k);
        if (status)
            atomic_fetch_add(&s->requests[req->route.kind][code_index(status)], 1);
        assets_upload_abort(req->upload); /* a client that went away mid-body */
        if (req->ticket && s->ctx.assets)
            assets_ticket_drop(s->ctx.assets, req->ticket);
        free(req->body);
        free(req);
        *con_cls = NULL;
    }
    connections_request_done(s->conns, k);
}

/* libmicrohttpd logs per connection (one refused for the per-address
 * limit, one that failed to send): a client could write the log full. At
 * most MHD_LOG_BURST of its warnings go out each MHD_LOG_WINDOW_S; the rest
 * are counted, and the count logged when the next window opens. */
enum { MHD_LOG_BURST = 20, MHD_LOG_WINDOW_S = 10 };
static pthread_mutex_t mhd_log_lock = PTHREAD_MUTEX_INITIALIZER;
static double mhd_log_window;
static unsigned mhd_log_count;

static bool mhd_log_allowed(void)
{
    double now = clock_mono_s();
    unsigned suppressed = 0;
    pthread_mutex_lock(&mhd_log_lock);
    if (now - mhd_log_window >= MHD_LOG_WINDOW_S) {
        suppressed = mhd_log_count > MHD_LOG_BURST ? mhd_log_count - MHD_LOG_BURST : 0;
        mhd_log_window = now;
        mhd_log_count = 0;
    }
    bool allowed = ++mhd_log_count <= MHD_LOG_BURST;
    pthread_mutex_unlock(&mhd_log_lock);
    if (suppressed)
        LOG(LOG_WARN, "libmicrohttpd: %u more messages in %d s were not logged", suppressed,
            MHD_LOG_WINDOW_S);
    return allowed;
}

static void on_mhd_log(void *cls, const char *fmt, va_list ap)
{
    (void)cls;
    char msg[512];
    vsnprintf(msg, sizeof(msg), fmt, ap);
    size_t n = strlen(msg);
    while (n && msg[n - 1] == '\n')
        msg[--n] = '\0';
    bool expected = closing_gone_client && strstr(msg, "internal error");
    closing_gone_client = false;
    if (expected)
        LOG(LOG_DEBUG, "libmicrohttpd: %s (a waiting client hung up)", msg);
    else if (mhd_log_allowed())
        LOG(LOG_WARN, "libmicrohttpd: %s", msg);
}

struct http_server *http_server_create(const char *listen, const struct http_limits *limits,
                                       const struct http_context *ctx, char *err,
                                       size_t errlen)
{
    char host[256];
    const char *colon = strrchr(listen, ':');
    if (!colon || colon == listen) {
        snprintf(err, errlen, "--listen %s: expected HOST:PORT", listen);
        return NULL;
    }
    const char *h = listen;
    size_t hlen = (size_t)(colon - listen);
    if (h[0] == '[' && hlen >= 2 && h[hlen - 1] == ']')
        h++, hlen -= 2;
    if (hlen >= sizeof(host)) {
        snprintf(err, errlen, "--listen %s: host too long", listen);
        return NULL;
    }
    memcpy(host, h, hlen);
    host[hlen] = '\0';
    char *end;
    long port = strtol(colon + 1, &end, 10);
    if (*end || end == colon + 1 || port < 0 || port > 65535) {
        snprintf(err, errlen, "--listen %s: port must be 0 to 65535", listen);
        return NULL;
    }
    struct addrinfo hints = {.ai_family = AF_UNSPEC, .ai_socktype = SOCK_STREAM,
                             .ai_flags = AI_PASSIVE};
    struct addrinfo *ai = NULL;
    int gai = getaddrinfo(host, colon + 1, &hints, &ai);
    if (gai != 0) {
        snprintf(err, errlen, "--listen %s: %s", listen, gai_strerror(gai));
        return NULL;
    }
    struct http_server *s = calloc(1, sizeof(*s));
    if (!s) {
        freeaddrinfo(ai);
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    s->ctx = *ctx;
    s->queue = ctx->queue;
    s->sweeps = ctx->sweeps;
    s->limits = *limits;
    pthread_mutex_init(&s->token_lock, NULL);
    struct connections_config cc = {.header_s = limits->header_timeout_s,
                                    .body_s = limits->body_timeout_s,
                                    .per_ip = limits->max_connections_per_ip,
                                    .uploads_per_ip = limits->uploads_per_ip,
                                    .upload_min_rate = limits->upload_min_rate,
                                    .upload_window_s = limits->upload_window_s};
    s->conns = connections_create(&cc, wait_done, s, err, errlen);
    if (!s->conns) {
        freeaddrinfo(ai);
        pthread_mutex_destroy(&s->token_lock);
        free(s);
        return NULL;
    }
    /* Event-driven: a small pool of polling threads serves every connection,
     * and a long-poll is a suspended connection, not a blocked thread. */
    unsigned flags = MHD_USE_AUTO_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ERROR_LOG;
    if (ai->ai_family == AF_INET6)
        flags |= MHD_USE_IPv6;
    s->mhd = MHD_start_daemon(
        flags, (uint16_t)port, NULL, NULL, on_request, s, MHD_OPTION_EXTERNAL_LOGGER, on_mhd_log,
        s, MHD_OPTION_SOCK_ADDR, ai->ai_addr, MHD_OPTION_THREAD_POOL_SIZE,
        (unsigned)(limits->threads ? limits->threads : 1), MHD_OPTION_CONNECTION_LIMIT,
        (unsigned)limits->max_connections, MHD_OPTION_PER_IP_CONNECTION_LIMIT,
        (unsigned)(limits->max_connections_per_ip + CONNECTIONS_HEALTH_RESERVE),
        MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)limits->idle_timeout_s, MHD_OPTION_CONNECTION_MEMORY_LIMIT,
        (size_t)CONNECTION_MEMORY, MHD_OPTION_NOTIFY_CONNECTION, connections_notify, s->conns,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, s, MHD_OPTION_URI_LOG_CALLBACK, on_uri, s,
        MHD_OPTION_END);
    freeaddrinfo(ai);
    if (!s->mhd) {
        snprintf(err, errlen, "cannot listen on %s (address in use or not allowed?)", listen);
        connections_destroy(s->conns);
        pthread_mutex_destroy(&s->token_lock);
        free(s);
        return NULL;
    }
    queue_set_listener(s->queue, on_queue_change, s->conns);
    if (s->ctx.assets)
        assets_set_listener(s->ctx.assets, on_queue_change, s->conns);
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(s->mhd, MHD_DAEMON_INFO_BIND_PORT);
    s->port = info ? info->port : (int)port;
    return s;
}

void http_server_destroy(struct http_server *s)
{
    if (!s)
        return;
    connections_stop(s->conns, STOP_GRACE_S);
    queue_set_listener(s->queue, NULL, NULL);
    if (s->ctx.assets)
        assets_set_listener(s->ctx.assets, NULL, NULL);
    MHD_stop_daemon(s->mhd);
    connections_destroy(s->conns);
    pthread_mutex_destroy(&s->token_lock);
    free(s->token);
    free(s);
}

size_t http_server_open_connections(struct http_server *s)
{
    struct connections_stats cs;
    connections_stats(s->conns, &cs);
    return cs.open;
}

int http_server_port(const struct http_server *s) { return s->port; }
