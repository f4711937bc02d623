#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/outputs.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/png_io.h"
#include "common/result_keys.h"
#include "common/stats.h"

json_t *outputs_stats_json(const double *v, size_t n)
{
    struct stats s;
    stats_compute(v, n, &s);
    return json_pack("{s:I, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:[f, f]}", RK_N,
                     (json_int_t)s.n, RK_MEAN, s.mean, RK_MEDIAN, s.median, RK_STDDEV,
                     s.stddev, RK_MIN, s.min, RK_MAX, s.max, RK_P5, s.p5, RK_P95, s.p95,
                     RK_P99, s.p99, RK_CV, s.cv, RK_MEDIAN_CI95, s.median_lo, s.median_hi);
}

/* Reads the HDR colour attachment of fbo (w x h, RGBA float) into scratch. */
static void read_hdr_stats(GLuint fbo, int w, int h, float *scratch, struct hdr_stats *out)
{
    memset(out, 0, sizeof(*out));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, scratch);
    long long finite = 0;
    double sum[3] = {0, 0, 0};
    out->min = INFINITY;
    for (long long p = 0; p < (long long)w * h; p++) {
        const float *c = &scratch[p * 4];
        if (!isfinite(c[0]) || !isfinite(c[1]) || !isfinite(c[2])) {
            out->nonfinite++;
            continue;
        }
        finite++;
        for (int k = 0; k < 3; k++) {
            sum[k] += c[k];
            out->max = c[k] > out->max ? c[k] : out->max;
            out->min = c[k] < out->min ? c[k] : out->min;
        }
    }
    for (int k = 0; k < 3; k++)
        out->mean[k] = finite ? sum[k] / (double)finite : 0.0;
    if (!finite)
        out->min = 0.0;
}

static json_t *hdr_stats_json(const struct hdr_stats *s)
{
    return json_pack("{s:I, s:[f, f, f], s:f, s:f}", "nonfinite", (json_int_t)s->nonfinite,
                     "mean", s->mean[0], s->mean[1], s->mean[2], "min", s->min, "max", s->max);
}

/* The motion vectors' figures at a capture: their mean, the longest, and
 * the pixels that moved. */
static void read_motion(struct harness_run *run, struct run_capture *cap)
{
    int w = run->env.width, h = run->env.height;
    const float *m = run->motion_scratch;
    glBindTexture(GL_TEXTURE_2D, run->motion.tex);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RG, GL_FLOAT, run->motion_scratch);
    glBindTexture(GL_TEXTURE_2D, 0);
    double sum[2] = {0, 0}, max2 = 0;
    long long moving = 0, n = (long long)w * h;
    for (long long p = 0; p < n; p++) {
        double x = m[2 * p], y = m[2 * p + 1], l2 = x * x + y * y;
        sum[0] += x, sum[1] += y;
        max2 = l2 > max2 ? l2 : max2;
        moving += l2 > 0;
    }
    cap->motion.mean[0] = sum[0] / (double)n;
    cap->motion.mean[1] = sum[1] / (double)n;
    cap->motion.max = sqrt(max2);
    cap->motion.moving = moving;
}

bool outputs_read_capture(struct harness_run *run, int k)
{
    struct run_capture *cap = &run->capture[run->captured];
    int w = run->env.width, h = run->env.height;
    cap->frame = k;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, run->ldr_fbo);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, cap->pixels);
    if (run->hdr_scratch)
        read_hdr_stats(run->hdr_fbo, w, h, run->hdr_scratch, &cap->hdr);
    if (!post_chain_count_nonfinite(run->post, run->hdr_resolved, &cap->nonfinite, run->err,
                                    sizeof(run->err)))
        return false;
    if (run->motion_scratch)
        read_motion(run, cap);
    if (cap->heat) {
        glBindTexture(GL_TEXTURE_2D, run->products.heat_tex);
        glGetTexImage(GL_TEXTURE_2D, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, cap->heat);
        glBindTexture(GL_TEXTURE_2D, 0);
    }
    run->captured++;
    return true;
}

/* A capture's non-finite pixels, and over the job whether every capture
 * was finite (null without captures): the sweeps' finite criterion. */
static json_int_t nonfinite_pixels(const struct post_nonfinite *n)
{
    return (json_int_t)n->nan_pixels + n->inf_pixels + n->overflow_pixels;
}

