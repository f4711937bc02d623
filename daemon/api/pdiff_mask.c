/* GET /v1/jobs/ID/pdiff/K.png: PerceptualDiff's failing pixels of capture
 * K against its reference, white on black, at the capture's size, with
 * their count in X-Failing-Pixels. The job records the count
 * (captures[].metrics.pdiff.failing_pixels) but not where they are: the
 * mask is made on request (daemon/reports/diff_views.c) from the two stored
 * PNGs with the job's own options, so it shows exactly the pixels counted.
 * Runs on a polling thread; at most PDIFF_MASKS_AT_ONCE at a time, so that
 * masks (a PerceptualDiff each, longer for large captures) cannot hold the
 * server's threads: beyond that, 429 naming "pdiff". */
#define _POSIX_C_SOURCE 200809L
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/png_io.h"
#include "daemon/api/server.h"
#include "daemon/reports/diff_views.h"

enum { PDIFF_MASKS_AT_ONCE = 1 };
static atomic_int masks_running;

enum MHD_Result respond_pdiff_mask(struct http_server *s, struct MHD_Connection *c,
                                   const struct route *r, const char *dir)
{
    json_t *job = queue_job_json(s->queue, r->id, 0);
    if (!job)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "id", "no such job");
    if (!diff_views_has_pdiff(job, r->frame)) {
        json_decref(job);
        return respond_error(c, MHD_HTTP_NOT_FOUND, "frame",
                             "no such mask: this frame was not captured, or not scored by "
                             "PerceptualDiff against a reference (see result.captures)");
    }
    if (atomic_fetch_add(&masks_running, 1) >= PDIFF_MASKS_AT_ONCE) {
        atomic_fetch_sub(&masks_running, 1);
        json_decref(job);
        return respond_error(c, MHD_HTTP_TOO_MANY_REQUESTS, "pdiff",
                             "another PerceptualDiff mask is being made; retry in a moment");
    }
    char err[256] = "";
    struct image mask;
    long failing = 0;
    size_t len = 0;
    unsigned char *png = NULL;
    if (diff_views_pdiff_mask(job, dir, r->frame, &mask, &failing, err, sizeof(err))) {
        png = png_encode_thumbnail(&mask, mask.width, &len);
        if (!png)
            snprintf(err, sizeof(err), "out of memory");
        image_finish(&mask);
    }
    json_decref(job);
    atomic_fetch_sub(&masks_running, 1);
    if (!png)
        return respond_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "frame", err[0] ? err : "failed");
    char count[32];
    snprintf(count, sizeof(count), "%ld", failing);
    struct MHD_Response *resp = MHD_create_response_from_buffer(len, png, MHD_RESPMEM_MUST_FREE);
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
