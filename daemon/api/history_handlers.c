/* GET /v1/jobs/ID/history: the done jobs of ID's workload, oldest first,
 * with one figure's median and interval, their noise, and the changes the
 * client's timing gate would flag between them (daemon/reports/history.h
 * has the rules). Read from the store: the technique's done jobs, newest
 * first, at most HISTORY_SCAN of them, each spec compared with ID's.
 * Runs on a polling thread. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/api/job_filter.h"
#include "daemon/api/server.h"
#include "daemon/reports/charts.h"
#include "daemon/reports/history.h"
#include "daemon/store/job_dir.h"
#include "daemon/store/records.h"

enum { HISTORY_SCAN = 2000, HISTORY_POINTS_DEFAULT = 100, HISTORY_POINTS_MAX = 1000 };

static bool is_technique(void *ctx, const char *key)
{
    return technique_catalog_find(ctx, key) >= 0;
}

struct candidates {
    json_t *rows; /* [{"id", "created", "figures", "labels"}] */
};

static void take_row(void *ctx, const struct store_row *row)
{
    struct candidates *c = ctx;
    char created[32];
    job_filter_format_time((int64_t)(row->created * 1000.0), created);
    json_array_append_new(c->rows, json_pack("{s:s, s:s, s:O?, s:O?}", "id", row->id, "created",
                                             created, "figures", row->figures, "labels",
                                             row->labels));
}

/* A stored job's spec, from its row or its directory; NULL when gone. */
static json_t *spec_of(struct store *st, const char *id, char *dir, size_t cap)
{
    struct store_row row;
    json_t *spec = NULL;
    if (store_get(st, STORE_JOBS, id, true, &row) == STORE_FOUND) {
        spec = row.spec ? json_incref(row.spec) : job_dir_read_spec(&row);
        snprintf(dir, cap, "%s", row.dir);
    }
    store_row_finish(&row);
    return spec;
}

static bool arg_int(struct MHD_Connection *c, const char *key, int lo, int hi, int *out)
{
    const char *v = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, key);
    if (!v)
        return true;
    char *end;
    long n = strtol(v, &end, 10);
    if (!*v || *end || n < lo || n > hi)
        return false;
    *out = (int)n;
    return true;
}

