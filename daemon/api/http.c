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

#include "config.h"
#include "common/clock.h"
#include "common/job_files.h"
#include "common/log.h"
#include "daemon/api/charts.h"
#include "daemon/api/connections.h"
#include "daemon/api/links.h"
#include "daemon/api/report.h"
#include "daemon/api/routes.h"
#include "daemon/harness/telemetry.h"
#include "daemon/jobs/job_cost.h"
#include "daemon/jobs/job_eta.h"
#include "daemon/jobs/job_spec.h"
#include "daemon/quality/metrics.h"
#include "daemon/api/job_filter.h"
#include "daemon/jobs/sweep_spec.h"
#include "common/result_keys.h"

#ifndef MHD_HTTP_CONTENT_TOO_LARGE
#define MHD_HTTP_CONTENT_TOO_LARGE 413
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

/* The status codes the request counters of /metrics keep apart. */
static const unsigned COUNTED_CODES[] = {200, 201, 202, 400, 401, 403, 404, 405, 409, 413,
                                         422, 429, 431, 500, 503, 507, 0 /* other */};
enum { NCODES = sizeof(COUNTED_CODES) / sizeof(COUNTED_CODES[0]) };

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

void http_limits_defaults(struct http_limits *l)
{
    l->max_connections = 4096;
    l->max_connections_per_ip = 64;
    l->threads = 4;
    l->header_timeout_s = 10;
    l->body_timeout_s = 30;
    l->idle_timeout_s = 30;
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
        const char *auth = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Authorization");
        ok = auth && strncmp(auth, "Bearer ", 7) == 0 && token_matches(auth + 7, s->token);
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

/* Set by answer_waited just before it closes the connection of a client
 * that hung up, and read by on_mhd_log, which libmicrohttpd calls at once
 * on the same thread: its "internal error" line is then the expected end
 * of a wait, not an error (2,000 waits hung up made 2,000 warnings). */
static _Thread_local bool closing_gone_client;

static enum MHD_Result respond_text(struct MHD_Connection *c, unsigned status,
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
    connections_set_status(connections_of(c), status);
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

/* Takes ownership of body. A body that cannot be built or printed still
 * gets an answer: a fixed 500. */
static enum MHD_Result respond_json(struct MHD_Connection *c, unsigned status, json_t *body)
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

static enum MHD_Result respond_error(struct MHD_Connection *c, unsigned status,
                                     const char *field, const char *message)
{
    struct job_error e;
    snprintf(e.field, sizeof(e.field), "%s", field);
    snprintf(e.message, sizeof(e.message), "%s", message);
    return respond_json(c, status, job_error_to_json(&e));
}

/* An asset's refusal (assets.h): its message may be longer than a job
 * error's 256 bytes (it can name a path). */
static enum MHD_Result respond_asset_error(struct MHD_Connection *c, const struct assets_error *e)
{
    return respond_json(c, e->status ? e->status : MHD_HTTP_INTERNAL_SERVER_ERROR,
                        json_pack("{s:{s:s, s:s}}", "error", "field", e->field[0] ? e->field : "body",
                                  "message", e->message));
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

static enum MHD_Result respond_file(struct MHD_Connection *c, const char *path,
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

double http_memory_bytes(const struct http_limits *l)
{
    /* libmicrohttpd's per-connection pool plus a body buffer, per
     * connection, at the connection limit (a health check's reserve too). */
    return (double)l->max_connections * (CONNECTION_MEMORY + JOB_MAX_BODY_BYTES);
}

/* The daemon's memory budget (--memory-budget), by part: the driver and
 * libraries as measured at start, the connections at their limit, and what
 * is left for one job, which each job's estimate must fit (job_cost.h);
 * rss_bytes is the resident set now, the driver's allocations included. */
static json_t *memory_json(const struct http_server *s, double *total)
{
    const double side = 8192.0, frame = side * side * 4.0;
    double http = http_memory_bytes(&s->limits), job = job_cost_memory_limit();
    *total = s->ctx.memory_budget_bytes > 0 ? s->ctx.memory_budget_bytes
                                            : s->ctx.driver_bytes + http + job;
    /* What the API's own limits let a job's buffers reach, for scale: its
     * captures (bounded per job), a read-back frame and its per-frame
     * series, and the metrics stage at the largest image. */
    double captures = JOB_MAX_CAPTURE_BYTES, render = frame + 1e6 * 3 * sizeof(double);
    double metrics = metrics_memory_bytes(8192, 8192, 1000.0);
    return json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:s}", "budget_bytes", *total,
                     "driver_bytes", s->ctx.driver_bytes, "http_bytes", http, "job_bytes", job,
                     "rss_bytes", telemetry_rss_bytes(), "captures_bytes", captures,
                     "render_bytes", render, "metrics_bytes", metrics, "rule",
                     "budget_bytes = driver_bytes (the daemon's resident set at start, the GL "
                     "context up: driver, shader compiler, libraries) + http_bytes (every "
                     "connection's buffers) + job_bytes (what one job may take: a job whose "
                     "estimate, its answer's cost.memory_bytes, is over it is refused)");
}

static json_t *info_json(struct http_server *s)
{
    double total;
    json_t *memory = memory_json(s, &total);
    /* From the GL-free catalogue: HTTP threads never touch GL. */
    json_t *techs = technique_catalog_json(s->ctx.catalog);
    const struct http_limits *l = &s->limits;
    json_t *info = json_pack("{s:s, s:s, s:s, s:o, s:o, s:o, s:o, s:o, s:{s:i, s:i, s:i, s:I, s:I, s:f, "
                     "s:f, s:I, s:f, s:f, s:I, s:I}}",
                     "name", "shadebenchd", "version", PACKAGE_VERSION, "api", "v1", "memory",
                     memory, "device",
                     s->ctx.device_json(s->ctx.render), "techniques", techs,
                     "effects", effect_catalog_json(), /* post hook: look.post's effects */
                     "sweepable", sweep_params_json(s->ctx.catalog), "limits",
                     "max_body_bytes", JOB_MAX_BODY_BYTES, "max_queued_jobs",
                     queue_max_queued(s->queue), "max_wait_s", MAX_WAIT_S, "max_connections",
                     (json_int_t)l->max_connections, "max_connections_per_ip",
                     (json_int_t)l->max_connections_per_ip, "header_timeout_s",
                     l->header_timeout_s, "body_timeout_s", l->body_timeout_s,
                     "max_token_bytes", (json_int_t)HTTP_MAX_TOKEN_BYTES, "default_job_timeout_s",
                     job_spec_default_timeout(), "max_job_seconds", job_spec_max_seconds(),
                     "max_captures",
                     (json_int_t)JOB_MAX_CAPTURES, "max_image_pixels", (json_int_t)IMAGE_MAX_PIXELS);
    /* The asset limits (assets.h): the upload's body limit, the converter's
     * limits on what an asset may hold, and its memory, CPU and time. */
    json_t *limits = json_object_get(info, "limits");
    /* The bound on one whole frame (measure.c): over it, a job fails before
     * timing unless it accepts sliced timing. */
    json_object_set_new(limits, "max_frame_seconds", json_real(job_spec_max_frame_seconds()));
    if (limits && s->ctx.assets) {
        json_t *assets = assets_info_json(s->ctx.assets);
        json_object_set(limits, "max_asset_bytes", json_object_get(assets, "max_asset_bytes"));
        json_object_set_new(limits, "assets", assets);
    }
    return info;
}

/* The render thread's state as /healthz shows it. */
static json_t *render_json(const struct render_state *st, double stall_s)
{
    if (!st->alive)
        return json_pack("{s:s}", "state", "stopped");
    if (!st->busy)
        return json_pack("{s:s, s:f}", "state", "idle", "idle_s", st->since_progress_s);
    /* A job that ended early is drained, not rendered: its state is final. */
    return json_pack("{s:s, s:s, s:s, s:f, s:f, s:f}", "state",
                     render_state_stalled(st, stall_s) ? "stalled"
                     : render_state_draining(st)        ? "draining"
                                                        : "busy",
                     "job", st->job,
                     "phase", st->phase, "busy_s", st->busy_s, "since_progress_s",
                     st->since_progress_s, "stall_seconds", stall_s);
}

/* GET /healthz: cheap (no store, no lock), and true: 503 when the render
 * thread has stopped, or has made no progress for longer than the bound
 * while a job is on it, which no other endpoint would show (a job that
 * holds the GPU for minutes still left every other answer quick). */
static enum MHD_Result respond_healthz(struct http_server *s, struct MHD_Connection *c)
{
    struct render_state st;
    s->ctx.render_state(s->ctx.render, &st);
    json_t *render = render_json(&st, s->ctx.stall_s);
    if (!st.alive)
        return respond_json(c, MHD_HTTP_SERVICE_UNAVAILABLE,
                            json_pack("{s:s, s:o}", "status", "render thread is not running",
                                      "render", render));
    if (render_state_stalled(&st, s->ctx.stall_s)) {
        char msg[256];
        snprintf(msg, sizeof(msg), "the render thread has made no progress for %.0f s (more "
                 "than --stall-seconds %g) on job %s, phase %s", st.since_progress_s,
                 s->ctx.stall_s, st.job, st.phase);
        return respond_json(c, MHD_HTTP_SERVICE_UNAVAILABLE,
                            json_pack("{s:s, s:s, s:o}", "status", "stalled", "message", msg,
                                      "render", render));
    }
    return respond_json(c, MHD_HTTP_OK, json_pack("{s:s, s:o}", "status", "ok", "render", render));
}

/* Label values in the text format: a backslash, a quote and a newline are
 * escaped. A job id and a phase have none, but say so in one place. */
static void prometheus_label(FILE *f, const char *v)
{
    for (; v && *v; v++) {
        if (*v == '\\' || *v == '"')
            fputc('\\', f);
        if (*v == '\n')
            fputs("\\n", f);
        else
            fputc(*v, f);
    }
}

static void render_metrics(struct http_server *s, FILE *f)
{
    struct render_state st;
    s->ctx.render_state(s->ctx.render, &st);
    fprintf(f, "# HELP shadebench_render_up Whether the render thread runs.\n"
               "# TYPE shadebench_render_up gauge\n"
               "shadebench_render_up %d\n", st.alive);
    fprintf(f, "# HELP shadebench_render_busy Whether a job is on the render thread.\n"
               "# TYPE shadebench_render_busy gauge\n"
               "shadebench_render_busy %d\n", st.busy);
    fprintf(f, "# HELP shadebench_render_seconds_since_progress Seconds since the render thread "
               "last made progress (a frame, a slice of GPU work, a metric tile, a phase); 0 "
               "while idle.\n"
               "# TYPE shadebench_render_seconds_since_progress gauge\n"
               "shadebench_render_seconds_since_progress %.3f\n",
            st.busy ? st.since_progress_s : 0.0);
    fprintf(f, "# HELP shadebench_render_stalled Whether /healthz reports the render thread "
               "stalled (busy, no progress for longer than shadebench_render_stall_seconds).\n"
               "# TYPE shadebench_render_stalled gauge\n"
               "shadebench_render_stalled %d\n"
               "# HELP shadebench_render_stall_seconds The stall bound (--stall-seconds; 0: "
               "none).\n"
               "# TYPE shadebench_render_stall_seconds gauge\n"
               "shadebench_render_stall_seconds %g\n",
            render_state_stalled(&st, s->ctx.stall_s), s->ctx.stall_s);
    if (st.busy) {
        fprintf(f, "# HELP shadebench_render_job The job on the render thread and its phase.\n"
                   "# TYPE shadebench_render_job gauge\n"
                   "shadebench_render_job{job=\"");
        prometheus_label(f, st.job);
        fprintf(f, "\",phase=\"");
        prometheus_label(f, st.phase);
        fprintf(f, "\"} 1\n");
    }
}

/* GET /metrics: Prometheus text format 0.0.4. */
static enum MHD_Result respond_metrics(struct http_server *s, struct MHD_Connection *c)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "metrics", "out of memory");
    size_t counts[JOB_STATUS_COUNT];
    if (!queue_counts(s->queue, counts)) {
        fclose(f);
        free(text);
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "metrics",
                             "cannot read the store (see the log)");
    }
    fprintf(f, "# HELP shadebench_jobs Jobs in the store, by status.\n"
               "# TYPE shadebench_jobs gauge\n");
    for (int k = JOB_QUEUED; k <= JOB_INTERRUPTED; k++)
        fprintf(f, "shadebench_jobs{status=\"%s\"} %zu\n", job_status_name((enum job_status)k),
                counts[k]);
    fprintf(f, "# HELP shadebench_queue_depth Jobs waiting for the render thread.\n"
               "# TYPE shadebench_queue_depth gauge\n"
               "shadebench_queue_depth %zu\n", counts[JOB_QUEUED]);
    fprintf(f, "# HELP shadebench_queue_capacity Jobs that may wait at once.\n"
               "# TYPE shadebench_queue_capacity gauge\n"
               "shadebench_queue_capacity %d\n", queue_max_queued(s->queue));
    fprintf(f, "# HELP shadebench_state_disk_full Whether the state directory's disk is full: "
               "no job starts and none is accepted until there is room (docs/store.md).\n"
               "# TYPE shadebench_state_disk_full gauge\n"
               "shadebench_state_disk_full %d\n", store_disk_full(queue_store(s->queue)));
    struct telemetry t;
    telemetry_read(&t);
    fprintf(f, "# HELP shadebench_frames_rendered_total Frames rendered for jobs (warm-up and timed).\n"
               "# TYPE shadebench_frames_rendered_total counter\n"
               "shadebench_frames_rendered_total %llu\n", t.frames);
    render_metrics(s, f);
    fprintf(f, "# HELP shadebench_render_busy_seconds_total Seconds the render thread spent on jobs.\n"
               "# TYPE shadebench_render_busy_seconds_total counter\n"
               "shadebench_render_busy_seconds_total %.6f\n", t.render_busy_s);
    fprintf(f, "# HELP shadebench_metrics_seconds_total Seconds the metrics stage spent scoring captures.\n"
               "# TYPE shadebench_metrics_seconds_total counter\n"
               "shadebench_metrics_seconds_total %.6f\n", t.metrics_s);
    fprintf(f, "# HELP shadebench_metrics_captures_total Captures scored against their reference.\n"
               "# TYPE shadebench_metrics_captures_total counter\n"
               "shadebench_metrics_captures_total %llu\n", t.captures_scored);
    struct connections_stats cs;
    connections_stats(s->conns, &cs);
    fprintf(f, "# HELP shadebench_http_long_polls Requests suspended in a wait (?wait= or a cancel).\n"
               "# TYPE shadebench_http_long_polls gauge\n"
               "shadebench_http_long_polls %zu\n", cs.waiting);
    fprintf(f, "# HELP shadebench_http_connections Open HTTP connections.\n"
               "# TYPE shadebench_http_connections gauge\n"
               "shadebench_http_connections %zu\n", cs.open);
    fprintf(f, "# HELP shadebench_http_connections_cut_total Connections shut for headers or a body "
               "later than their deadline.\n"
               "# TYPE shadebench_http_connections_cut_total counter\n"
               "shadebench_http_connections_cut_total{phase=\"headers\"} %llu\n"
               "shadebench_http_connections_cut_total{phase=\"body\"} %llu\n",
            cs.header_timeouts, cs.body_timeouts);
    fprintf(f, "# HELP shadebench_http_waits_abandoned_total Waits ended because their client hung up.\n"
               "# TYPE shadebench_http_waits_abandoned_total counter\n"
               "shadebench_http_waits_abandoned_total %llu\n", cs.waits_gone);
    fprintf(f, "# HELP shadebench_http_requests_total HTTP requests answered, by route and status code.\n"
               "# TYPE shadebench_http_requests_total counter\n");
    for (int r = 0; r < ROUTE_COUNT; r++)
        for (size_t k = 0; k < NCODES; k++) {
            unsigned long long n = atomic_load(&s->requests[r][k]);
            if (n == 0)
                continue;
            char code[8];
            snprintf(code, sizeof(code), COUNTED_CODES[k] ? "%u" : "other", COUNTED_CODES[k]);
            fprintf(f, "shadebench_http_requests_total{route=\"%s\",code=\"%s\"} %llu\n",
                    route_label((enum route_kind)r), code, n);
        }
    double budget;
    json_decref(memory_json(s, &budget));
    fprintf(f, "# HELP shadebench_memory_budget_bytes The daemon's memory budget (parts in /v1/info).\n"
               "# TYPE shadebench_memory_budget_bytes gauge\n"
               "shadebench_memory_budget_bytes %.0f\n"
               "# HELP shadebench_memory_rss_bytes The daemon's resident set (the GL driver's "
               "allocations included).\n"
               "# TYPE shadebench_memory_rss_bytes gauge\n"
               "shadebench_memory_rss_bytes %.0f\n", budget, telemetry_rss_bytes());
    if (fclose(f) != 0 || !text) {
        free(text);
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "metrics", "out of memory");
    }
    return respond_text(c, MHD_HTTP_OK, text, len, "text/plain; version=0.0.4; charset=utf-8");
}

