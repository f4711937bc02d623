#define _POSIX_C_SOURCE 200809L
/* /v1/assets: the list, an asset's description, a delete, and an upload
 * (its body streamed into daemon/jobs/assets.h, then a wait on its
 * conversion without a thread, as a long-poll waits) (server.h). */
#include "daemon/api/server.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/scene_spec.h"

/* The status that answers each cause of a refusal (assets.h). */
static unsigned refusal_status(enum assets_cause cause)
{
    switch (cause) {
    case ASSETS_INVALID:
        return MHD_HTTP_BAD_REQUEST;
    case ASSETS_READ_ONLY:
        return MHD_HTTP_FORBIDDEN;
    case ASSETS_NOT_FOUND:
        return MHD_HTTP_NOT_FOUND;
    case ASSETS_CONFLICT:
        return MHD_HTTP_CONFLICT;
    case ASSETS_TOO_LARGE:
        return MHD_HTTP_CONTENT_TOO_LARGE;
    case ASSETS_UNCONVERTIBLE:
        return MHD_HTTP_UNPROCESSABLE_CONTENT;
    case ASSETS_BUSY:
        return MHD_HTTP_TOO_MANY_REQUESTS;
    case ASSETS_STOPPING:
        return MHD_HTTP_SERVICE_UNAVAILABLE;
    case ASSETS_NO_SPACE:
        return MHD_HTTP_INSUFFICIENT_STORAGE;
    case ASSETS_INTERNAL:
        break;
    }
    return MHD_HTTP_INTERNAL_SERVER_ERROR;
}

/* An asset's URL, /v1/assets/NAME. */
static void asset_url(const char *name, char *out, size_t cap)
{
    snprintf(out, cap, "/v1/assets/%s", name);
}

/* Consumes record: the same with its url, after read_only (or last). */
static json_t *with_url(json_t *record)
{
    const char *name = json_string_value(json_object_get(record, "name"));
    if (!record || !name)
        return record;
    char url[STORE_ASSET_NAME_CAP + 16];
    asset_url(name, url, sizeof(url));
    json_t *out = json_object();
    const char *key;
    json_t *v;
    bool placed = false;
    json_object_foreach(record, key, v) {
        json_object_set(out, key, v);
        if (strcmp(key, "read_only") == 0) {
            json_object_set_new(out, "url", json_string(url));
            placed = true;
        }
    }
    if (!placed)
        json_object_set_new(out, "url", json_string(url));
    json_decref(record);
    return out;
}

/* GET /v1/assets: the page, each record with its url, the next page's. */
static json_t *list_json(const struct assets_page *page, int limit)
{
    json_t *items = json_array();
    size_t i;
    json_t *v;
    json_array_foreach(page->items, i, v)
        json_array_append_new(items, with_url(json_incref(v)));
    json_t *o = json_pack("{s:o}", "assets", items);
    if (o && page->next[0]) {
        char url[STORE_ASSET_NAME_CAP + 64];
        snprintf(url, sizeof(url), "/v1/assets?limit=%d&cursor=%s", limit, page->next);
        json_object_set_new(o, "next", json_string(url));
    }
    if (o && (page->converting || page->failed))
        json_object_set_new(o, "asset_dir", json_pack("{s:I, s:I}", "converting",
                                                      (json_int_t)page->converting, "failed",
                                                      (json_int_t)page->failed));
    return o;
}

/* An asset's refusal (assets.h): its message may be longer than a job
 * error's 256 bytes (it can name a path). */
enum MHD_Result respond_asset_error(struct MHD_Connection *c, const struct assets_error *e)
{
    return respond_json(c, refusal_status(e->cause),
                        json_pack("{s:{s:s, s:s}}", "error", "field", e->field[0] ? e->field : "body",
                                  "message", e->message));
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
enum MHD_Result asset_resource(struct http_server *s, struct MHD_Connection *c,
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
        struct assets_page page;
        if (!assets_list(s->ctx.assets, a.cursor, a.limit, &page, &e))
            return respond_asset_error(c, &e);
        body = list_json(&page, a.limit);
        json_decref(page.items);
    } else if (req->route.asset_too_long) {
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "name",
                             "an asset name is at most 128 bytes");
    } else if (strcmp(method, "DELETE") == 0) {
        body = assets_delete(s->ctx.assets, req->route.asset, &e);
    } else {
        body = assets_describe(s->ctx.assets, req->route.asset, &e);
        if (!body)
            return respond_asset_error(c, &e);
        body = with_url(body);
    }
    if (!body)
        return respond_asset_error(c, &e);
    return respond_json(c, MHD_HTTP_OK, body);
}

/* The upload's body is in: its conversion is queued and the request waits
 * for it without a thread (connections.h), as a long-poll does. */
enum MHD_Result finish_upload(struct http_server *s, struct MHD_Connection *c,
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

bool begin_upload(struct http_server *s, struct MHD_Connection *c, struct request *req,
                  const char *cl, enum MHD_Result *ret)
{
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
    /* An address's share of the upload slots, so that a slow client cannot
     * take them all (and its body must keep up a minimum rate:
     * connections.h). */
    double retry_s = 0;
    if (!connections_upload_begin(s->conns, req->conn, &retry_s)) {
        char rule[200];
        snprintf(rule, sizeof(rule), "this address has %u uploads streaming or converting "
                 "already; retry after %.0f s", s->limits.uploads_per_ip, retry_s);
        *ret = respond_retry(c, "body", rule, retry_s);
        return true;
    }
    uint64_t length = cl ? strtoull(cl, NULL, 10) : 0;
    struct assets_error e = {0};
    req->upload = assets_upload_begin(s->ctx.assets, req->route.asset, length, &e);
    if (!req->upload) {
        req->too_large = e.cause == ASSETS_TOO_LARGE;
        *ret = e.cause == ASSETS_BUSY
                   ? respond_retry(c, e.field, e.message, connections_upload_retry_s(s->conns))
                   : respond_asset_error(c, &e);
        return true;
    }
    /* Its body's deadline grows with its size: 1 MiB/s at least; a body
     * slower than the minimum rate is cut sooner (connections.h). */
    uint64_t expect = length ? length : assets_max_bytes(s->ctx.assets);
    connections_body_deadline(s->conns, req->conn,
                              s->limits.body_timeout_s + (double)expect / (1 << 20));
    return false;
}

enum MHD_Result answer_upload(struct http_server *s, struct MHD_Connection *c,
                              struct request *req, enum wake why)
{
    struct assets_answer answer;
    if (s->ctx.assets && assets_ticket_take(s->ctx.assets, req->ticket, &answer)) {
        req->ticket = 0;
        if (!answer.record)
            return respond_asset_error(c, &answer.refusal);
        return respond_json(c, answer.replaced ? MHD_HTTP_OK : MHD_HTTP_CREATED,
                            with_url(answer.record));
    }
    return respond_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "body",
                         why == WAKE_TIMEOUT ? "the conversion is still waiting or running "
                                               "past its time; GET /v1/assets/NAME later"
                                             : "the daemon is stopping: the upload was not "
                                               "converted; upload it again once it is back");
}
