#define _POSIX_C_SOURCE 200809L
/* /healthz, /v1/info and /metrics: the daemon's state as the API shows it
 * (server.h). Cheap: /healthz and /metrics read the render thread's state
 * lock-free. */
#include "daemon/api/server.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "daemon/effects/effect_info.h"
#include "daemon/quality/metrics.h"
#include "daemon/jobs/fidelity.h"
#include "daemon/spec/job_cost.h"
#include "daemon/spec/job_spec.h"
#include "daemon/spec/sweep_spec.h"
#include "daemon/status/telemetry.h"

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

/* How to read the difference maps back (the dashboard stretches their
 * contrast): the FLIP map's ramp, and the SSIM map's encoding. */
static json_t *maps_json(void)
{
    const float(*stops)[3];
    int n = metrics_flip_ramp(&stops);
    json_t *ramp = json_array();
    for (int i = 0; i < n; i++)
        json_array_append_new(ramp, json_pack("[f, f, f]", stops[i][0], stops[i][1], stops[i][2]));
    return json_pack("{s:{s:o, s:s}, s:{s:s, s:i}}", "flip", "ramp", ramp, "encoding",
                     "each pixel's FLIP value v (0 to 1) on the ramp's stops, evenly spaced, "
                     "linearly between them, in sRGB bytes", "ssim", "encoding",
                     "grey: the local luma SSIM times 255, clamped to [0, 1] (white = 1)",
                     "inset_px", SSIM_WINDOW / 2);
}

json_t *info_json(struct http_server *s)
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
        /* What an upload's client must keep to its slot (connections.h). */
        json_object_set_new(assets, "max_uploads_per_address", json_integer(l->uploads_per_ip));
        json_object_set_new(assets, "upload_min_bytes_per_s", json_real(l->upload_min_rate));
        json_object_set_new(assets, "upload_rate_window_s", json_real(l->upload_window_s));
        json_object_set_new(limits, "assets", assets);
    }
    json_object_set_new(info, "maps", maps_json());
    json_object_set_new(info, "reference", fidelity_info_json(s->ctx.fidelity));
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

/* GET /healthz: cheap (no store query), and true: 503 when the render
 * thread has stopped, or has made no progress for longer than the bound
 * while a job is on it, which no other endpoint would show (a job that
 * holds the GPU for minutes still left every other answer quick); 200
 * "disk full" while the state directory's disk is (reads served, writes
 * refused until there is room). */
enum MHD_Result respond_healthz(struct http_server *s, struct MHD_Connection *c)
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
    /* A full disk: the daemon serves what it has (reads, results) but
     * accepts nothing new until there is room, which it finds by itself. */
    struct store *store = queue_store(s->queue);
    if (store_disk_full(store) && !store_has_room(store))
        return respond_json(
            c, MHD_HTTP_OK,
            json_pack("{s:s, s:s, s:o}", "status", "disk full", "message",
                      "the state directory's disk is full: results are served, but jobs, "
                      "sweeps and assets are refused (507) until there is room again; "
                      "free some space and it recovers by itself",
                      "render", render));
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
enum MHD_Result respond_metrics(struct http_server *s, struct MHD_Connection *c)
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
    fprintf(f, "# HELP shadebench_http_uploads Uploads holding a slot (streaming or converting).\n"
               "# TYPE shadebench_http_uploads gauge\n"
               "shadebench_http_uploads %zu\n"
               "# HELP shadebench_http_uploads_slow_total Uploads cut for bringing their body "
               "slower than the minimum rate.\n"
               "# TYPE shadebench_http_uploads_slow_total counter\n"
               "shadebench_http_uploads_slow_total %llu\n", cs.uploads, cs.slow_uploads);
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
