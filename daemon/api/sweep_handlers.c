#define _POSIX_C_SOURCE 200809L
/* /v1/sweeps: submitting, reading, waiting on and cancelling a sweep, its
 * charts and report (server.h). */
#include "daemon/api/server.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/api/links.h"
#include "daemon/reports/charts.h"
#include "daemon/reports/report.h"
#include "daemon/reports/sweep_verdict.h"
#include "daemon/spec/sweep_spec.h"

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

json_t *served_sweep(struct http_server *s, const char *id)
{
    json_t *sw = sweeps_json(s->sweeps, id, 0);
    links_add_sweep(sw);
    return sw;
}

bool sweep_json_finished(const json_t *sw)
{
    const char *st = json_string_value(json_object_get(sw, "status"));
    return !st || (strcmp(st, "queued") != 0 && strcmp(st, "running") != 0);
}

enum MHD_Result post_sweep(struct http_server *s, struct MHD_Connection *c,
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
    if (!jf_check_numbers(req->body ? req->body : "", req->len, &err)) {
        json_decref(body);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    }
    if (!sweep_spec_parse(body, s->ctx.catalog, &spec, &err)) {
        sweep_spec_finish(&spec);
        json_decref(body);
        return respond_json(c, MHD_HTTP_BAD_REQUEST, job_error_to_json(&err));
    }
    /* A sweep on an asset: refused now, with the rule's status, rather than
     * at its first point; sweeps_submit pins the hash for all its points. */
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
    if (r == QUEUE_REFUSED) /* the asset was deleted since the probe above */
        return respond_error(c, MHD_HTTP_CONFLICT, "base.scene.asset", queue_submit_error());
    if (r != QUEUE_OK)
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "body",
                             "too many sweeps are waiting; retry later");
    char url[ROUTE_URL_MAX];
    route_sweep_url(id, url);
    return respond_json(c, MHD_HTTP_ACCEPTED,
                        json_pack("{s:s, s:s, s:s}", "id", id, "status", "queued", "url", url));
}

/* GET /v1/sweeps/ID/verdict: the report's verdict as JSON (sweep_verdict.h),
 * for ?series= or the one that means something on the device. */
static enum MHD_Result respond_verdict(struct http_server *s, struct MHD_Connection *c,
                                       const json_t *sw)
{
    const char *series = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "series");
    if (series && strcmp(series, RK_FRAME_MS) && strcmp(series, RK_GPU_MS) &&
        strcmp(series, RK_CPU_MS))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "series", "must be frame_ms, gpu_ms or cpu_ms");
    if (!series) {
        json_t *device = s->ctx.device_json(s->ctx.render);
        series = charts_default_series(device);
        json_decref(device);
    }
    return respond_json(c, MHD_HTTP_OK, sweep_verdict_json(sw, series));
}

enum MHD_Result sweep_resource(struct http_server *s, struct MHD_Connection *c,
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
        if (wait > 0 && !sweep_json_finished(sw)) {
            json_decref(sw);
            return suspend_request(s, c, req, WAIT_SWEEP, wait, MHD_HTTP_OK);
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
            return suspend_request(s, c, req, WAIT_SWEEP, CANCEL_WAIT_S, MHD_HTTP_ACCEPTED);
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
    } else if (r->kind == ROUTE_SWEEP_VERDICT) {
        ret = respond_verdict(s, c, sw);
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