enum MHD_Result respond_history(struct http_server *s, struct MHD_Connection *c,
                                const struct route *r)
{
    struct store *st = queue_store(s->queue);
    int limit = HISTORY_POINTS_DEFAULT;
    if (!arg_int(c, "limit", 1, HISTORY_POINTS_MAX, &limit))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "limit", "must be an integer from 1 to 1000");
    const char *figure = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "figure");
    if (figure && strcmp(figure, RK_FRAME_MS) && strcmp(figure, RK_GPU_MS) && strcmp(figure, RK_CPU_MS))
        return respond_error(c, MHD_HTTP_BAD_REQUEST, "figure", "must be frame_ms, gpu_ms or cpu_ms");
    char dir[PATH_MAX], path[PATH_MAX + 32], err[240] = "";
    struct store_row self;
    if (store_get(st, STORE_JOBS, r->id, true, &self) != STORE_FOUND) {
        store_row_finish(&self);
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    }
    json_t *spec = self.spec ? json_incref(self.spec) : job_dir_read_spec(&self);
    if (!figure) /* the series that means something on the job's device */
        figure = charts_default_series(self.figures);
    store_row_finish(&self);
    const char *technique = json_string_value(json_object_get(spec, "technique"));
    if (!technique) {
        json_decref(spec);
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "the job's spec cannot be read");
    }

    /* The technique's done jobs, newest first, page by page. */
    struct candidates cand = {json_array()};
    struct store_query q;
    job_filter_init(&q, STORE_JOBS);
    q.newest = true;
    q.limit = STORE_LIMIT_MAX;
    q.nterms = 2;
    q.terms[0].kind = STORE_TERM_TECHNIQUE;
    snprintf(q.terms[0].value, sizeof(q.terms[0].value), "%s", technique);
    q.terms[1].kind = STORE_TERM_STATUS;
    snprintf(q.terms[1].value, sizeof(q.terms[1].value), "done");
    char next[RECORD_ID_LEN];
    bool ok = true;
    do {
        ok = store_list(st, &q, take_row, &cand, next, err, sizeof(err));
        snprintf(q.after, sizeof(q.after), "%s", next);
    } while (ok && next[0] && json_array_size(cand.rows) < HISTORY_SCAN);
    if (!ok) {
        json_decref(spec);
        json_decref(cand.rows);
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "store", err);
    }

    json_t *points = json_array();
    size_t i, scanned = 0;
    json_t *row;
    json_array_foreach(cand.rows, i, row) {
        if (i >= HISTORY_SCAN || json_array_size(points) >= (size_t)limit)
            break;
        scanned++;
        const char *id = json_string_value(json_object_get(row, "id"));
        json_t *other = spec_of(st, id, dir, sizeof(dir));
        bool same = other && history_same_workload(spec, other, is_technique,
                                                    (void *)s->ctx.catalog);
        json_decref(other);
        json_t *fig = json_object_get(json_object_get(row, "figures"), figure);
        if (!same || !json_is_object(fig))
            continue;
        /* The noise of its run: the result's interference figures. */
        snprintf(path, sizeof(path), "%s/%s", dir, "result.json");
        char why[256];
        json_t *result = record_read(path, why, sizeof(why));
        json_t *inter = json_object_get(result, RK_INTERFERENCE);
        json_t *point = json_pack("{s:O, s:O, s:O, s:O, s:O?, s:b, s:O?, s:O?, s:O?}", "id",
                                  json_object_get(row, "id"), "created",
                                  json_object_get(row, "created"), "median",
                                  json_object_get(fig, RK_MEDIAN), "ci95",
                                  json_object_get(fig, RK_CI95), "over",
                                  json_object_get(fig, "over"), "noisy",
                                  json_is_true(json_object_get(inter, "noisy")),
                                  "other_cpu_share", json_object_get(inter, "other_cpu_share"),
                                  "worst_ssim",
                                  json_object_get(json_object_get(row, "figures"), RK_WORST_SSIM),
                                  "labels", json_object_get(row, "labels"));
        json_decref(result);
        if (point)
            json_array_insert_new(points, 0, point); /* oldest first */
    }
    json_decref(cand.rows);
    json_t *workload = json_object();
    const char *k;
    json_t *v;
    json_object_foreach(spec, k, v) {
        bool other = strcmp(k, technique) != 0 && technique_catalog_find(s->ctx.catalog, k) >= 0;
        if (!history_ignored_field(k, other))
            json_object_set(workload, k, v);
    }
    json_decref(spec);
    json_t *body = json_pack(
        "{s:s, s:s, s:o, s:o, s:o, s:I, s:b, s:{s:f, s:s, s:s}}", "job", r->id, "figure", figure,
        "workload", workload, "points", points, "changes",
        history_changes(points, HISTORY_MIN_EFFECT), "scanned", (json_int_t)scanned, "complete",
        scanned < HISTORY_SCAN, "rule", "min_effect", HISTORY_MIN_EFFECT, "same_workload",
        "the job's technique and spec, but for the fields the gate ignores (labels, repeat, "
        "capture_interval, reference, metrics, timeout_s, reference_look) and other techniques' "
        "options", "change",
        "later / earlier median, interval [lo_b / hi_a, hi_b / lo_a] from their 95% intervals, "
        "noisy runs left out: slower when the interval lies above 1 and the ratio above 1 + "
        "min_effect (the gate's regression), faster when it lies below 1 and the ratio below "
        "1 / (1 + min_effect)");
    return respond_json(c, MHD_HTTP_OK, body);
}