static enum MHD_Result submit_job(struct http_server *s, struct MHD_Connection *c,
                                  struct request *req)
{
    struct job_spec spec;
    struct job_error err;
    if (!job_spec_parse_text(req->body ? req->body : "", req->len, s->ctx.catalog,
                             &spec, &err))
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    /* scene.asset: pinned to the stored asset's hash here, so that the
     * answer names the rule (400 unknown, 409 a different pinned hash);
     * queue_submit resolves again, for the sweeps' points. */
    if (spec.scene.asset[0]) {
        struct assets_error ae;
        if (!s->ctx.assets)
            return respond_error(c, MHD_HTTP_BAD_REQUEST, "scene.asset",
                                 "this daemon has no asset store");
        if (!assets_resolve(s->ctx.assets, &spec.scene, &ae))
            return respond_asset_error(c, &ae);
    }
    /* Its duration on this device, where a job of its technique has run: a
     * projection far past its timeout_s (or a frame far past the frame
     * bound) is refused with the figures (job_eta.h). */
    struct job_eta eta;
    job_eta_estimate(&spec, &eta);
    if (!job_eta_admit(&spec, &eta, &err))
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    char id[24];
    switch (queue_submit(s->queue, &spec, NULL, id)) {
    case QUEUE_OK:
        break;
    case QUEUE_REFUSED: /* the asset changed since: its rule */
        return respond_error(c, MHD_HTTP_CONFLICT, "scene.asset", queue_submit_error());
    case QUEUE_FULL: {
        char msg[96];
        snprintf(msg, sizeof(msg), "the queue is full (%d jobs waiting); retry later",
                 queue_max_queued(s->queue));
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "body", msg);
    }
    case QUEUE_STOPPING:
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "body", "the daemon is stopping");
    default: /* QUEUE_IO_ERROR: not persisted, so not accepted */
        return respond_error(c, MHD_HTTP_INSUFFICIENT_STORAGE, "state_dir", queue_submit_error());
    }
    char url[ROUTE_URL_MAX];
    route_job_url(id, url);
    LOG(LOG_INFO, "queued job %s (%s)", id, spec.technique);
    struct job_cost cost;
    job_cost_estimate(&spec, &cost);
    return respond_json(c, MHD_HTTP_ACCEPTED,
                        json_pack("{s:s, s:s, s:s, s:o, s:o}", "id", id, "status", "queued", "url",
                                  url, "cost", job_cost_json(&cost), "estimate",
                                  job_eta_json(&eta)));
}

