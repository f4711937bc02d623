/* One comparison of a test frame against its reference: the chosen metrics
 * as JSON, plus the SSIM and FLIP difference images. Shared by the daemon's
 * metrics thread and shadebench-compare so both report the same fields. */
#define _POSIX_C_SOURCE 200809L
#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/clock.h"
#include "daemon/quality/metrics.h"

void metrics_options_defaults(struct metrics_options *o)
{
    o->which = METRIC_ALL;
    pdiff_defaults(&o->pdiff);
    o->flip_ppd = flip_default_ppd();
}

/* Infinite PSNR (identical planes) is JSON null. */
static json_t *db(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

/* FLIP is the longest metric: it runs on a thread of its own beside the
 * others, and writes its map there too. */
struct flip_task {
    const struct image *ref, *test;
    double ppd;
    const char *map_path;
    const struct metrics_stop *stop;
    struct flip_result result;
    double ms;
    bool ok;
    char err[256];
};

static void *flip_thread(void *arg)
{
    struct flip_task *t = arg;
    double t0 = (clock_mono_s() * 1e3);
    t->ok = flip_compute(t->ref, t->test, t->ppd, t->map_path != NULL, t->stop, &t->result,
                         t->err, sizeof(t->err));
    if (t->ok && t->map_path) {
        if (!t->result.map) {
            snprintf(t->err, sizeof(t->err), "flip: out of memory for the map");
            t->ok = false;
        } else {
            t->ok = metrics_write_flip_map(t->map_path, &t->result, t->ref->width,
                                           t->ref->height, t->err, sizeof(t->err));
        }
    }
    free(t->result.map);
    t->result.map = NULL;
    t->ms = (clock_mono_s() * 1e3) - t0;
    return NULL;
}

double metrics_memory_bytes(int width, int height, double flip_ppd)
{
    double n = (double)width * (double)height;
    /* The two images, FLIP (its map and tiles) beside SSIM (its 8-bit map and
     * four planes' strips) and PerceptualDiff's tiles, and the PNG writer's
     * row for a map. */
    return 2.0 * n * 3.0 + (double)flip_memory_bytes(width, height, flip_ppd) +
           (double)ssim_memory_bytes(width, height) + (double)pdiff_memory_bytes(width, height) +
           2.0 * width * 3.0;
}

double metrics_alpha_memory_bytes(int width, int height)
{
    double n = (double)width * (double)height;
    return 2.0 * n + 2.0 * n * 3.0;
}

/* img's colours times its alpha, rounded to 8 bits: the image composited
 * over black. An opaque image is copied as it is. */
static bool premultiplied(const struct image *img, struct image *out)
{
    size_t n = (size_t)img->width * (size_t)img->height;
    *out = (struct image){.width = img->width, .height = img->height,
                          .rgb = malloc(n > 0 ? n * 3 : 1)};
    if (!out->rgb)
        return false;
    for (size_t i = 0; i < n; i++) {
        unsigned a = img->alpha ? img->alpha[i] : 255;
        for (int c = 0; c < 3; c++)
            out->rgb[3 * i + c] = (uint8_t)((img->rgb[3 * i + c] * a + 127) / 255);
    }
    return true;
}

json_t *metrics_compare(const struct image *ref, const struct image *test,
                        const struct metrics_options *o, const char *ssim_map_path,
                        const char *flip_map_path, const struct metrics_stop *stop, char *err,
                        size_t errlen)
{
    if (ref->width != test->width || ref->height != test->height) {
        snprintf(err, errlen, "image sizes differ: %dx%d and %dx%d", ref->width, ref->height,
                 test->width, test->height);
        return NULL;
    }
    if ((long long)ref->width * ref->height > IMAGE_MAX_PIXELS) {
        snprintf(err, errlen, "%dx%d is %lld pixels, over the limit of %lld", ref->width,
                 ref->height, (long long)ref->width * ref->height, IMAGE_MAX_PIXELS);
        return NULL;
    }
    /* PerceptualDiff premultiplies itself, in float; the others read the
     * premultiplied 8-bit copies of translucent images. */
    const struct image *pdiff_ref = ref, *pdiff_test = test;
    struct image pm_ref = {0}, pm_test = {0};
    if (ref->alpha || test->alpha) {
        if (!premultiplied(ref, &pm_ref) || !premultiplied(test, &pm_test)) {
            image_finish(&pm_ref);
            image_finish(&pm_test);
            snprintf(err, errlen, "out of memory for the premultiplied images");
            return NULL;
        }
        ref = &pm_ref;
        test = &pm_test;
    }
    struct flip_task flip = {.ref = ref, .test = test, .ppd = o->flip_ppd,
                             .map_path = flip_map_path, .stop = stop};
    double start = (clock_mono_s() * 1e3);
    pthread_t flip_tid;
    bool flip_threaded = false;
    if (o->which & METRIC_FLIP) {
        flip_threaded = pthread_create(&flip_tid, NULL, flip_thread, &flip) == 0;
        if (!flip_threaded)
            flip_thread(&flip);
    }
    json_t *out = json_object(), *timing = json_object();
    json_object_set_new(out, "timing_ms", timing);
    double t0 = (clock_mono_s() * 1e3);
    if (o->which & METRIC_SSIM) {
        struct ssim_result s;
        if (!ssim_compute(ref, test, ssim_map_path != NULL, stop, &s, err, errlen))
            goto fail;
        json_object_set_new(out, "ssim", json_real(s.luma));
        json_object_set_new(out, "ssim_rgb", json_real(s.rgb));
        json_object_set_new(out, "ssim_channels",
                            json_pack("[f, f, f]", s.channel[0], s.channel[1], s.channel[2]));
        json_object_set_new(out, "ssim_min",
                            json_pack("{s:f, s:i, s:i}", "value", s.min, "x", s.min_x, "y", s.min_y));
        bool ok = !ssim_map_path || metrics_write_ssim_map(ssim_map_path, &s, err, errlen);
        free(s.map);
        if (!ok)
            goto fail;
        json_object_set_new(timing, "ssim", json_real((clock_mono_s() * 1e3) - t0));
        t0 = (clock_mono_s() * 1e3);
    }
    if (o->which & METRIC_PDIFF) {
        struct pdiff_result p;
        if (!pdiff_compute(pdiff_ref, pdiff_test, &o->pdiff, stop, &p, err, errlen))
            goto fail;
        json_object_set_new(out, "pdiff",
                            json_pack("{s:b, s:I, s:f, s:I}", "pass", p.pass, "failing_pixels",
                                      (json_int_t)p.failing_pixels, "fov", o->pdiff.fov,
                                      "threshold_pixels", (json_int_t)o->pdiff.threshold_pixels));
        json_object_set_new(timing, "pdiff", json_real((clock_mono_s() * 1e3) - t0));
        t0 = (clock_mono_s() * 1e3);
    }
    if ((o->which & METRIC_PSNR) && !metrics_stopped(stop, err, errlen)) {
        struct psnr_result p;
        if (!psnr_compute(ref, test, &p, err, errlen))
            goto fail;
        json_object_set_new(out, "psnr",
                            json_pack("{s:o, s:o, s:o, s:o, s:b, s:f}", "overall", db(p.overall),
                                      "r", db(p.channel[0]), "g", db(p.channel[1]), "b",
                                      db(p.channel[2]), "identical", p.identical, "mse", p.mse));
        json_object_set_new(timing, "psnr", json_real((clock_mono_s() * 1e3) - t0));
        t0 = (clock_mono_s() * 1e3);
    }
    if (flip_threaded)
        pthread_join(flip_tid, NULL);
    flip_threaded = false;
    if (metrics_stopped(stop, err, errlen))
        goto fail;
    if (o->which & METRIC_FLIP) {
        if (!flip.ok) {
            snprintf(err, errlen, "%s", flip.err);
            goto fail;
        }
        const struct flip_result *f = &flip.result;
        json_object_set_new(out, "flip",
                            json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f}", "mean", f->mean,
                                      "weighted_median", f->weighted_median, "weighted_q1",
                                      f->weighted_q1, "weighted_q3", f->weighted_q3, "min", f->min,
                                      "max", f->max, "pixels_per_degree", o->flip_ppd));
        json_object_set_new(timing, "flip", json_real(flip.ms));
    }
    /* FLIP overlaps the others: the wall time of the whole comparison. */
    json_object_set_new(timing, "total", json_real((clock_mono_s() * 1e3) - start));
    image_finish(&pm_ref);
    image_finish(&pm_test);
    return out;
fail:
    if (flip_threaded)
        pthread_join(flip_tid, NULL);
    json_decref(out);
    image_finish(&pm_ref);
    image_finish(&pm_test);
    return NULL;
}