static json_t *nonfinite_json(const struct post_nonfinite *n)
{
    return json_pack("{s:I, s:I, s:I, s:I}", "pixels", nonfinite_pixels(n), "nan",
                     (json_int_t)n->nan_pixels, "inf", (json_int_t)n->inf_pixels, "overflow",
                     (json_int_t)n->overflow_pixels);
}

static json_t *nonfinite_summary(const struct harness_run *run)
{
    json_int_t worst = 0, with = 0;
    for (int c = 0; c < run->capture_count; c++) {
        json_int_t px = nonfinite_pixels(&run->capture[c].nonfinite);
        worst = px > worst ? px : worst;
        with += px > 0;
    }
    return json_pack("{s:i, s:I, s:I, s:o, s:s}", RK_CAPTURES, run->capture_count,
                     "captures_with_nonfinite", with, RK_PIXELS_MAX, worst, RK_FINITE,
                     run->capture_count ? json_boolean(with == 0) : json_null(), "counted",
                     "pixels of the HDR colour the resolve read, at each captured frame, with "
                     "R, G or B NaN, infinite, or (rgba16f) at 65504, where a driver that "
                     "clamps an overflowing write leaves it");
}

/* The heat maps as PNG on a colour ramp from 0 (black) to the frame's
 * largest count (white), with each frame's mean and max: result.heatmap. */
static json_t *write_heatmaps(struct harness_run *run)
{
    static const float ramp[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}};
    size_t n = (size_t)run->env.width * (size_t)run->env.height;
    uint8_t *rgba = malloc(n * 4);
    json_t *list = json_array();
    if (!rgba) {
        snprintf(run->err, sizeof(run->err), "out of memory for the heat map");
        goto fail;
    }
    for (int c = 0; c < run->captured; c++) {
        const uint32_t *count = run->capture[c].heat;
        double sum = 0;
        uint32_t max = 0;
        for (size_t i = 0; i < n; i++)
            sum += count[i], max = count[i] > max ? count[i] : max;
        for (size_t i = 0; i < n; i++) {
            float t = max ? 5.0f * (float)count[i] / (float)max : 0.0f;
            int seg = t >= 5.0f ? 4 : (int)t;
            float f = t - (float)seg;
            for (int ch = 0; ch < 3; ch++)
                rgba[i * 4 + ch] = (uint8_t)(255.0f * (ramp[seg][ch] + f * (ramp[seg + 1][ch] - ramp[seg][ch])) + 0.5f);
            rgba[i * 4 + 3] = 255;
        }
        int k = run->capture[c].frame;
        char name[JOB_IMAGE_NAME_MAX], path[PATH_MAX + JOB_IMAGE_NAME_MAX];
        job_image_name(JOB_IMAGE_HEATMAP, k, name);
        job_file_path(run->job->dir, name, path, sizeof(path));
        if (!png_write_gl_rgba(path, rgba, run->env.width, run->env.height, run->err,
                               sizeof(run->err)))
            goto fail;
        json_array_append_new(list, json_pack("{s:i, s:s, s:f, s:i, s:i}", "frame", k,
                                              job_image_kind(JOB_IMAGE_HEATMAP)->file_key, name,
                                              "mean", sum / (double)n, "max", (int)max,
                                              "scale_max", (int)max));
    }
    free(rgba);
    return json_pack("{s:s, s:s, s:o}", "unit", "light evaluations per pixel", "ramp",
                     "black (0), blue, cyan, green, yellow, white (scale_max)", RK_CAPTURES, list);
fail:
    free(rgba);
    json_decref(list);
    return NULL;
}

/* The captured frames as PNG files, each with its figures. */
static json_t *write_captures(struct harness_run *run)
{
    json_t *captures = json_array();
    for (int c = 0; c < run->captured; c++) {
        struct run_capture *cap = &run->capture[c];
        int k = cap->frame;
        char name[JOB_IMAGE_NAME_MAX], path[PATH_MAX + JOB_IMAGE_NAME_MAX];
        job_image_name(JOB_IMAGE_FRAME, k, name);
        job_file_path(run->job->dir, name, path, sizeof(path));
        if (!png_write_gl_rgba(path, cap->pixels, run->env.width, run->env.height, run->err,
                               sizeof(run->err))) {
            json_decref(captures);
            return NULL;
        }
        free(cap->pixels);
        cap->pixels = NULL;
        json_t *entry = json_pack("{s:i, s:s, s:o}", "frame", k,
                                  job_image_kind(JOB_IMAGE_FRAME)->file_key, name, "nonfinite",
                                  nonfinite_json(&cap->nonfinite));
        if (run->hdr_scratch)
            json_object_set_new(entry, "hdr", hdr_stats_json(&cap->hdr));
        if (run->motion_scratch)
            json_object_set_new(entry, "motion",
                                json_pack("{s:[f, f], s:f, s:I}", "mean_px", cap->motion.mean[0],
                                          cap->motion.mean[1], "max_px", cap->motion.max,
                                          "moving_pixels", (json_int_t)cap->motion.moving));
        json_array_append_new(captures, entry);
    }
    return captures;
}