static bool parse_wait(struct MHD_Connection *c, double *wait)
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

static enum MHD_Result respond_chart(struct MHD_Connection *c, const json_t *subject,
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

struct list_args {
    struct store_query query;
    struct job_error err;
    bool ok;
};

static enum MHD_Result list_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                const char *value)
{
    (void)kind;
    struct list_args *a = cls;
    a->ok = a->ok && job_filter_add(&a->query, key, value, &a->err);
    return a->ok ? MHD_YES : MHD_NO;
}

/* GET /v1/jobs and GET /v1/sweeps: a page, with the link to the next one.
 * Jobs take filters (?technique=&status=&label.KEY=VALUE&since=), both
 * take ?limit=&cursor= (daemon/api/job_filter.h). */
static enum MHD_Result respond_list(struct http_server *s, struct MHD_Connection *c,
                                    enum route_kind route)
{
    struct list_args *a = calloc(1, sizeof(*a));
    if (!a)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "url", "out of memory");
    a->ok = true;
    job_filter_init(&a->query, route == ROUTE_SWEEPS ? STORE_SWEEPS : STORE_JOBS);
    MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, list_arg, a);
    if (!a->ok) {
        json_t *body = job_error_to_json(&a->err);
        free(a);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, body);
    }
    /* The error goes in a 256-byte message (respond_error): logged whole. */
    char next[RECORD_ID_LEN], err[240];
    json_t *list = route == ROUTE_SWEEPS
                       ? sweeps_list_page(s->sweeps, &a->query, next, err, sizeof(err))
                       : queue_list_page(s->queue, &a->query, next, err, sizeof(err));
    if (!list) {
        free(a);
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "store", err);
    }
    if (route == ROUTE_SWEEPS)
        links_add_sweep_list(list);
    else
        links_add_job_list(list);
    links_add_next(list, route, &a->query, next);
    free(a);
    return respond_json(c, MHD_HTTP_OK, list);
}

