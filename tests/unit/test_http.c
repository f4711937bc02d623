/* The HTTP layer without GL: a real server on a loopback port over a real
 * store in a temporary directory, handed the real technique catalogue and a
 * render thread of the test's own (which takes jobs from the queue and
 * finishes them with a made-up result), asked with plain sockets. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <arpa/inet.h>
#include <jansson.h>
#include <limits.h>
#include <netinet/in.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/log.h"
#include "daemon/api/connections.h"
#include "daemon/api/http.h"
#include "daemon/spec/job_cost.h"
#include "daemon/store/store.h"

static atomic_bool render_up = true;

/* The real render state (render_state.c), which the test drives as the
 * render thread would. */
static void fake_state(void *render, struct render_state *out)
{
    (void)render;
    render_state_read(out);
    out->alive = atomic_load(&render_up);
}

static json_t *fake_device(void *render)
{
    (void)render;
    return json_pack("{s:s}", "gl_renderer", "test renderer");
}

struct reply {
    int status;
    char *body; /* NUL-terminated */
    json_t *json;
};

static void reply_finish(struct reply *r)
{
    free(r->body);
    json_decref(r->json);
    memset(r, 0, sizeof(*r));
}

static void sleep_ms(long ms)
{
    struct timespec t = {.tv_sec = ms / 1000, .tv_nsec = (ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

/* Until the server holds exactly n connections (at most 10 s): a
 * connection is counted once the server has taken it, which a loaded
 * machine may do late. */
static bool wait_connections_ms(struct http_server *http, size_t n, int ms)
{
    for (int i = 0; i < ms / 10; i++) {
        if (http_server_open_connections(http) == n)
            return true;
        sleep_ms(10);
    }
    return false;
}

static bool wait_connections(struct http_server *http, size_t n)
{
    return wait_connections_ms(http, n, 10000);
}

static int connect_to(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    /* A server that never answers fails the check rather than hanging. */
    struct timeval tv = {.tv_sec = 10};
    if (fd >= 0 && (setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv)) != 0 ||
                    connect(fd, (struct sockaddr *)&a, sizeof(a)) != 0)) {
        close(fd);
        fd = -1;
    }
    return fd;
}

/* Is the silent connection fd still open at the server's end (no close
 * seen: a refusal by libmicrohttpd closes it unanswered)? */
static bool hog_held(int fd)
{
    char c;
    if (fd < 0)
        return false;
    ssize_t n = recv(fd, &c, 1, MSG_PEEK | MSG_DONTWAIT);
    return n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
}

static struct reply read_reply(int fd);

/* Sends len bytes as they are (the request line and headers included) on
 * a fresh connection and reads the answer until the server closes. */
static struct reply raw_request(int port, const char *data, size_t len)
{
    struct reply r = {0};
    int fd = connect_to(port);
    if (fd < 0)
        return r;
    if (write(fd, data, len) != (ssize_t)len) {
        close(fd);
        return r;
    }
    return read_reply(fd);
}

/* One request on a fresh connection; extra: more header lines, each ending
 * in \r\n. */
static struct reply request(int port, const char *method, const char *path, const char *body,
                            const char *extra)
{
    struct reply r = {0};
    size_t blen = body ? strlen(body) : 0;
    char *head = malloc(strlen(path) + 1024);
    if (!head)
        return r;
    int n = sprintf(head, "%s %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n"
                    "Content-Length: %zu\r\n%s\r\n",
                    method, path, blen, extra ? extra : "");
    int fd = connect_to(port);
    bool sent = fd >= 0 && write(fd, head, (size_t)n) == n &&
                (!blen || write(fd, body, blen) == (ssize_t)blen);
    free(head);
    if (!sent) {
        if (fd >= 0)
            close(fd);
        return r;
    }
    return read_reply(fd);
}

/* Reads an answer until the server closes fd, then closes it. */
static struct reply read_reply(int fd)
{
    struct reply r = {0};
    size_t cap = 1 << 16, used = 0;
    char *buf = malloc(cap);
    ssize_t got;
    while (buf && (got = read(fd, buf + used, cap - used - 1)) > 0) {
        used += (size_t)got;
        if (cap - used < 4096) {
            char *more = realloc(buf, cap *= 2);
            if (!more)
                break;
            buf = more;
        }
    }
    close(fd);
    if (!buf)
        return r;
    buf[used] = '\0';
    sscanf(buf, "HTTP/1.%*d %d", &r.status);
    char *sep = strstr(buf, "\r\n\r\n");
    r.body = strdup(sep ? sep + 4 : "");
    r.json = json_loads(r.body, 0, NULL);
    free(buf);
    return r;
}

static const char *error_field(const struct reply *r)
{
    return json_string_value(json_object_get(json_object_get(r->json, "error"), "field"));
}

static const char *str(const json_t *o, const char *key)
{
    return json_string_value(json_object_get(o, key));
}

static const char *JOB = "{\"technique\":\"unlit\",\"frames\":2,\"warmup_frames\":0,"
                         "\"capture_interval\":2,\"scene\":{\"width\":16,\"height\":16}}";

/* The test's render thread: one job from the queue, finished with a result
 * naming one capture, as the harness would leave it. */
static void finish_next(struct queue *q, const char *expect_id)
{
    struct job *job = queue_next(q);
    CHECK(job && strcmp(job->id, expect_id) == 0);
    if (!job)
        return;
    json_t *result = json_pack("{s:s, s:i, s:[{s:i, s:s}], s:{s:f, s:[f, f]}}", "technique",
                               "unlit", "frames", 2, "captures", "frame", 2, "file",
                               "frame-000002.png", "frame_ms", "median", 1.0, "median_ci95", 0.9,
                               1.1);
    char path[PATH_MAX + 32];
    job_file_path(job->dir, JOB_FILE_RESULT, path, sizeof(path));
    CHECK(fs_write_json_atomic(path, result));
    job_file_path(job->dir, JOB_FILE_TIMINGS, path, sizeof(path));
    CHECK(fs_write_atomic(path, "frame,gpu_ms\n1,1.0\n2,1.0\n", 25));
    queue_finish(q, job, JOB_DONE, NULL, result);
}

int main(void)
{
    log_set_level(LOG_WARN);
    char state[] = "/tmp/test_http-XXXXXX";
    CHECK(mkdtemp(state) != NULL);
    char err[PATH_MAX + 300];
    struct technique_catalog catalog;
    CHECK(technique_catalog_init(&catalog, err, sizeof(err)));
    struct store *store = store_open(state, err, sizeof(err));
    struct queue *q = store ? queue_create(store, 4) : NULL;
    CHECK(q && queue_load(q, &catalog, err, sizeof(err)) == 0);
    struct sweeps *sweeps = q ? sweeps_create(q, &catalog) : NULL;
    CHECK(sweeps != NULL);
    struct http_limits limits;
    http_limits_defaults(&limits);
    limits.max_connections_per_ip = 3;
    /* Assets, with a converter of the test's own (the CLI contract of
     * shadebench-asset: exit 0 with a description, 2 with a refusal): what
     * is tested here is the HTTP layer and the store, not the loader. */
    char converter[PATH_MAX];
    snprintf(converter, sizeof(converter), "%s/converter.sh", state);
    static const char script[] =
        "#!/bin/sh\n"
        "case \"$(head -c 4 \"$2\")\" in\n"
        "glTF) printf cache > \"$3\"; echo '{\"meshes\":2,\"triangles\":12}'; exit 0;;\n"
        "*) echo '{\"status\":422,\"field\":\"magic\",\"message\":\"not a glb\"}'; exit 2;;\n"
        "esac\n";
    CHECK(fs_write_atomic(converter, script, sizeof(script) - 1) && chmod(converter, 0755) == 0);
    struct assets_config acfg = {.state_dir = state, .converter = converter,
                                 .max_asset_bytes = 4096};
    asset_limits_defaults(&acfg.limits);
    asset_run_limits_defaults(&acfg.run);
    struct assets *assets = q ? assets_create(&acfg, store, q, err, sizeof(err)) : NULL;
    CHECK(assets != NULL);
    if (assets) {
        struct queue_asset_hooks hooks;
        assets_queue_hooks(assets, &hooks);
        queue_set_asset_hooks(q, &hooks);
    }
    const struct http_context ctx = {.catalog = &catalog, .queue = q, .sweeps = sweeps,
                                     .assets = assets,
                                     .render_state = fake_state, .device_json = fake_device,
                                     .stall_s = 0.3};
    struct http_server *http = sweeps ? http_server_create("127.0.0.1:0", &limits, &ctx, err,
                                                           sizeof(err))
                                      : NULL;
    CHECK(http != NULL);
    if (!http)
        return check_finish("test_http");
    int port = http_server_port(http);
    struct reply r;

    /* /healthz follows the render thread: idle, busy with a job (which and
     * in what phase), stalled once it makes no progress for longer than
     * stall_s, healthy again with progress, and 503 once it has stopped. */
    render_state_end();
    r = request(port, "GET", "/healthz", NULL, NULL);
    json_t *render = json_object_get(r.json, "render");
    CHECK(r.status == 200 && !strcmp(str(r.json, "status"), "ok") &&
          !strcmp(str(render, "state"), "idle"));
    reply_finish(&r);
    render_state_begin("20260101-000000-0042", "setup");
    render_state_phase("rendering");
    r = request(port, "GET", "/healthz", NULL, NULL);
    render = json_object_get(r.json, "render");
    CHECK(r.status == 200 && !strcmp(str(render, "state"), "busy") &&
          !strcmp(str(render, "job"), "20260101-000000-0042") &&
          !strcmp(str(render, "phase"), "rendering") &&
          json_real_value(json_object_get(render, "since_progress_s")) < 0.3);
    reply_finish(&r);
    sleep_ms(400);
    r = request(port, "GET", "/healthz", NULL, NULL);
    render = json_object_get(r.json, "render");
    CHECK(r.status == 503 && !strcmp(str(r.json, "status"), "stalled") &&
          strstr(str(r.json, "message"), "20260101-000000-0042") &&
          !strcmp(str(render, "state"), "stalled") &&
          json_real_value(json_object_get(render, "since_progress_s")) > 0.3);
    reply_finish(&r);
    r = request(port, "GET", "/metrics", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "shadebench_render_stalled 1\n") &&
          strstr(r.body, "shadebench_render_busy 1\n") &&
          strstr(r.body, "shadebench_render_job{job=\"20260101-000000-0042\",phase=\"rendering\"} 1"));
    reply_finish(&r);
    render_progress(); /* a frame went round */
    r = request(port, "GET", "/healthz", NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);
    sleep_ms(400);
    render_state_end(); /* idle is never stalled, however long */
    sleep_ms(400);
    r = request(port, "GET", "/healthz", NULL, NULL);
    CHECK(r.status == 200 && !strcmp(str(json_object_get(r.json, "render"), "state"), "idle"));
    reply_finish(&r);
    r = request(port, "GET", "/metrics", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "shadebench_render_stalled 0\n") &&
          strstr(r.body, "shadebench_render_busy 0\n") && !strstr(r.body, "render_job{"));
    reply_finish(&r);
    atomic_store(&render_up, false);
    r = request(port, "GET", "/healthz", NULL, NULL);
    CHECK(r.status == 503);
    reply_finish(&r);
    atomic_store(&render_up, true);

    /* /v1/info: the catalogue handed in, every technique of it, and the device. */
    r = request(port, "GET", "/v1/info", NULL, NULL);
    json_t *techs = json_object_get(r.json, "techniques");
    CHECK(r.status == 200 && json_array_size(techs) == (size_t)catalog.count);
    for (int i = 0; i < catalog.count; i++)
        CHECK(strcmp(str(json_array_get(techs, (size_t)i), "name"), catalog.infos[i]->name) == 0);
    CHECK(strcmp(str(json_object_get(r.json, "device"), "gl_renderer"), "test renderer") == 0);
    reply_finish(&r);

    /* Rejections are JSON naming the field and the rule. */
    r = request(port, "POST", "/v1/jobs", "{\"technique\":\"nope\"}", NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "technique") == 0);
    CHECK(strstr(r.body, "unlit") != NULL); /* the rule lists the catalogue */
    reply_finish(&r);
    r = request(port, "POST", "/v1/jobs", "{\"technique\":", NULL);
    CHECK(r.status == 400 && error_field(&r) != NULL);
    reply_finish(&r);
    r = request(port, "GET", "/v1/nothing", NULL, NULL);
    CHECK(r.status == 404 && error_field(&r) != NULL);
    reply_finish(&r);
    r = request(port, "PUT", "/v1/jobs", JOB, NULL);
    CHECK(r.status == 405 && error_field(&r) != NULL);
    reply_finish(&r);
    char *big = malloc(70 * 1024);
    memset(big, ' ', 70 * 1024 - 1);
    big[70 * 1024 - 1] = '\0';
    r = request(port, "POST", "/v1/jobs", big, NULL);
    CHECK(r.status == 413 && error_field(&r) != NULL);
    reply_finish(&r);
    free(big);
    r = request(port, "POST", "/v1/sweeps", "{\"base\":{}, \"vary\":{\"frames\":[]}}", NULL);
    CHECK(r.status == 400 && error_field(&r) != NULL);
    reply_finish(&r);

    /* The request itself (issue 26): every refusal JSON naming what is wrong. */
    static const char no_host[] = "GET /v1/info HTTP/1.1\r\nConnection: close\r\n\r\n";
    r = raw_request(port, no_host, sizeof(no_host) - 1);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "Host") == 0);
    reply_finish(&r);
    static const char old_http[] = "GET /healthz HTTP/1.0\r\n\r\n"; /* Host is 1.1's */
    r = raw_request(port, old_http, sizeof(old_http) - 1);
    CHECK(r.status == 200);
    reply_finish(&r);
    /* %00 would cut the decoded path: 1.png%00.txt must not serve 1.png. */
    r = request(port, "GET", "/v1/jobs/1/frames/1.png%00.txt", NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "url") == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs?label.a=x%00y", NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "url") == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs?label.a=100%25", NULL, NULL); /* an encoded '%' is fine */
    CHECK(r.status == 200);
    reply_finish(&r);
    /* 500 filters: refused as JSON (libmicrohttpd's pool ran out and nobody
     * answered); 40 are past the store's 32 and refused by the filter. */
    char *many = malloc(16 * 1024);
    int at = sprintf(many, "/v1/jobs");
    for (int i = 0; i < 500; i++)
        at += sprintf(many + at, "%clabel.k%d=v", i ? '&' : '?', i);
    r = request(port, "GET", many, NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "query") == 0 &&
          strstr(r.body, "500"));
    reply_finish(&r);
    memcpy(many + strlen("/v1/jobs?label.k0="), "%00", 3); /* and an encoded NUL: still answered */
    r = request(port, "GET", many, NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "url") == 0);
    reply_finish(&r);
    at = sprintf(many, "/v1/jobs");
    for (int i = 0; i < 40; i++)
        at += sprintf(many + at, "%clabel.k%d=v", i ? '&' : '?', i);
    r = request(port, "GET", many, NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strncmp(error_field(&r), "label.", 6) == 0);
    reply_finish(&r);
    free(many);
    /* A NUL byte in a body: Jansson would stop reading at it. */
    static const char nul_body[] = "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                                   "Content-Length: 33\r\n\r\n{\"technique\":\"unlit\",\"frames\":1\0}";
    r = raw_request(port, nul_body, sizeof(nul_body) - 1);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "body") == 0 &&
          strstr(r.body, "NUL"));
    reply_finish(&r);
    struct job_spec nul_spec;
    struct job_error nul_err;
    CHECK(!job_spec_parse_text("{\"frames\":1\0}", 13, &catalog, &nul_spec, &nul_err) &&
          strcmp(nul_err.field, "body") == 0);

    /* Memory: /v1/info states the budget with the resident set; a job over
     * what a job may take is refused naming the field that drives it. */
    r = request(port, "GET", "/v1/info", NULL, NULL);
    json_t *memory = json_object_get(r.json, "memory");
    CHECK(r.status == 200 && json_real_value(json_object_get(memory, "rss_bytes")) > 0 &&
          json_real_value(json_object_get(memory, "budget_bytes")) > 0 &&
          json_object_get(memory, "job_bytes") && json_object_get(memory, "driver_bytes"));
    reply_finish(&r);
    job_cost_set_memory_limit(1048576.0);
    r = request(port, "POST", "/v1/jobs", "{\"technique\":\"unlit\",\"scene\":{\"width\":1024,"
                "\"height\":1024}}", NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "scene.width") == 0 &&
          strstr(r.body, "MiB"));
    reply_finish(&r);
    job_cost_set_memory_limit(0);

    /* Accepted jobs wait in the queue: nothing takes them until the test does. */
    char ids[3][32] = {{0}};
    for (int i = 0; i < 3; i++) {
        r = request(port, "POST", "/v1/jobs", JOB, NULL);
        CHECK(r.status == 202 && str(r.json, "id") && strcmp(str(r.json, "status"), "queued") == 0);
        CHECK(json_real_value(json_object_get(json_object_get(r.json, "cost"), "memory_bytes")) > 0);
        snprintf(ids[i], sizeof(ids[i]), "%s", str(r.json, "id") ? str(r.json, "id") : "");
        reply_finish(&r);
    }
    char path[128];
    snprintf(path, sizeof(path), "/v1/jobs/%s", ids[0]);
    r = request(port, "GET", path, NULL, NULL);
    CHECK(r.status == 200 && strcmp(str(r.json, "status"), "queued") == 0 &&
          strcmp(str(r.json, "url"), path) == 0);
    reply_finish(&r);
    snprintf(path, sizeof(path), "/v1/jobs/%s/frames/2.png", ids[0]);
    r = request(port, "GET", path, NULL, NULL);
    CHECK(r.status == 409); /* files exist once the job is done */
    reply_finish(&r);

    /* A page of two, then the rest through next. */
    r = request(port, "GET", "/v1/jobs?limit=2", NULL, NULL);
    json_t *jobs = json_object_get(r.json, "jobs");
    const char *next = str(r.json, "next");
    CHECK(r.status == 200 && json_array_size(jobs) == 2 && next != NULL);
    CHECK(json_array_size(jobs) == 2 && strcmp(str(json_array_get(jobs, 0), "id"), ids[0]) == 0 &&
          strcmp(str(json_array_get(jobs, 1), "id"), ids[1]) == 0);
    char next_path[512];
    snprintf(next_path, sizeof(next_path), "%s", next ? next : "/");
    reply_finish(&r);
    r = request(port, "GET", next_path, NULL, NULL);
    jobs = json_object_get(r.json, "jobs");
    CHECK(r.status == 200 && json_array_size(jobs) == 1 && !json_object_get(r.json, "next") &&
          json_array_size(jobs) == 1 && strcmp(str(json_array_get(jobs, 0), "id"), ids[2]) == 0);
    reply_finish(&r);
    /* Newest first (the dashboard's order): the same jobs the other way
     * round, a page at a time through next. */
    r = request(port, "GET", "/v1/jobs?order=newest&limit=2", NULL, NULL);
    jobs = json_object_get(r.json, "jobs");
    CHECK(r.status == 200 && json_array_size(jobs) == 2 &&
          strcmp(str(json_array_get(jobs, 0), "id"), ids[2]) == 0 &&
          strcmp(str(json_array_get(jobs, 1), "id"), ids[1]) == 0);
    next = str(r.json, "next");
    CHECK(next && strstr(next, "order=newest"));
    snprintf(next_path, sizeof(next_path), "%s", next ? next : "/");
    reply_finish(&r);
    r = request(port, "GET", next_path, NULL, NULL);
    jobs = json_object_get(r.json, "jobs");
    CHECK(r.status == 200 && json_array_size(jobs) == 1 && !json_object_get(r.json, "next") &&
          strcmp(str(json_array_get(jobs, 0), "id"), ids[0]) == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs?order=sideways", NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "order") == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs?limit=0", NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "limit") == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs?colour=red", NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) != NULL);
    reply_finish(&r);

    /* The first job runs and finishes: its result, its links and its files. */
    finish_next(q, ids[0]);
    snprintf(path, sizeof(path), "/v1/jobs/%s?wait=5", ids[0]);
    r = request(port, "GET", path, NULL, NULL);
    json_t *capture = json_array_get(json_object_get(json_object_get(r.json, "result"), "captures"), 0);
    char frame_url[128];
    snprintf(frame_url, sizeof(frame_url), "/v1/jobs/%s/frames/2.png", ids[0]);
    CHECK(r.status == 200 && strcmp(str(r.json, "status"), "done") == 0);
    CHECK(str(capture, "url") && strcmp(str(capture, "url"), frame_url) == 0);
    char timings_url[128];
    snprintf(timings_url, sizeof(timings_url), "/v1/jobs/%s/%s", ids[0], JOB_FILE_TIMINGS);
    CHECK(str(r.json, "timings_url") && strcmp(str(r.json, "timings_url"), timings_url) == 0);
    reply_finish(&r);
    r = request(port, "GET", timings_url, NULL, NULL);
    CHECK(r.status == 200 && strncmp(r.body, "frame,gpu_ms", 12) == 0);
    reply_finish(&r);
    r = request(port, "GET", frame_url, NULL, NULL);
    CHECK(r.status == 404 && error_field(&r) && strcmp(error_field(&r), "frame") == 0);
    reply_finish(&r);
    /* Its workload's history: the one done job, no change to flag. */
    snprintf(path, sizeof(path), "/v1/jobs/%s/history", ids[0]);
    r = request(port, "GET", path, NULL, NULL);
    CHECK(r.status == 200 && json_array_size(json_object_get(r.json, "points")) == 1 &&
          json_array_size(json_object_get(r.json, "changes")) == 0 &&
          strcmp(str(json_object_get(r.json, "workload"), "technique"), "unlit") == 0 &&
          !json_object_get(json_object_get(r.json, "workload"), "labels"));
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs/1-2/history", NULL, NULL);
    CHECK(r.status == 404);
    reply_finish(&r);
    snprintf(path, sizeof(path), "/v1/jobs/%s/history?figure=fps", ids[0]);
    r = request(port, "GET", path, NULL, NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "figure") == 0);
    reply_finish(&r);

    /* DELETE: a queued job is cancelled at once; a finished one is 409. */
    snprintf(path, sizeof(path), "/v1/jobs/%s", ids[1]);
    r = request(port, "DELETE", path, NULL, NULL);
    CHECK(r.status == 200 && strcmp(str(r.json, "status"), "cancelled") == 0);
    reply_finish(&r);
    snprintf(path, sizeof(path), "/v1/jobs/%s", ids[0]);
    r = request(port, "DELETE", path, NULL, NULL);
    CHECK(r.status == 409);
    reply_finish(&r);

    /* /metrics counts the store's jobs by status, in Prometheus' text form. */
    r = request(port, "GET", "/metrics", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "# TYPE ") && strstr(r.body, "shadebench_"));
    reply_finish(&r);

    /* A health check has connections of its own: past an address's 3, the
     * next CONNECTIONS_HEALTH_RESERVE serve /healthz and /metrics only (and
     * close after one answer); past those, libmicrohttpd refuses. */
    int hogs[3 + CONNECTIONS_HEALTH_RESERVE];
    for (int i = 0; i < 3; i++)
        hogs[i] = connect_to(port); /* open, and silent: each holds its slot */
    wait_connections(http, 3);
    r = request(port, "GET", "/v1/info", NULL, NULL);
    CHECK(r.status == 429 && error_field(&r) && strcmp(error_field(&r), "connections") == 0 &&
          strstr(r.body, "/healthz"));
    reply_finish(&r);
    r = request(port, "GET", "/healthz", NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);
    r = request(port, "GET", "/metrics", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "shadebench_render_up 1"));
    reply_finish(&r);
    for (int i = 3; i < 3 + CONNECTIONS_HEALTH_RESERVE; i++)
        hogs[i] = connect_to(port);
    /* On a loaded machine libmicrohttpd may still count a closed connection
     * of the requests above, and refuse a hog (closing it unanswered) while
     * the count still shows the closed one: the check needs every reserve
     * slot held by a hog, which it then must refuse past. A refused hog is
     * opened again until all of them hold. */
    bool full = false;
    /* At most 10 s for the first fill, 1 s for each refill after it. */
    for (int round = 0; round < 10 && !full; round++) {
        full = wait_connections_ms(http, 3 + CONNECTIONS_HEALTH_RESERVE, round ? 1000 : 10000);
        sleep_ms(50); /* a refusal's close reaches the hog */
        for (int i = 0; i < 3 + CONNECTIONS_HEALTH_RESERVE; i++)
            if (!hog_held(hogs[i])) {
                full = false;
                if (hogs[i] >= 0)
                    close(hogs[i]);
                hogs[i] = connect_to(port);
            }
        full = full && http_server_open_connections(http) == 3 + CONNECTIONS_HEALTH_RESERVE;
    }
    r = request(port, "GET", "/healthz", NULL, NULL);
    if (!full)
        printf("test_http: the reserve never filled (%zu connections); not checked\n",
               http_server_open_connections(http));
    CHECK(!full || r.status == 0); /* closed unanswered */
    reply_finish(&r);
    for (int i = 0; i < 3 + CONNECTIONS_HEALTH_RESERVE; i++)
        if (hogs[i] >= 0)
            close(hogs[i]);
    wait_connections(http, 0);
    r = request(port, "GET", "/v1/info", NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);

    /* Assets: upload (201, then 200 for the same bytes), describe, list,
     * refusals naming the field, a job pinned to the hash, a delete refused
     * while that job is queued, then allowed. */
    r = request(port, "PUT", "/v1/assets/a.glb", "glTF asset one", NULL);
    CHECK(r.status == 201 && str(r.json, "sha256") && strlen(str(r.json, "sha256")) == 64 &&
          json_integer_value(json_object_get(json_object_get(r.json, "description"),
                                             "triangles")) == 12);
    char sha[65] = "";
    if (str(r.json, "sha256"))
        snprintf(sha, sizeof(sha), "%s", str(r.json, "sha256"));
    reply_finish(&r);
    char cache[PATH_MAX + 100];
    CHECK(asset_store_cache_path(state, sha, cache, sizeof(cache)) && access(cache, R_OK) == 0);
    CHECK(!asset_store_cache_path(state, "../../etc/passwd", cache, sizeof(cache)) && !cache[0]);
    r = request(port, "PUT", "/v1/assets/a.glb", "glTF asset one", NULL);
    CHECK(r.status == 200 && str(r.json, "sha256") && strcmp(str(r.json, "sha256"), sha) == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/assets/a.glb", NULL, NULL);
    CHECK(r.status == 200 && str(r.json, "sha256") && strcmp(str(r.json, "sha256"), sha) == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/assets", NULL, NULL);
    CHECK(r.status == 200 && json_array_size(json_object_get(r.json, "assets")) == 1 &&
          json_integer_value(json_object_get(
              json_object_get(json_array_get(json_object_get(r.json, "assets"), 0), "summary"),
              "meshes")) == 2);
    reply_finish(&r);
    r = request(port, "PUT", "/v1/assets/b.glb", "nope", NULL);
    CHECK(r.status == 422 && error_field(&r) && strcmp(error_field(&r), "magic") == 0);
    reply_finish(&r);
    r = request(port, "PUT", "/v1/assets/.b.glb", "glTF", NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "name") == 0);
    reply_finish(&r);
    r = request(port, "POST", "/v1/assets/b.glb", "glTF", NULL);
    CHECK(r.status == 405 && strstr(r.body, "PUT"));
    reply_finish(&r);
    static const char big_put[] = "PUT /v1/assets/c.glb HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                                  "Connection: close\r\nContent-Length: 5000\r\n\r\n";
    r = raw_request(port, big_put, sizeof(big_put) - 1);
    CHECK(r.status == 413 && error_field(&r) && strcmp(error_field(&r), "body") == 0);
    reply_finish(&r);
    r = request(port, "GET", "/v1/assets/b.glb", NULL, NULL);
    CHECK(r.status == 404 && error_field(&r) && strcmp(error_field(&r), "name") == 0);
    reply_finish(&r);
    r = request(port, "POST", "/v1/jobs",
                "{\"technique\":\"unlit\",\"frames\":2,\"scene\":{\"asset\":\"b.glb\"}}", NULL);
    CHECK(r.status == 400 && error_field(&r) && strcmp(error_field(&r), "scene.asset") == 0);
    reply_finish(&r);
    r = request(port, "POST", "/v1/jobs",
                "{\"technique\":\"unlit\",\"frames\":2,\"scene\":{\"asset\":\"a.glb\"}}", NULL);
    CHECK(r.status == 202 && str(r.json, "id"));
    char asset_job[32] = "";
    if (str(r.json, "id"))
        snprintf(asset_job, sizeof(asset_job), "%s", str(r.json, "id"));
    reply_finish(&r);
    char job_path[64];
    snprintf(job_path, sizeof(job_path), "/v1/jobs/%s", asset_job);
    r = request(port, "GET", job_path, NULL, NULL);
    CHECK(r.status == 200 &&
          str(json_object_get(json_object_get(r.json, "spec"), "scene"), "asset_sha256") &&
          strcmp(str(json_object_get(json_object_get(r.json, "spec"), "scene"), "asset_sha256"),
                 sha) == 0);
    reply_finish(&r);
    r = request(port, "DELETE", "/v1/assets/a.glb", NULL, NULL);
    CHECK(r.status == 409 && strstr(r.body, asset_job));
    reply_finish(&r);
    r = request(port, "DELETE", job_path, NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);
    r = request(port, "DELETE", "/v1/assets/a.glb", NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);
    CHECK(asset_store_cache_path(state, sha, cache, sizeof(cache)) && access(cache, F_OK) != 0);
    struct store_asset gone;
    CHECK(store_asset_get(store, "a.glb", &gone) == STORE_MISSING);
    store_asset_finish(&gone);

    /* With a token, everything but /healthz needs it. */
    CHECK(http_server_set_token(http, "s3cret"));
    r = request(port, "GET", "/v1/info", NULL, NULL);
    CHECK(r.status == 401 && error_field(&r) != NULL);
    reply_finish(&r);
    r = request(port, "GET", "/v1/info", NULL, "Authorization: Bearer wrong\r\n");
    CHECK(r.status == 401);
    reply_finish(&r);
    r = request(port, "GET", "/v1/info", NULL, "Authorization: Bearer s3cret\r\n");
    CHECK(r.status == 200);
    reply_finish(&r);
    r = request(port, "GET", "/healthz", NULL, NULL);
    CHECK(r.status == 200);
    reply_finish(&r);
    /* The dashboard's files hold no data: served without the token, which
     * the page then asks for; an unknown file is a 404. */
    r = request(port, "GET", "/", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "/ui/app.js"));
    reply_finish(&r);
    r = request(port, "GET", "/ui/api.js", NULL, NULL);
    CHECK(r.status == 200 && strstr(r.body, "Authorization"));
    reply_finish(&r);
    r = request(port, "GET", "/ui/nothing.js", NULL, NULL);
    CHECK(r.status == 404);
    reply_finish(&r);
    r = request(port, "GET", "/v1/jobs", NULL, NULL);
    CHECK(r.status == 401);
    reply_finish(&r);

    http_server_destroy(http);
    sweeps_destroy(sweeps);
    queue_set_asset_hooks(q, NULL);
    assets_destroy(assets);
    queue_stop(q);
    queue_destroy(q);
    store_close(store);
    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof(cmd), "rm -rf %s", state);
    CHECK(system(cmd) == 0);
    return check_finish("test_http");
}
