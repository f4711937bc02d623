/* GET /v1/jobs/ID/pdiff/K.png: PerceptualDiff's failing pixels of capture
 * K against its reference, white on black, at the capture's size. The job
 * records the count (captures[].metrics.pdiff.failing_pixels) but not
 * where they are: the mask is made on request from the two stored PNGs
 * with the job's own options (its spec's metrics.pdiff), so it shows
 * exactly the pixels counted. Runs on a polling thread; at most
 * PDIFF_MASKS_AT_ONCE at a time (tens of milliseconds each at 1080x720 on
 * llvmpipe's box, longer for large captures), so that masks cannot hold
 * the server's threads: beyond that, 429 naming "pdiff". */
#define _POSIX_C_SOURCE 200809L
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/job_files.h"
#include "common/png_io.h"
#include "common/result_keys.h"
#include "daemon/api/server.h"
#include "daemon/quality/metrics.h"

enum { PDIFF_MASKS_AT_ONCE = 1 };
static atomic_int masks_running;

/* The job's PerceptualDiff options, as its spec states them (every field
 * filled in by the daemon when it accepted the job), over the defaults. */
static void options_of(const json_t *job, struct pdiff_options *o)
{
    pdiff_defaults(o);
    json_t *p = json_object_get(json_object_get(json_object_get(job, "spec"), "metrics"), "pdiff");
    json_t *v;
    if ((v = json_object_get(p, "fov")) && json_is_number(v))
        o->fov = json_number_value(v);
    if ((v = json_object_get(p, "threshold_pixels")) && json_is_integer(v))
        o->threshold_pixels = (long)json_integer_value(v);
    if ((v = json_object_get(p, "gamma")) && json_is_number(v))
        o->gamma = json_number_value(v);
    if ((v = json_object_get(p, "luminance")) && json_is_number(v))
        o->luminance = json_number_value(v);
    if ((v = json_object_get(p, "color_factor")) && json_is_number(v))
        o->color_factor = json_number_value(v);
    if ((v = json_object_get(p, "luminance_only")) && json_is_boolean(v))
        o->luminance_only = json_is_true(v);
}

static bool captured_with_pdiff(const json_t *job, int frame)
{
    size_t i;
    json_t *c;
    json_array_foreach(json_object_get(json_object_get(job, RK_RESULT), RK_CAPTURES), i, c)
        if (json_integer_value(json_object_get(c, "frame")) == frame)
            return json_is_object(json_object_get(json_object_get(c, "metrics"), "pdiff"));
    return false;
}

enum MHD_Result respond_pdiff_mask(struct http_server *s, struct MHD_Connection *c,
                                   const struct route *r, const char *dir)
{
    json_t *job = queue_job_json(s->queue, r->id, 0);
    if (!job)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    bool scored = captured_with_pdiff(job, r->frame);
    struct pdiff_options o;
    options_of(job, &o);
    json_decref(job);
    if (!scored)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "frame",
                             "no such mask: this frame was not captured, or not scored by "
                             "PerceptualDiff against a reference (see result.captures)");
    if (atomic_fetch_add(&masks_running, 1) >= PDIFF_MASKS_AT_ONCE) {
        atomic_fetch_sub(&masks_running, 1);
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "pdiff",
                             "another PerceptualDiff mask is being made; retry in a moment");
    }
    char path[PATH_MAX + 64], err[256] = "";
    struct image test = {0}, ref = {0}, mask = {0};
    struct pdiff_result res;
    unsigned char *png = NULL;
    size_t len = 0, n = 0;
    uint8_t *failing = NULL;
    bool ok = job_image_path(dir, JOB_IMAGE_FRAME, r->frame, path, sizeof(path)) &&
              png_read_rgb(path, &test, err, sizeof(err)) &&
              job_image_path(dir, JOB_IMAGE_REFERENCE, r->frame, path, sizeof(path)) &&
              png_read_rgb(path, &ref, err, sizeof(err));
    if (ok) {
        n = (size_t)test.width * (size_t)test.height;
        failing = calloc(n ? n : 1, 1);
        mask = (struct image){test.width, test.height, malloc(n * 3 + 1)};
        ok = failing && mask.rgb &&
             pdiff_compute_mask(&ref, &test, &o, NULL, &res, failing, err, sizeof(err));
    }
    if (ok) {
        for (size_t i = 0; i < n; i++)
            memset(mask.rgb + 3 * i, failing[i] ? 255 : 0, 3);
        png = png_encode_thumbnail(&mask, mask.width, &len);
        ok = png != NULL;
        if (!ok)
            snprintf(err, sizeof(err), "out of memory");
    }
    free(failing);
    image_finish(&test);
    image_finish(&ref);
    image_finish(&mask);
    atomic_fetch_sub(&masks_running, 1);
    if (!ok)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "frame", err[0] ? err : "failed");
    char count[32];
    snprintf(count, sizeof(count), "%ld", res.failing_pixels);
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, png, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(png);
        return MHD_NO;
    }
    MHD_add_response_header(resp, "Content-Type", "image/png");
    MHD_add_response_header(resp, "X-Failing-Pixels", count);
    connections_set_status(connections_of(c), MHD_HTTP_OK);
    enum MHD_Result ret = MHD_queue_response(c, MHD_HTTP_OK, resp);
    MHD_destroy_response(resp);
    return ret;
}