static bool point_job_dir(void *ctx, const char *job_id, char *dir, size_t cap, int *last_frame)
{
    struct http_server *s = ctx;
    enum job_status status;
    if (!queue_job_dir(s->queue, job_id, dir, cap, &status))
        return false;
    json_t *job = queue_job_json(s->queue, job_id, 0);
    json_t *caps = json_object_get(json_object_get(job, RK_RESULT), RK_CAPTURES);
    *last_frame = (int)json_integer_value(json_object_get(json_array_get(caps, json_array_size(caps) - 1), "frame"));
    json_decref(job);
    return true;
}

static enum MHD_Result respond_html(struct MHD_Connection *c, char *html, size_t len)
{
    if (!html)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "report", "out of memory");
    return respond_text(c, MHD_HTTP_OK, html, len, "text/html; charset=utf-8");
}

/* A job or sweep as the API serves it: the stored JSON plus its URLs. */
static json_t *served_job(struct http_server *s, const char *id)
{
    json_t *job = queue_job_json(s->queue, id, 0);
    links_add_job(job);
    return job;
}

static json_t *served_sweep(struct http_server *s, const char *id)
{
    json_t *sw = sweeps_json(s->sweeps, id, 0);
    links_add_sweep(sw);
    return sw;
}

static bool finished_status(enum job_status st)
{
    return st != JOB_QUEUED && st != JOB_RUNNING;
}

