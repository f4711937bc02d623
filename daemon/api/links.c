#include "daemon/api/links.h"

#include "daemon/api/job_filter.h"
#include "daemon/api/routes.h"
#include "common/result_keys.h"

#include <stdio.h>
#include <stdlib.h>

/* The images a capture entry of result.captures may name. */
static const enum job_image CAPTURE_IMAGES[] = {JOB_IMAGE_FRAME, JOB_IMAGE_REFERENCE,
                                                JOB_IMAGE_SSIM, JOB_IMAGE_FLIP};

/* Adds the URL of every file a capture entry names; heat map captures
 * (result.heatmap.captures) name one file each. */
static void link_captures(const char *id, json_t *captures, bool heatmap)
{
    size_t i;
    json_t *c;
    char url[ROUTE_URL_MAX];
    json_array_foreach(captures, i, c) {
        json_t *frame = json_object_get(c, "frame");
        if (!json_is_integer(frame))
            continue;
        int k = (int)json_integer_value(frame);
        size_t count = heatmap ? 1 : sizeof(CAPTURE_IMAGES) / sizeof(CAPTURE_IMAGES[0]);
        for (size_t f = 0; f < count; f++) {
            enum job_image image = heatmap ? JOB_IMAGE_HEATMAP : CAPTURE_IMAGES[f];
            const struct job_image_kind *kind = job_image_kind(image);
            if (!json_is_string(json_object_get(c, kind->file_key)))
                continue;
            route_image_url(id, image, k, url);
            json_object_set_new(c, kind->url_key, json_string(url));
        }
        /* Scored by PerceptualDiff against a reference: its failing pixels. */
        json_t *pdiff = json_object_get(json_object_get(c, "metrics"), "pdiff");
        if (!heatmap && json_is_object(pdiff) && json_is_string(json_object_get(c, "reference_file"))) {
            route_pdiff_url(id, k, url);
            json_object_set_new(c, "pdiff_mask_url", json_string(url));
        }
    }
}

void links_add_job(json_t *job)
{
    const char *id = json_string_value(json_object_get(job, "id"));
    if (!id)
        return;
    char url[ROUTE_URL_MAX];
    route_job_url(id, url);
    json_object_set_new(job, "url", json_string(url));
    json_t *result = json_object_get(job, RK_RESULT);
    if (result) {
        route_timings_url(id, url);
        json_object_set_new(job, "timings_url", json_string(url));
        route_history_url(id, url);
        json_object_set_new(job, "history_url", json_string(url));
    }
    link_captures(id, json_object_get(result, RK_CAPTURES), false);
    link_captures(id, json_object_get(json_object_get(result, RK_HEATMAP), RK_CAPTURES), true);
}

void links_add_sweep(json_t *sweep)
{
    const char *id = json_string_value(json_object_get(sweep, "id"));
    if (!id)
        return;
    char url[ROUTE_URL_MAX];
    route_sweep_url(id, url);
    json_object_set_new(sweep, "url", json_string(url));
    route_verdict_url(id, url);
    json_object_set_new(sweep, "verdict_url", json_string(url));
    size_t i;
    json_t *point;
    json_array_foreach(json_object_get(sweep, "points"), i, point) {
        const char *job = json_string_value(json_object_get(point, "job"));
        if (job) {
            route_job_url(job, url);
            json_object_set_new(point, "job_url", json_string(url));
        }
    }
}

void links_add_job_list(json_t *list)
{
    size_t i;
    json_t *job;
    json_array_foreach(json_object_get(list, "jobs"), i, job)
        links_add_job(job);
}

void links_add_sweep_list(json_t *list)
{
    size_t i;
    json_t *sweep;
    json_array_foreach(json_object_get(list, "sweeps"), i, sweep)
        links_add_sweep(sweep);
}

void links_add_next(json_t *list, enum route_kind kind, const struct store_query *q,
                    const char *next)
{
    if (!next || !next[0])
        return;
    /* The question as job_filter_add reads it: filters, since, limit, cursor. */
    const char *keys[STORE_MAX_TERMS + 4], *values[STORE_MAX_TERMS + 4];
    char names[STORE_MAX_TERMS][48], since[32], limit[16];
    size_t n = 0;
    for (size_t i = 0; i < q->nterms; i++) {
        const struct store_term *t = &q->terms[i];
        if (t->kind == STORE_TERM_LABEL)
            snprintf(names[i], sizeof(names[i]), "label.%s", t->label);
        else
            snprintf(names[i], sizeof(names[i]), "%s",
                     t->kind == STORE_TERM_TECHNIQUE ? "technique" : "status");
        keys[n] = names[i];
        values[n++] = t->value;
    }
    if (q->since_ms > 0) {
        job_filter_format_time(q->since_ms, since);
        keys[n] = "since";
        values[n++] = since;
    }
    if (q->newest) {
        keys[n] = "order";
        values[n++] = "newest";
    }
    snprintf(limit, sizeof(limit), "%d", q->limit);
    keys[n] = "limit";
    values[n++] = limit;
    keys[n] = "cursor";
    values[n++] = next;
    char *url = route_list_url(kind, n, keys, values);
    if (url)
        json_object_set_new(list, "next", json_string(url));
    free(url);
}
