#define _POSIX_C_SOURCE 200809L
/* /v1/jobs: submitting, reading, waiting on and cancelling a job, its
 * report, charts and files, and the lists of jobs and sweeps (server.h). */
#include "daemon/api/server.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/job_files.h"
#include "common/log.h"
#include "common/result_keys.h"
#include "daemon/api/job_filter.h"
#include "daemon/api/links.h"
#include "daemon/reports/report.h"
#include "daemon/spec/job_cost.h"
#include "daemon/jobs/fidelity.h"
#include "daemon/jobs/job_eta.h"
#include "daemon/spec/job_spec.h"

/* A parsed job queued: its assets pinned, its 202 with the cost. */
static enum MHD_Result queue_spec(struct http_server *s, struct MHD_Connection *c,
                                  struct job_spec *sp)
{
    /* Refused at once where the Khronos reference is not installed: the
     * job could only fail. */
    char why[600];
    if (sp->fidelity.enabled && !fidelity_available(s->ctx.fidelity, why, sizeof(why))) {
        char msg[256];
        snprintf(msg, sizeof(msg), "the Khronos reference is not available: %.200s", why);
        return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "fidelity", msg);
    }
    struct job_spec spec = *sp;
    struct job_error err;
    /* Its assets (scene.asset, an environment map): resolved and pinned to
     * the stored hashes in one step here, so that the answer names the rule
     * (400 unknown, 409 a different pinned hash) and the asset's memory is
     * charged to the job (job_cost.h); queue_submit pins them again until
     * the job is live, and this pin goes after it. */
    bool pinned = false;
    if (job_spec_names_asset(&spec)) {
        struct assets_error ae;
        if (!s->ctx.assets)
            return respond_error(c, MHD_HTTP_BAD_REQUEST,
                                 spec.scene.asset[0] ? "scene.asset" : "look.ibl.environment",
                                 "this daemon has no asset store");
        if (!assets_pin(s->ctx.assets, &spec, false, &ae))
            return respond_asset_error(c, &ae);
        pinned = true;
        struct job_cost cost;
        job_cost_estimate(&spec, &cost);
        if (!job_cost_admit(&cost, &err)) {
            assets_unpin(s->ctx.assets, &spec);
            return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
        }
    }
    /* Its duration on this device, where a job of its technique has run: a
     * projection far past its timeout_s (or a frame far past the frame
     * bound) is refused with the figures (job_eta.h). */
    struct job_eta eta;
    job_eta_estimate(&spec, &eta);
    if (!job_eta_admit(&spec, &eta, &err)) {
        if (pinned)
            assets_unpin(s->ctx.assets, &spec);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    }
    char id[24];
    enum queue_submit_result submitted = queue_submit(s->queue, &spec, NULL, id);
    if (pinned)
        assets_unpin(s->ctx.assets, &spec);
    switch (submitted) {
    case QUEUE_OK:
        break;
    case QUEUE_REFUSED: /* held by the pin above: only an internal failure */
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

enum MHD_Result submit_job(struct http_server *s, struct MHD_Connection *c,
                           struct request *req)
{
    struct job_spec spec;
    struct job_error err;
    if (!job_spec_parse_text(req->body ? req->body : "", req->len, s->ctx.catalog,
                             &spec, &err))
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    return queue_spec(s, c, &spec);
}

/* POST /v1/assets/NAME/fidelity: a fidelity job of the asset (fidelity_spec.h). */
enum MHD_Result post_fidelity(struct http_server *s, struct MHD_Connection *c,
                              struct request *req)
{
    if (req->too_large)
        return respond_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body",
                             "the request must be at most 65536 bytes");
    if (req->route.asset_too_long)
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "name", "an asset name is at most 128 bytes");
    json_t *body = NULL;
    if (req->len) {
        json_error_t je;
        if (!(body = json_loadb(req->body, req->len, JSON_REJECT_DUPLICATES, &je))) {
            char msg[256];
            snprintf(msg, sizeof(msg), "malformed JSON at line %d, column %d: %s", je.line,
                     je.column, je.text);
            return respond_error(c, MHD_HTTP_BAD_REQUEST, "body", msg);
        }
    }
    struct job_error err = {0};
    json_t *job = fidelity_job_body(req->route.asset, body, &err);
    json_decref(body);
    struct job_spec spec;
    bool ok = job && job_spec_parse(job, s->ctx.catalog, &spec, &err);
    json_decref(job);
    if (!ok)
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    return queue_spec(s, c, &spec);
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
enum MHD_Result respond_list(struct http_server *s, struct MHD_Connection *c,
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

/* A job or sweep as the API serves it: the stored JSON plus its URLs. */
json_t *served_job(struct http_server *s, const char *id)
{
    json_t *job = queue_job_json(s->queue, id, 0);
    links_add_job(job);
    return job;
}

enum MHD_Result job_resource(struct http_server *s, struct MHD_Connection *c,
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
        if (wait > 0 && !job_status_finished(status))
            return suspend_request(s, c, req, WAIT_JOB, wait, MHD_HTTP_OK);
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
            return suspend_request(s, c, req, WAIT_JOB, CANCEL_WAIT_S, MHD_HTTP_ACCEPTED);
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
    if (r->kind == ROUTE_JOB_PDIFF)
        return respond_pdiff_mask(s, c, r, dir);
    if (r->kind == ROUTE_JOB_FIDELITY) {
        snprintf(path, sizeof(path), "%s/fidelity/%s", dir, r->chart);
        if (access(path, R_OK) != 0)
            return respond_error(c, MHD_HTTP_NOT_FOUND, "file",
                                 "no such image: see result.fidelity.channels.*.files");
        return respond_file(c, path, "image/png");
    }
    job_image_path(dir, r->image, r->frame, path, sizeof(path));
    if (access(path, R_OK) != 0)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "frame",
                             "no such image: this frame was not captured, or the job has no "
                             "reference or that metric (see result.captures)");
    return respond_file(c, path, "image/png");
}