static bool sweep_finished(const json_t *sw)
{
    const char *st = json_string_value(json_object_get(sw, "status"));
    return !st || (strcmp(st, "queued") != 0 && strcmp(st, "running") != 0);
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
        return !queue_job_dir(s->queue, id, dir, sizeof(dir), &st) || finished_status(st);
    }
    json_t *sw = sweeps_json(s->sweeps, id, 0);
    bool done = sweep_finished(sw);
    json_decref(sw);
    return done;
}

static void on_queue_change(void *ctx)
{
    connections_poke(ctx);
}

/* Holds the request without a thread until the job or sweep finishes or
 * wait_s pass (answered by answer_waited once resumed). */
static enum MHD_Result suspend(struct http_server *s, struct MHD_Connection *c,
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
    if (req->ticket) {
        unsigned status;
        json_t *body;
        if (s->ctx.assets && assets_ticket_take(s->ctx.assets, req->ticket, &status, &body)) {
            req->ticket = 0;
            return respond_json(c, status, body);
        }
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "body",
                             why == WAKE_TIMEOUT ? "the conversion is still waiting or running "
                                                   "past its time; GET /v1/assets/NAME later"
                                                 : "the daemon is stopping: the upload was not "
                                                   "converted; upload it again once it is back");
    }
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

