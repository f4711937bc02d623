#define _POSIX_C_SOURCE 200809L
#include "daemon/api/http.h"

#include <errno.h>
#include <fcntl.h>
#include <microhttpd.h>
#include <netdb.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "config.h"
#include "daemon/api/charts.h"
#include "daemon/api/job_filter.h"
#include "daemon/jobs/job_spec.h"
#include "daemon/api/report.h"
#include "common/log.h"
#include "daemon/techniques/catalog.h"

#ifndef MHD_HTTP_CONTENT_TOO_LARGE
#define MHD_HTTP_CONTENT_TOO_LARGE 413
#endif

enum { MAX_CONNECTIONS = 256, MAX_WAIT_S = 3600 };

struct http_server {
    struct MHD_Daemon *mhd;
    struct queue *queue;
    struct runner *runner;
    struct sweeps *sweeps;
    int port;
    pthread_mutex_t token_lock;
    char token[512];
};

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
    bool ok = s->token[0] == '\0';
    if (!ok) {
        const char *auth = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Authorization");
        ok = auth && strncmp(auth, "Bearer ", 7) == 0 && token_matches(auth + 7, s->token);
    }
    pthread_mutex_unlock(&s->token_lock);
    return ok;
}

void http_server_set_token(struct http_server *s, const char *token)
{
    pthread_mutex_lock(&s->token_lock);
    snprintf(s->token, sizeof(s->token), "%s", token ? token : "");
    pthread_mutex_unlock(&s->token_lock);
}

struct request {
    char *body;
    size_t len;
    bool too_large;
};

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
    if (status == MHD_HTTP_METHOD_NOT_ALLOWED)
        MHD_add_response_header(resp, "Allow", "GET, HEAD, POST, DELETE");
    if (status == MHD_HTTP_UNAUTHORIZED)
        MHD_add_response_header(resp, "WWW-Authenticate", "Bearer realm=\"shadebench\"");
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

/* Takes ownership of body. */
static enum MHD_Result respond_json(struct MHD_Connection *c, unsigned status, json_t *body)
{
    char *text = json_dumps(body, JSON_COMPACT);
    json_decref(body);
    if (!text)
        return MHD_NO;
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
    enum MHD_Result ret = MHD_queue_response(c, MHD_HTTP_OK, resp);
    MHD_destroy_response(resp);
    return ret;
}

static bool valid_id(const char *id, size_t len)
{
    if (len == 0 || len >= 24)
        return false;
    for (size_t i = 0; i < len; i++)
        if (!((id[i] >= '0' && id[i] <= '9') || id[i] == '-'))
            return false;
    return true;
}

static json_t *info_json(struct http_server *s)
{
    /* From the GL-free catalogue: HTTP threads never touch GL. */
    json_t *techs = technique_catalog_json(technique_catalog());
    return json_pack("{s:s, s:s, s:s, s:o, s:o, s:o, s:{s:i, s:i, s:i}}", "name", "shadebenchd",
                     "version", PACKAGE_VERSION, "api", "v1", "device",
                     runner_device_json(s->runner), "techniques", techs, "sweepable",
                     sweep_params_json(technique_catalog()), "limits",
                     "max_body_bytes", JOB_MAX_BODY_BYTES, "max_queued_jobs",
                     queue_max_queued(s->queue), "max_wait_s", MAX_WAIT_S);
}

static enum MHD_Result submit_job(struct http_server *s, struct MHD_Connection *c,
                                  struct request *req)
{
    struct job_spec spec;
    struct job_error err;
    if (!job_spec_parse_text(req->body ? req->body : "", req->len, technique_catalog(),
                             &spec, &err))
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    char id[24];
    switch (queue_submit(s->queue, &spec, NULL, id)) {
    case QUEUE_OK:
        break;
    case QUEUE_FULL: {
        char msg[96];
        snprintf(msg, sizeof(msg), "the queue is full (%d jobs waiting); retry later",
                 queue_max_queued(s->queue));
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "body", msg);
    }
    case QUEUE_STOPPING:
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "body", "the daemon is stopping");
    default:
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "body",
                             "cannot create the job's directory under the state directory");
    }
    char url[64];
    snprintf(url, sizeof(url), "/v1/jobs/%s", id);
    LOG(LOG_INFO, "queued job %s (%s)", id, spec.technique);
    return respond_json(c, MHD_HTTP_ACCEPTED,
                        json_pack("{s:s, s:s, s:s}", "id", id, "status", "queued", "url", url));
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