/* timings.csv: one row per timed frame, every pass in frame order. */
static bool write_timings(struct harness_run *run, const double *gpu, const int *order, int sections)
{
    int n = run->spec->frames, w0 = run->spec->warmup_frames;
    size_t cap = (size_t)n * (80 + 24 * (size_t)sections) + 256, used = 0;
    char *csv = malloc(cap), path[PATH_MAX + 32];
    if (!csv) {
        snprintf(run->err, sizeof(run->err), "out of memory for timings.csv");
        return false;
    }
    used += (size_t)snprintf(csv + used, cap - used, "frame,gpu_ms,cpu_ms,frame_ms");
    for (int o = 0; o < sections; o++)
        used += (size_t)snprintf(csv + used, cap - used, ",gpu_%s_ms",
                                 run->passes.names[order[o]]);
    used += (size_t)snprintf(csv + used, cap - used, "\n");
    for (int i = 0; i < n; i++) {
        used += (size_t)snprintf(csv + used, cap - used, "%d,%.6f,%.6f,%.6f", i + 1, gpu[i],
                                 run->cpu_ms[i], run->frame_ms[i]);
        for (int o = 0; o < sections; o++)
            used += (size_t)snprintf(csv + used, cap - used, ",%.6f",
                                     gpu_timer_ms(run->timer, w0 + i, order[o]));
        used += (size_t)snprintf(csv + used, cap - used, "\n");
    }
    job_file_path(run->job->dir, JOB_FILE_TIMINGS, path, sizeof(path));
    bool ok = fs_write_atomic(path, csv, used);
    free(csv);
    if (!ok)
        snprintf(run->err, sizeof(run->err), "cannot write %.900s: %s", path, strerror(errno));
    return ok;
}