static enum MHD_Result job_resource(struct http_server *s, struct MHD_Connection *c,
                                    const char *method, struct request *req)
{
    const struct route *r = &req->route;
    bool get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
    char dir[PATH_MAX], path[PATH_MAX + 64];
    enum job_status status;

    if (r->kind == ROUTE_JOB && get) {
        double wait;
        if (!parse_wait(c, &wait))
            return respond_error(c, MHD_HTTP_BAD_REQUEST, "wait",
                                 "must be a number of seconds from 0 to 3600");
        if (!queue_job_dir(s->queue, r->id, dir, sizeof(dir), &status))
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        if (wait > 0 && !finished_status(status))
            return suspend(s, c, req, WAIT_JOB, wait, MHD_HTTP_OK);
        json_t *job = served_job(s, r->id);
        if (!job)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        return respond_json(c, MHD_HTTP_OK, job);
    }
    if (r->kind == ROUTE_JOB) { /* DELETE */
        switch (queue_cancel(s->queue, r->id)) {
        case CANCEL_NOT_FOUND:
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        case CANCEL_FINISHED:
            return respond_error(c, MHD_HTTP_CONFLICT, "id", "the job has already finished");
        case CANCEL_DONE:
            return respond_json(c, MHD_HTTP_OK, served_job(s, r->id));
        case CANCEL_REQUESTED:
            /* The job stops at its next frame or metric tile; give it a moment
             * so that the answer usually shows the final state. */
            return suspend(s, c, req, WAIT_JOB, CANCEL_WAIT_S, MHD_HTTP_ACCEPTED);
        }
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "id", "unexpected cancel result");
    }
    if (r->kind == ROUTE_JOB_REPORT) {
        json_t *job = queue_job_json(s->queue, r->id, 0);
        if (!job || !queue_job_dir(s->queue, r->id, dir, sizeof(dir), &status)) {
            json_decref(job);
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        }
        json_t *device = s->ctx.device_json(s->ctx.render);
        size_t len = 0;
        char *html = report_job_html(job, dir, device, &len);
        json_decref(device);
        json_decref(job);
        return respond_html(c, html, len);
    }
    if (r->kind == ROUTE_JOB_CHART) {
        json_t *job = queue_job_json(s->queue, r->id, 0);
        if (!job)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        enum MHD_Result ret =
            json_object_get(job, RK_RESULT)
                ? respond_chart(c, job, r, false, NULL)
                : respond_error(c, MHD_HTTP_CONFLICT, "id", "the job has no result yet");
        json_decref(job);
        return ret;
    }
    /* Files: timings.csv and the per-capture images. */
    if (!queue_job_dir(s->queue, r->id, dir, sizeof(dir), &status))
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    if (status != JOB_DONE)
        return respond_error(c, MHD_HTTP_CONFLICT, "id",
                             "the job has not finished: its files exist once it is done");
    if (r->kind == ROUTE_JOB_TIMINGS) {
        job_file_path(dir, JOB_FILE_TIMINGS, path, sizeof(path));
        return respond_file(c, path, "text/csv");
    }
    job_image_path(dir, r->image, r->frame, path, sizeof(path));
    if (access(path, R_OK) != 0)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "frame",
                             "no such image: this frame was not captured, or the job has no "
                             "reference or that metric (see result.captures)");
    return respond_file(c, path, "image/png");
}