/* ".../charts/NAME.svg" or ".png": renders from the JSON of a sweep or job. */
static enum MHD_Result respond_chart(struct MHD_Connection *c, const json_t *subject,
                                     const char *file, bool is_sweep, const json_t *device)
{
    char name[32];
    const char *dot = strrchr(file, '.');
    if (!dot || (size_t)(dot - file) >= sizeof(name) ||
        (strcmp(dot, ".svg") != 0 && strcmp(dot, ".png") != 0))
        return respond_error(c, MHD_HTTP_NOT_FOUND, "chart", "charts are NAME.svg or NAME.png");
    snprintf(name, sizeof(name), "%.*s", (int)(dot - file), file);
    enum chart_format format = strcmp(dot, ".svg") == 0 ? CHART_SVG : CHART_PNG;
    struct chart_options o = {.device = device};
    o.series = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "series");
    if (o.series && strcmp(o.series, "frame_ms") && strcmp(o.series, "gpu_ms") && strcmp(o.series, "cpu_ms"))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "series", "must be frame_ms, gpu_ms or cpu_ms");
    const char *y = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "y");
    if (y && strcmp(y, "ssim") && strcmp(y, "flip"))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "y", "must be ssim or flip");
    o.flip = y && strcmp(y, "flip") == 0;
    char err[256];
    size_t len = 0;
    char *data = is_sweep ? charts_sweep(subject, name, format, &o, &len, err, sizeof(err))
                          : charts_job(subject, name, format, &o, &len, err, sizeof(err));
    if (!data)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "chart", err);
    return respond_text(c, MHD_HTTP_OK, data, len, format == CHART_SVG ? "image/svg+xml" : "image/png");
}

struct list_args {
    struct job_filter filter;
    struct job_error err;
    bool ok;
};

static enum MHD_Result list_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                const char *value)
{
    (void)kind;
    struct list_args *a = cls;
    a->ok = a->ok && job_filter_add(&a->filter, key, value, &a->err);
    return a->ok ? MHD_YES : MHD_NO;
}

