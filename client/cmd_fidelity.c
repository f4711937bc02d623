/* shadebench fidelity ASSET [REQUEST.json]: the asset against the Khronos
 * glTF Sample Viewer (POST /v1/assets/NAME/fidelity; docs/client.md). Prints
 * each channel's SSIM, FLIP and pixels off, and what the reference cost;
 * with --out DIR downloads job.json, result.json and every channel's images
 * (both renders, the SSIM and FLIP maps); --min-ssim and --max-flip fail a
 * channel past them (exit 1). Single-threaded, like every command. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/client.h"
#include "common/fsutil.h"

static bool download_images(struct conn *c, const char *id, const json_t *channels,
                            const char *dir)
{
    const char *name;
    json_t *m;
    bool ok = true;
    json_object_foreach((json_t *)channels, name, m) {
        const char *kind;
        json_t *rel;
        json_object_foreach(json_object_get(m, "files"), kind, rel) {
            const char *r = json_string_value(rel);
            const char *base = r ? strrchr(r, '/') : NULL;
            if (!base)
                continue;
            char url[512], file[4200];
            snprintf(url, sizeof(url), "/v1/jobs/%s/%s", id, r);
            snprintf(file, sizeof(file), "%s/%s", dir, base + 1);
            ok = conn_download(c, url, file) && ok;
        }
    }
    return ok;
}

int cmd_fidelity(struct conn *c, const struct options *o, const char *asset,
                 const char *request_file)
{
    char err[600];
    if (o->out_dir && !out_dir_claim(o->out_dir, "job.json", NULL, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    json_t *body = request_file ? load_json_file("request file", request_file, err, sizeof(err))
                                : json_object();
    if (!body) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    if (json_array_size(o->channels)) {
        json_t *ch = json_array();
        json_array_append_new(ch, json_string("lit"));
        json_array_extend(ch, o->channels);
        json_object_set_new(body, "channels", ch);
    }
    if (json_object_size(o->labels))
        json_object_set(body, "labels", o->labels);
    char *text = json_dumps(body, JSON_COMPACT);
    json_decref(body);
    char path[512];
    snprintf(path, sizeof(path), "/v1/assets/%s/fidelity", asset);
    json_t *sub = text ? conn_json(c, "POST", path, text, NULL) : NULL;
    free(text);
    const char *id = json_string_value(json_object_get(sub, "id"));
    if (!id) {
        json_decref(sub);
        return EXIT_ERROR;
    }
    char idbuf[64];
    snprintf(idbuf, sizeof(idbuf), "%s", id);
    json_decref(sub);
    if (!o->quiet)
        fprintf(stderr, "fidelity of %s against the Khronos viewer: job %s\n", asset, idbuf);
    json_t *job = conn_follow_job(c, idbuf, "fidelity", o->quiet, o->timeout_s);
    if (!job)
        return EXIT_ERROR;
    const char *status = json_string_value(json_object_get(job, "status"));
    if (!status || strcmp(status, "done") != 0) {
        fprintf(stderr, "shadebench: job %s %s: %s\n", idbuf, status ? status : "?",
                json_string_value(json_object_get(job, "error"))
                    ? json_string_value(json_object_get(job, "error")) : "");
        json_decref(job);
        return EXIT_FAIL;
    }
    json_t *f = json_object_get(json_object_get(job, "result"), "fidelity");
    json_t *channels = json_object_get(f, "channels");
    int failed = 0;
    printf("%-17s %8s %8s %8s %9s %9s %4s\n", "channel", "ssim", "ssim_rgb", "flip", "px>8",
           "px>32", "max");
    const char *name;
    json_t *m;
    json_object_foreach(channels, name, m) {
        const char *e = json_string_value(json_object_get(m, "error"));
        if (e) {
            printf("%-17s not drawn: %s\n", name, e);
            continue;
        }
        double ssim = json_number_value(json_object_get(m, "ssim"));
        double ssim_rgb = json_number_value(json_object_get(m, "ssim_rgb"));
        double flip = json_number_value(json_object_get(json_object_get(m, "flip"), "mean"));
        bool bad = (!isnan(o->min_ssim) && fmin(ssim, ssim_rgb) < o->min_ssim) ||
                   (!isnan(o->max_flip) && flip > o->max_flip);
        failed += bad;
        printf("%-17s %8.5f %8.5f %8.5f %9lld %9lld %4lld%s\n", name, ssim, ssim_rgb, flip,
               (long long)json_integer_value(json_object_get(m, "pixels_over_8")),
               (long long)json_integer_value(json_object_get(m, "pixels_over_32")),
               (long long)json_integer_value(json_object_get(m, "max_difference")),
               bad ? "  FAIL" : "");
    }
    json_t *cost = json_object_get(f, "cost");
    double chans = 0;
    json_t *v;
    json_object_foreach(json_object_get(cost, "render_ms"), name, v)
        chans += json_number_value(v);
    printf("reference: %s in %s, %s; Chromium start %.0f ms, page %.0f ms, asset %.0f ms, "
           "environment %.0f ms, channels %.0f ms (%s)\n",
           json_string_value(json_object_get(f, "viewer")),
           json_string_value(json_object_get(f, "browser")),
           json_is_true(json_object_get(f, "cache_hit")) ? "from the cache" : "rendered now",
           json_number_value(json_object_get(cost, "chromium_start_ms")),
           json_number_value(json_object_get(cost, "page_ms")),
           json_number_value(json_object_get(cost, "load_ms")),
           json_number_value(json_object_get(cost, "environment_ms")), chans,
           json_string_value(json_object_get(f, "lit_transfer"))
               ? json_string_value(json_object_get(f, "lit_transfer")) : "");
    int rc = failed ? EXIT_FAIL : EXIT_PASS;
    if (o->out_dir) {
        char file[4200];
        bool ok = fs_mkdir_p(o->out_dir);
        snprintf(file, sizeof(file), "%s/job.json", o->out_dir);
        ok = ok && fs_write_json_atomic(file, job);
        snprintf(file, sizeof(file), "%s/result.json", o->out_dir);
        ok = ok && fs_write_json_atomic(file, json_object_get(job, "result"));
        ok = ok && download_images(c, idbuf, channels, o->out_dir);
        if (!ok) {
            fprintf(stderr, "shadebench: cannot write into --out %s: %s\n", o->out_dir,
                    strerror(errno));
            rc = EXIT_ERROR;
        } else if (!o->quiet) {
            fprintf(stderr, "files in %s\n", o->out_dir);
        }
    }
    if (failed)
        fprintf(stderr, "shadebench: %d channel(s) past --min-ssim / --max-flip\n", failed);
    json_decref(job);
    return rc;
}