static enum MHD_Result post_sweep(struct http_server *s, struct MHD_Connection *c,
                                  struct request *req)
{
    json_error_t jerr;
    json_t *body = json_loadb(req->body ? req->body : "", req->len, JSON_REJECT_DUPLICATES, &jerr);
    if (!body) {
        struct job_error e;
        job_error_set(&e, "body", "malformed JSON at line %d, column %d: %s", jerr.line,
                      jerr.column, jerr.text);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&e));
    }
    struct sweep_spec spec;
    struct job_error err;
    if (!sweep_spec_parse(body, s->ctx.catalog, &spec, &err)) {
        sweep_spec_finish(&spec);
        json_decref(body);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    }
    /* A sweep on an asset: refused now rather than at its first point (each
     * point is pinned to the asset's hash when the sweep submits it). */
    const json_t *asset = json_object_get(json_object_get(spec.base, "scene"), "asset");
    if (json_is_string(asset)) {
        struct scene_spec probe;
        struct assets_error ae;
        memset(&probe, 0, sizeof(probe));
        snprintf(probe.asset, sizeof(probe.asset), "%s", json_string_value(asset));
        if (!s->ctx.assets || !assets_resolve(s->ctx.assets, &probe, &ae)) {
            sweep_spec_finish(&spec);
            json_decref(body);
            if (s->ctx.assets)
                snprintf(ae.field, sizeof(ae.field), "base.scene.asset");
            return s->ctx.assets ? respond_asset_error(c, &ae)
                                 : respond_error(c, MHD_HTTP_BAD_REQUEST, "base.scene.asset",
                                                 "this daemon has no asset store");
        }
    }
    char id[24];
    enum queue_submit_result r = sweeps_submit(s->sweeps, &spec, body, id);
    sweep_spec_finish(&spec);
    json_decref(body);
    if (r == QUEUE_IO_ERROR) /* not persisted, so not accepted */
        return respond_error(c, MHD_HTTP_INSUFFICIENT_STORAGE, "state_dir", queue_submit_error());
    if (r != QUEUE_OK)
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "body",
                             "too many sweeps are waiting; retry later");
    char url[ROUTE_URL_MAX];
    route_sweep_url(id, url);
    return respond_json(c, MHD_HTTP_ACCEPTED,
                        json_pack("{s:s, s:s, s:s}", "id", id, "status", "queued", "url", url));
}

static enum MHD_Result sweep_resource(struct http_server *s, struct MHD_Connection *c,
                                      const char *method, struct request *req)
{
    const struct route *r = &req->route;
    bool get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
    if (r->kind == ROUTE_SWEEP && get) {
        double wait;
        if (!parse_wait(c, &wait))
            return respond_error(c, MHD_HTTP_BAD_REQUEST, "wait",
                                 "must be a number of seconds from 0 to 3600");
        json_t *sw = sweeps_json(s->sweeps, r->id, 0);
        if (!sw)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
        if (wait > 0 && !sweep_finished(sw)) {
            json_decref(sw);
            return suspend(s, c, req, WAIT_SWEEP, wait, MHD_HTTP_OK);
        }
        links_add_sweep(sw);
        return respond_json(c, MHD_HTTP_OK, sw);
    }
    if (r->kind == ROUTE_SWEEP) { /* DELETE */
        switch (sweeps_cancel(s->sweeps, r->id)) {
        case CANCEL_NOT_FOUND:
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
        case CANCEL_FINISHED:
            return respond_error(c, MHD_HTTP_CONFLICT, "id", "the sweep has already finished");
        case CANCEL_DONE:
            return respond_json(c, MHD_HTTP_OK, served_sweep(s, r->id));
        case CANCEL_REQUESTED:
            return suspend(s, c, req, WAIT_SWEEP, CANCEL_WAIT_S, MHD_HTTP_ACCEPTED);
        }
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "id", "unexpected cancel result");
    }
    json_t *sw = sweeps_json(s->sweeps, r->id, 0);
    if (!sw)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
    enum MHD_Result ret;
    if (r->kind == ROUTE_SWEEP_CHART) {
        json_t *device = s->ctx.device_json(s->ctx.render);
        ret = respond_chart(c, sw, r, true, device);
        json_decref(device);
    } else {
        json_t *device = s->ctx.device_json(s->ctx.render);
        size_t len = 0;
        char *html = report_sweep_html(sw, device, point_job_dir, s, &len);
        json_decref(device);
        ret = respond_html(c, html, len);
    }
    json_decref(sw);
    return ret;
}

struct asset_list_args {
    const char *cursor;
    int limit;
    const char *bad, *rule;
};

static enum MHD_Result asset_list_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                      const char *value)
{
    (void)kind;
    struct asset_list_args *a = cls;
    if (strcmp(key, "limit") == 0) {
        char *end;
        long v = value ? strtol(value, &end, 10) : 0;
        if (!value || *end || end == value || v < 1 || v > STORE_LIMIT_MAX) {
            a->bad = "limit";
            a->rule = "must be an integer from 1 to 1000";
            return MHD_NO;
        }
        a->limit = (int)v;
    } else if (strcmp(key, "cursor") == 0) {
        if (!value || !scene_asset_name_valid(value)) {
            a->bad = "cursor";
            a->rule = "must be an asset name, as the previous page's \"next\" gives it";
            return MHD_NO;
        }
        a->cursor = value;
    } else {
        a->bad = key;
        a->rule = "unknown argument: the asset list takes limit and cursor";
        return MHD_NO;
    }
    return MHD_YES;
}