static bool point_job_dir(void *ctx, const char *job_id, char *dir, size_t cap, int *last_frame)
{
    struct http_server *s = ctx;
    enum job_status status;
    if (!queue_job_dir(s->queue, job_id, dir, cap, &status))
        return false;
    json_t *job = queue_job_json(s->queue, job_id, 0);
    json_t *caps = json_object_get(json_object_get(job, "result"), "captures");
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

static enum MHD_Result job_routes(struct http_server *s, struct MHD_Connection *c,
                                  const char *method, const char *rest)
{
    /* rest is what follows "/v1/jobs/": ID, ID/timings.csv or ID/frames/K.png */
    const char *slash = strchr(rest, '/');
    size_t id_len = slash ? (size_t)(slash - rest) : strlen(rest);
    if (!valid_id(rest, id_len))
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    char id[24];
    memcpy(id, rest, id_len);
    id[id_len] = '\0';
    bool get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;

    if (!slash) {
        if (get) {
            double wait;
            if (!parse_wait(c, &wait))
                return respond_error(c, MHD_HTTP_BAD_REQUEST, "wait",
                                     "must be a number of seconds from 0 to 3600");
            json_t *job = queue_job_json(s->queue, id, wait);
            if (!job)
                return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
            return respond_json(c, MHD_HTTP_OK, job);
        }
        if (strcmp(method, "DELETE") == 0) {
            switch (queue_cancel(s->queue, id)) {
            case CANCEL_NOT_FOUND:
                return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
            case CANCEL_FINISHED:
                return respond_error(c, MHD_HTTP_CONFLICT, "id",
                                     "the job has already finished");
            case CANCEL_DONE:
                return respond_json(c, MHD_HTTP_OK, queue_job_json(s->queue, id, 0));
            case CANCEL_REQUESTED:
                /* The render thread stops at the next frame; give it a moment so
                 * the answer usually shows the final state. */
                return respond_json(c, MHD_HTTP_ACCEPTED, queue_job_json(s->queue, id, 5));
            }
        }
        return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method",
                             "use GET or DELETE on a job");
    }

    if (strcmp(slash + 1, "report.html") == 0) {
        if (!get)
            return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
        char dir[PATH_MAX];
        enum job_status status;
        json_t *job = queue_job_json(s->queue, id, 0);
        if (!job || !queue_job_dir(s->queue, id, dir, sizeof(dir), &status)) {
            json_decref(job);
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        }
        json_t *device = runner_device_json(s->runner);
        size_t len = 0;
        char *html = report_job_html(job, dir, device, &len);
        json_decref(device);
        json_decref(job);
        return respond_html(c, html, len);
    }
    if (strncmp(slash + 1, "charts/", 7) == 0) {
        if (!get)
            return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
        json_t *job = queue_job_json(s->queue, id, 0);
        if (!job)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
        enum MHD_Result ret =
            json_object_get(job, "result")
                ? respond_chart(c, job, slash + 8, false, NULL)
                : respond_error(c, MHD_HTTP_CONFLICT, "id", "the job has no result yet");
        json_decref(job);
        return ret;
    }
    /* Per-capture images: URL folder -> file prefix in the job's directory. */
    static const char *const kinds[][2] = {
        {"frames/", "frame"}, {"reference/", "reference"}, {"ssim/", "ssim"}, {"flip/", "flip"},
    };
    const char *sub = slash + 1, *prefix = NULL;
    char dir[PATH_MAX], path[PATH_MAX + 64];
    enum job_status status;
    bool csv = strcmp(sub, "timings.csv") == 0;
    int frame = 0;
    char tail[8] = "";
    for (size_t k = 0; k < sizeof(kinds) / sizeof(kinds[0]) && !prefix; k++) {
        size_t len = strlen(kinds[k][0]);
        if (strncmp(sub, kinds[k][0], len) == 0 &&
            sscanf(sub + len, "%9d%7s", &frame, tail) == 2 && strcmp(tail, ".png") == 0 && frame > 0)
            prefix = kinds[k][1];
    }
    bool png = prefix != NULL;
    if (!csv && !png)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "url", "no such resource");
    if (!get)
        return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
    if (!queue_job_dir(s->queue, id, dir, sizeof(dir), &status))
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    if (status != JOB_DONE)
        return respond_error(c, MHD_HTTP_CONFLICT, "id",
                             "the job has not finished: its files exist once it is done");
    if (csv) {
        snprintf(path, sizeof(path), "%s/timings.csv", dir);
        return respond_file(c, path, "text/csv");
    }
    snprintf(path, sizeof(path), "%s/%s-%06d.png", dir, prefix, frame);
    if (access(path, R_OK) != 0)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "frame",
                             "no such image: this frame was not captured, or the job has no "
                             "reference or that metric (see result.captures)");
    return respond_file(c, path, "image/png");
}

