/* A job's difference views for people (diff_views.h). */
#define _POSIX_C_SOURCE 200809L
#include "daemon/reports/diff_views.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/job_files.h"
#include "common/result_keys.h"

void diff_views_pdiff_options(const json_t *job, struct pdiff_options *o)
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

bool diff_views_has_pdiff(const json_t *job, int frame)
{
    size_t i;
    json_t *c;
    json_array_foreach(json_object_get(json_object_get(job, RK_RESULT), RK_CAPTURES), i, c)
        if (json_integer_value(json_object_get(c, "frame")) == frame)
            return json_is_object(json_object_get(json_object_get(c, "metrics"), "pdiff"));
    return false;
}

bool diff_views_pdiff_mask(const json_t *job, const char *dir, int frame, struct image *mask,
                           long *failing, char *err, size_t errlen)
{
    struct pdiff_options o;
    diff_views_pdiff_options(job, &o);
    char path[PATH_MAX + 64];
    struct image test = {0}, ref = {0};
    struct pdiff_result res;
    uint8_t *bits = NULL;
    memset(mask, 0, sizeof(*mask));
    bool ok = job_image_path(dir, JOB_IMAGE_FRAME, frame, path, sizeof(path)) &&
              png_read_rgb(path, &test, err, errlen) &&
              job_image_path(dir, JOB_IMAGE_REFERENCE, frame, path, sizeof(path)) &&
              png_read_rgb(path, &ref, err, errlen);
    size_t n = ok ? (size_t)test.width * (size_t)test.height : 0;
    if (ok) {
        bits = calloc(n ? n : 1, 1);
        mask->rgb = malloc(n * 3 + 1);
        ok = bits && mask->rgb;
        if (!ok)
            snprintf(err, errlen, "out of memory");
    }
    /* The order the metrics stage scores in: the reference first. */
    ok = ok && pdiff_compute_mask(&ref, &test, &o, NULL, &res, bits, err, errlen);
    if (ok) {
        mask->width = test.width;
        mask->height = test.height;
        for (size_t i = 0; i < n; i++)
            memset(mask->rgb + 3 * i, bits[i] ? 255 : 0, 3);
        *failing = res.failing_pixels;
    } else {
        image_finish(mask);
    }
    free(bits);
    image_finish(&test);
    image_finish(&ref);
    return ok;
}