/* /v1/assets and /v1/assets/NAME (daemon/jobs/assets.h). PUT reaches here
 * only once its body is in and refused before any conversion (begin
 * answered in refuse_early, finish in on_request). */
static enum MHD_Result asset_resource(struct http_server *s, struct MHD_Connection *c,
                                      const char *method, struct request *req)
{
    if (!s->ctx.assets)
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "url",
                             "this daemon has no asset store");
    struct assets_error e = {0};
    json_t *body;
    if (req->route.kind == ROUTE_ASSETS) {
        struct asset_list_args a = {.cursor = "", .limit = STORE_LIMIT_DEFAULT};
        MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, asset_list_arg, &a);
        if (a.bad)
            return respond_error(c, MHD_HTTP_BAD_REQUEST, a.bad, a.rule);
        body = assets_list(s->ctx.assets, a.cursor, a.limit, &e);
    } else if (req->route.asset_too_long) {
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "name",
                             "an asset name is at most 128 bytes");
    } else if (strcmp(method, "DELETE") == 0) {
        body = assets_delete(s->ctx.assets, req->route.asset, &e);
    } else {
        body = assets_describe(s->ctx.assets, req->route.asset, &e);
    }
    if (!body)
        return respond_asset_error(c, &e);
    return respond_json(c, MHD_HTTP_OK, body);
}

/* The upload's body is in: its conversion is queued and the request waits
 * for it without a thread (connections.h), as a long-poll does. */
static enum MHD_Result finish_upload(struct http_server *s, struct MHD_Connection *c,
                                     struct request *req)
{
    struct assets_error e = {0};
    struct asset_upload *u = req->upload;
    req->upload = NULL;
    uint64_t ticket = assets_upload_finish(u, &e);
    if (!ticket)
        return respond_asset_error(c, &e);
    req->ticket = ticket;
    char id[32];
    snprintf(id, sizeof(id), "%llu", (unsigned long long)ticket);
    if (!connections_suspend(s->conns, req->conn, WAIT_ASSET, id,
                             assets_answer_wait_s(s->ctx.assets)))
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "body",
                             "the daemon is stopping; upload the asset again once it is back");
    req->waiting = true;
    return MHD_YES;
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
    case ROUTE_JOB:
    case ROUTE_JOB_REPORT:
    case ROUTE_JOB_CHART:
    case ROUTE_JOB_TIMINGS:
    case ROUTE_JOB_IMAGE:
        return job_resource(s, c, method, req);
    case ROUTE_SWEEP:
    case ROUTE_SWEEP_CHART:
    case ROUTE_SWEEP_REPORT:
        return sweep_resource(s, c, method, req);
    default:
        return respond_error(c, MHD_HTTP_NOT_FOUND, req->route.field ? req->route.field : "url",
                             req->route.message ? req->route.message : "no such route");
    }
}

struct header_scan {
    size_t bytes;
    int content_length, transfer_encoding;
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
    if (req->route.kind != ROUTE_HEALTHZ && !authorized(s, c)) {
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
    if (req->route.kind == ROUTE_ASSET && strcmp(method, "PUT") == 0) {
        /* The file streams to disk (assets.h): its own limit, not a job's. */
        if (!s->ctx.assets) {
            *ret = respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "url",
                                 "this daemon has no asset store");
            return true;
        }
        if (req->route.asset_too_long) {
            *ret = respond_error(c, MHD_HTTP_BAD_REQUEST, "name",
                                 "an asset name is at most 128 bytes");
            return true;
        }
        uint64_t length = cl ? strtoull(cl, NULL, 10) : 0;
        struct assets_error e = {0};
        req->upload = assets_upload_begin(s->ctx.assets, req->route.asset, length, &e);
        if (!req->upload) {
            req->too_large = e.status == MHD_HTTP_CONTENT_TOO_LARGE;
            *ret = respond_asset_error(c, &e);
            return true;
        }
        /* Its body's deadline grows with its size: 1 MiB/s at least. */
        uint64_t expect = length ? length : assets_max_bytes(s->ctx.assets);
        connections_body_deadline(s->conns, req->conn,
                                  s->limits.body_timeout_s + (double)expect / (1 << 20));
        return false;
    }
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
                                    .per_ip = limits->max_connections_per_ip};
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