static enum MHD_Result sweep_routes(struct http_server *s, struct MHD_Connection *c,
                                    const char *method, const char *rest, struct request *req)
{
    bool get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
    if (!*rest) {
        if (strcmp(method, "POST") == 0) {
            if (req->too_large)
                return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                                     "the sweep must be at most 65536 bytes");
            json_error_t jerr;
            json_t *body = json_loadb(req->body ? req->body : "", req->len, JSON_REJECT_DUPLICATES, &jerr);
            if (!body) {
                char msg[256];
                snprintf(msg, sizeof(msg), "malformed JSON at line %d, column %d: %s", jerr.line,
                         jerr.column, jerr.text);
                return respond_error(c, MHD_HTTP_BAD_REQUEST, "body", msg);
            }
            struct sweep_spec spec;
            struct job_error err;
            if (!sweep_spec_parse(body, technique_catalog(), &spec, &err)) {
                sweep_spec_finish(&spec);
                json_decref(body);
                return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
            }
            char id[24];
            bool ok = sweeps_submit(s->sweeps, &spec, body, id);
            sweep_spec_finish(&spec);
            json_decref(body);
            if (!ok)
                return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "body",
                                     "too many sweeps are waiting; retry later");
            char url[64];
            snprintf(url, sizeof(url), "/v1/sweeps/%s", id);
            return respond_json(c, MHD_HTTP_ACCEPTED,
                                json_pack("{s:s, s:s, s:s}", "id", id, "status", "queued", "url", url));
        }
        if (get)
            return respond_json(c, MHD_HTTP_OK, sweeps_list_json(s->sweeps));
        return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method",
                             "use GET to list sweeps or POST to start one");
    }
    size_t id_len = strcspn(rest, "/");
    if (!valid_id(rest, id_len))
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
    char id[24];
    memcpy(id, rest, id_len);
    id[id_len] = '\0';
    if (rest[id_len]) {
        const char *sub = rest + id_len + 1;
        if (!get)
            return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
        json_t *sw = sweeps_json(s->sweeps, id, 0);
        if (!sw)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
        enum MHD_Result ret;
        if (strncmp(sub, "charts/", 7) == 0) {
            json_t *device = runner_device_json(s->runner);
            ret = respond_chart(c, sw, sub + 7, true, device);
            json_decref(device);
        } else if (strcmp(sub, "report.html") == 0) {
            json_t *device = runner_device_json(s->runner);
            size_t len = 0;
            char *html = report_sweep_html(sw, device, point_job_dir, s, &len);
            json_decref(device);
            ret = respond_html(c, html, len);
        } else
            ret = respond_error(c, MHD_HTTP_NOT_FOUND, "url", "no such resource");
        json_decref(sw);
        return ret;
    }
    if (get) {
        double wait;
        if (!parse_wait(c, &wait))
            return respond_error(c, MHD_HTTP_BAD_REQUEST, "wait",
                                 "must be a number of seconds from 0 to 3600");
        json_t *sw = sweeps_json(s->sweeps, id, wait);
        return sw ? respond_json(c, MHD_HTTP_OK, sw)
                  : respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
    }
    if (strcmp(method, "DELETE") == 0) {
        switch (sweeps_cancel(s->sweeps, id)) {
        case CANCEL_NOT_FOUND:
            return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such sweep");
        case CANCEL_FINISHED:
            return respond_error(c, MHD_HTTP_CONFLICT, "id", "the sweep has already finished");
        case CANCEL_DONE:
            return respond_json(c, MHD_HTTP_OK, sweeps_json(s->sweeps, id, 0));
        case CANCEL_REQUESTED:
            return respond_json(c, MHD_HTTP_ACCEPTED, sweeps_json(s->sweeps, id, 5));
        }
    }
    return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET or DELETE on a sweep");
}