json_t *outputs_write(struct harness_run *run)
{
    const struct job_spec *spec = run->spec;
    int n = spec->frames, w0 = spec->warmup_frames;
    int order[GPU_MAX_PASSES];
    int sections = run_pass_order(run, order);
    double *gpu = malloc((size_t)n * sizeof(double));
    double *sec = malloc((size_t)n * sizeof(double));
    json_t *captures = NULL, *heatmap = NULL, *result = NULL;
    char path[PATH_MAX + 32];
    if (!gpu || !sec) {
        snprintf(run->err, sizeof(run->err), "out of memory for statistics");
        goto out;
    }
    for (int i = 0; i < n; i++)
        gpu[i] = gpu_timer_ms(run->timer, w0 + i, -1);
    bool heat = run->captured && run->capture[0].heat;
    if (!(captures = write_captures(run)) || (heat && !(heatmap = write_heatmaps(run))) ||
        !write_timings(run, gpu, order, sections))
        goto out;

    double wall_s = run->wall_s, timed_wall = wall_s - run->capture_s;
    result = json_pack(
        "{s:s, s:i, s:i, s:f, s:f, s:f, s:o, s:o, s:o, s:I, s:i, s:i, s:O, s:s, s:s, s:I, s:O}",
        RK_TECHNIQUE, run->tech->info->name, "frames", n, "warmup_frames", w0, RK_WALL_S,
        timed_wall, "wall_s_including_captures", wall_s, RK_FPS,
        timed_wall > 0 ? n / timed_wall : 0.0, RK_GPU_MS, outputs_stats_json(gpu, (size_t)n),
        RK_CPU_MS, outputs_stats_json(run->cpu_ms, (size_t)n), RK_FRAME_MS,
        outputs_stats_json(run->frame_ms, (size_t)n), "triangles_per_frame",
        (json_int_t)scene_triangles(&run->scene), "instances", run->scene.instance_count,
        "lights", run->scene.light_count, RK_CAPTURES, captures, "capture_policy",
        "each captured frame is read back with glReadPixels after its GPU timer "
        "query has ended and its CPU time was taken; the readback time is "
        "subtracted from wall_s (wall_s_including_captures keeps it), and PNG "
        "encoding happens after the last timed frame",
        "timing_method",
        "gpu_ms: GL_TIME_ELAPSED per frame from a ring of 8 queries read back a ring "
        "later; cpu_ms: CLOCK_MONOTONIC around the frame's submission and glFlush; "
        "frame_ms: CLOCK_MONOTONIC between frame starts with at most 2 frames in "
        "flight (fence-bounded, as a swap chain), readback time excluded",
        "timer_query_stalls", (json_int_t)gpu_timer_stalls(run->timer), "device",
        run->gl->device_json);
    /* Every pass, the harness's resolve included, in frame order. */
    json_t *by_section = json_object();
    for (int o = 0; o < sections; o++) {
        for (int i = 0; i < n; i++)
            sec[i] = gpu_timer_ms(run->timer, w0 + i, order[o]);
        json_object_set_new(by_section, run->passes.names[order[o]],
                            outputs_stats_json(sec, (size_t)n));
    }
    json_object_set_new(result, "gpu_sections_ms", by_section);
    double slice_s, free_s;
    gpu_budget_limits(&slice_s, &free_s);
    json_object_set_new(result, "gpu_budget",
                        json_pack("{s:f, s:f, s:I, s:I, s:s}", "slice_s", slice_s,
                                  "whole_below_s", free_s, "pieces_sliced",
                                  (json_int_t)run->budget.pieces_sliced, "waits",
                                  (json_int_t)run->budget.waits, "rule",
                                  "a pass's work (or a loop of draws) that measured whole_below_s "
                                  "or more runs in tiles of about slice_s, waited for in turn, so "
                                  "that a cancel, a timeout or a stop acts within about a slice; "
                                  "each piece is measured in tiles in its first run (the first "
                                  "warm-up frame); pieces_sliced counts the runs drawn in more "
                                  "than one tile, warm-up frames included"));
    json_object_set_new(result, "timer_query_implausible",
                        json_integer((json_int_t)gpu_timer_implausible(run->timer, w0)));
    json_object_set_new(result, "look", look_spec_to_json(&spec->look));
    json_object_set_new(result, RK_NONFINITE, nonfinite_summary(run));
    look_stages_describe(&run->stages, result);
    json_object_set_new(result, "targets_bytes", json_real(gpu_targets_bytes(run->gl->targets)));
    json_object_set_new(result, "msaa", run_msaa_json(run));
    json_t *time = run_time_json(run);
    if (time)
        json_object_set_new(result, "time", time);
    json_object_set_new(result, RK_STARTED_UNIX, json_real(run->job->started));
    if (heatmap)
        json_object_set(result, RK_HEATMAP, heatmap);
    json_t *scene = scene_describe(&run->scene);
    json_t *asset = json_object_get(scene, "asset");
    if (run->asset && json_is_object(asset))
        json_object_set_new(asset, "load_ms",
                            json_pack("{s:f, s:f, s:s}", "read", run->asset_read_ms,
                                      "scene_and_upload", run->scene_upload_ms, "includes",
                                      "reading the cache file; building the scene, its "
                                      "textures with mipmaps and buffers up to a glFinish; "
                                      "before the warm-up, outside every timed region"));
    json_object_set_new(result, "scene", scene);
    /* What could have disturbed the timed region. */
    json_object_set_new(result, RK_INTERFERENCE,
                        interference_json(&run->interference[0], &run->interference[1]));
    if (run->tech->describe) {
        json_t *d = run->tech->describe(run->state);
        if (d)
            json_object_set_new(result, run->tech->info->name, d); /* result[result.technique] */
    }
    job_file_path(run->job->dir, JOB_FILE_RESULT, path, sizeof(path));
    if (!fs_write_json_atomic(path, result)) {
        snprintf(run->err, sizeof(run->err), "cannot write %.900s: %s", path, strerror(errno));
        json_decref(result);
        result = NULL;
    }
out:
    json_decref(captures);
    json_decref(heatmap);
    free(gpu);
    free(sec);
    return result;
}