static enum MHD_Result route(struct http_server *s, struct MHD_Connection *c,
                             const char *url, const char *method, struct request *req)
{
    bool get = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
    if (strcmp(url, "/healthz") == 0) {
        if (!get)
            return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
        if (!runner_alive(s->runner))
            return respond_json(c, MHD_HTTP_SERVICE_UNAVAILABLE,
                                json_pack("{s:s}", "status", "render thread is not running"));
        return respond_json(c, MHD_HTTP_OK, json_pack("{s:s}", "status", "ok"));
    }
    if (strcmp(url, "/v1/info") == 0) {
        if (!get)
            return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method", "use GET");
        return respond_json(c, MHD_HTTP_OK, info_json(s));
    }
    if (strcmp(url, "/v1/jobs") == 0 || strcmp(url, "/v1/jobs/") == 0) {
        if (strcmp(method, "POST") == 0) {
            if (req->too_large)
                return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                                     "the job must be at most 65536 bytes");
            return submit_job(s, c, req);
        }
        if (get) {
            /* ?technique=&status=&label.KEY=VALUE&since= (daemon/api/job_filter.h) */
            struct list_args a = {.ok = true};
            job_filter_init(&a.filter);
            MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, list_arg, &a);
            if (!a.ok)
                return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&a.err));
            return respond_json(c, MHD_HTTP_OK,
                                queue_list_json_with(s->queue, job_filter_visit, &a.filter));
        }
        return respond_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "method",
                             "use GET to list jobs or POST to submit one");
    }
    if (strncmp(url, "/v1/jobs/", 9) == 0)
        return job_routes(s, c, method, url + 9);
    if (strcmp(url, "/v1/sweeps") == 0)
        return sweep_routes(s, c, method, "", req);
    if (strncmp(url, "/v1/sweeps/", 11) == 0)
        return sweep_routes(s, c, method, url + 11, req);
    return respond_error(c, MHD_HTTP_NOT_FOUND, "url", "no such route");
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    (void)version;
    struct http_server *s = cls;
    struct request *req = *con_cls;
    if (!req) {
        req = calloc(1, sizeof(*req));
        if (!req)
            return MHD_NO;
        *con_cls = req;
        /* Refuse before reading any body. */
        if (strcmp(url, "/healthz") != 0 && !authorized(s, c))
            return respond_error(c, MHD_HTTP_UNAUTHORIZED, "Authorization",
                                 "this daemon needs \"Authorization: Bearer <token>\"");
        const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
        if (cl && strtoull(cl, NULL, 10) > JOB_MAX_BODY_BYTES) {
            /* Answer before reading the body; MHD closes the connection after. */
            req->too_large = true;
            return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                                 "the job must be at most 65536 bytes");
        }
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
    return route(s, c, url, method, req);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode code)
{
    (void)cls, (void)c, (void)code;
    struct request *req = *con_cls;
    if (req) {
        free(req->body);
        free(req);
        *con_cls = NULL;
    }
}

static void on_mhd_log(void *cls, const char *fmt, va_list ap)
{
    (void)cls;
    char msg[512];
    vsnprintf(msg, sizeof(msg), fmt, ap);
    size_t n = strlen(msg);
    while (n && msg[n - 1] == '\n')
        msg[--n] = '\0';
    LOG(LOG_WARN, "libmicrohttpd: %s", msg);
}

struct http_server *http_server_create(const char *listen, struct queue *q,
                                       struct runner *r, struct sweeps *sweeps, char *err,
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
    s->queue = q;
    s->runner = r;
    s->sweeps = sweeps;
    pthread_mutex_init(&s->token_lock, NULL);
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION |
                     MHD_USE_ERROR_LOG;
    if (ai->ai_family == AF_INET6)
        flags |= MHD_USE_IPv6;
    s->mhd = MHD_start_daemon(flags, (uint16_t)port, NULL, NULL, on_request, s,
                              MHD_OPTION_EXTERNAL_LOGGER, on_mhd_log, s,
                              MHD_OPTION_SOCK_ADDR, ai->ai_addr,
                              MHD_OPTION_CONNECTION_LIMIT, (unsigned)MAX_CONNECTIONS,
                              MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)60,
                              MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                              MHD_OPTION_END);
    freeaddrinfo(ai);
    if (!s->mhd) {
        snprintf(err, errlen, "cannot listen on %s (address in use or not allowed?)", listen);
        pthread_mutex_destroy(&s->token_lock);
        free(s);
        return NULL;
    }
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(s->mhd, MHD_DAEMON_INFO_BIND_PORT);
    s->port = info ? info->port : (int)port;
    return s;
}

void http_server_destroy(struct http_server *s)
{
    if (!s)
        return;
    MHD_stop_daemon(s->mhd);
    pthread_mutex_destroy(&s->token_lock);
    free(s);
}

int http_server_port(const struct http_server *s) { return s->port; }
