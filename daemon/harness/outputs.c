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

/* The heat maps' one scale, the same for every job and technique, so that
 * a colour means one count everywhere: log2(1 + n) / log2(1 + 65,536)
 * onto a ramp from black (0) through blue, cyan, green and yellow to white
 * (65,536, the most lights a scene holds). Below each map, a legend strip:
 * a grey row, then the ramp from 0 to 65,536 across the width with black
 * ticks at 1, 4, 16, ... 65,536 (every power of 4). */
#define HEAT_SCALE_MAX ((double)SCENE_MAX_LIGHTS)
#define HEAT_LEGEND_TICKS 9 /* 4^0 .. 4^8 */

static const float heat_ramp[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1},
                                      {0, 1, 0}, {1, 1, 0}, {1, 1, 1}};

static double heat_position(double count)
{
    double t = log2(1.0 + count) / log2(1.0 + HEAT_SCALE_MAX);
    return t < 0 ? 0 : t > 1 ? 1 : t;
}

static void heat_colour(double t, uint8_t *rgba)
{
    double x = 5.0 * t;
    int seg = x >= 5.0 ? 4 : (int)x;
    float f = (float)(x - seg);
    for (int ch = 0; ch < 3; ch++)
        rgba[ch] = (uint8_t)(255.0f * (heat_ramp[seg][ch] +
                                       f * (heat_ramp[seg + 1][ch] - heat_ramp[seg][ch])) + 0.5f);
    rgba[3] = 255;
}

static int heat_legend_rows(int height)
{
    int rows = height / 12;
    return 1 + (rows < 4 ? 4 : rows > 24 ? 24 : rows);
}

/* The legend under the map, in the bottom-first rows glReadPixels order
 * gives (so that png_write_gl_rgba puts it below): rows 0 .. legend - 2
 * the ramp with its ticks, the top row grey. */
static void heat_legend(uint8_t *rgba, int width, int legend)
{
    for (int y = 0; y < legend; y++)
        for (int x = 0; x < width; x++) {
            uint8_t *px = &rgba[((size_t)y * width + x) * 4];
            if (y == legend - 1) {
                px[0] = px[1] = px[2] = 128, px[3] = 255;
                continue;
            }
            heat_colour(width > 1 ? (double)x / (width - 1) : 0.0, px);
        }
    /* Ticks: the lower half of the strip, black, at every power of 4. */
    for (int i = 0; i < HEAT_LEGEND_TICKS; i++) {
        int x = (int)(heat_position(pow(4.0, i)) * (width - 1) + 0.5);
        for (int y = 0; y < (legend - 1) / 2 + 1 && y < legend - 1; y++) {
            uint8_t *px = &rgba[((size_t)y * width + x) * 4];
            px[0] = px[1] = px[2] = 0;
        }
    }
}

/* The heat maps as PNG on the one scale above, with each frame's mean and
 * max: result.heatmap. */
static json_t *write_heatmaps(struct harness_run *run)
{
    int w = run->env.width, h = run->env.height, legend = heat_legend_rows(h);
    size_t n = (size_t)w * (size_t)h;
    uint8_t *rgba = malloc((n + (size_t)w * legend) * 4);
    json_t *list = json_array();
    if (!rgba) {
        snprintf(run->err, sizeof(run->err), "out of memory for the heat map");
        goto fail;
    }
    /* glReadPixels order: the bottom row first, so the legend goes first. */
    heat_legend(rgba, w, legend);
    uint8_t *map = rgba + (size_t)w * legend * 4;
    for (int c = 0; c < run->captured; c++) {
        const uint32_t *count = run->capture[c].heat;
        double sum = 0;
        uint32_t max = 0;
        for (size_t i = 0; i < n; i++)
            sum += count[i], max = count[i] > max ? count[i] : max;
        for (size_t i = 0; i < n; i++)
            heat_colour(heat_position(count[i]), &map[i * 4]);
        int k = run->capture[c].frame;
        char name[JOB_IMAGE_NAME_MAX], path[PATH_MAX + JOB_IMAGE_NAME_MAX];
        job_image_name(JOB_IMAGE_HEATMAP, k, name);
        job_file_path(run->job->dir, name, path, sizeof(path));
        if (!png_write_gl_rgba(path, rgba, w, h + legend, run->err, sizeof(run->err)))
            goto fail;
        json_array_append_new(list, json_pack("{s:i, s:s, s:f, s:i}", "frame", k,
                                              job_image_kind(JOB_IMAGE_HEATMAP)->file_key, name,
                                              "mean", sum / (double)n, "max", (int)max));
    }
    free(rgba);
    json_t *ticks = json_array();
    for (int i = 0; i < HEAT_LEGEND_TICKS; i++)
        json_array_append_new(ticks, json_integer((json_int_t)pow(4.0, i)));
    return json_pack(
        "{s:s, s:s, s:{s:s, s:f, s:s, s:i, s:i, s:o}, s:o}", "unit",
        "light evaluations per pixel", "ramp",
        "black (0), blue, cyan, green, yellow, white (scale.max)", "scale", "kind",
        "log2(1 + count) / log2(1 + max), the same for every job", "max", HEAT_SCALE_MAX,
        "legend", "below the map: a grey row, then the ramp from 0 (left) to max (right) with "
                  "black ticks at the counts in ticks",
        "map_rows", h, "legend_rows", legend, "ticks", ticks, RK_CAPTURES, list);
fail:
    free(rgba);
    json_decref(list);
    return NULL;
}

/* result.timing: how the timed frames were drawn and the figures that
 * decided it (measure.c). */
static json_t *outputs_timing_json(const struct harness_run *run)
{
    const struct run_timing_rule *rule = run->rule;
    int n = run->spec->frames, whole = 0;
    for (int i = 0; i < n; i++)
        whole += run->drawn_whole[i] != 0;
    bool sliced = rule->mode == GPU_BUDGET_SLICED;
    json_t *o = json_pack(
        "{s:s, s:i, s:i, s:f, s:b, s:i, s:o, s:o, s:o, s:o, s:s}", "rule", sliced ? "sliced" : "whole",
        "frames_whole", whole, "frames_sliced", n - whole, "limit_s", rule->limit_s,
        "accept_sliced_timing", run->spec->accept_sliced_timing, "measuring_runs",
        rule->measuring_frames, "first_frame_estimate_s",
        rule->estimate_s[0] >= 0 ? json_real(rule->estimate_s[0]) : json_null(),
        "second_estimate_s", rule->estimate_s[1] >= 0 ? json_real(rule->estimate_s[1]) : json_null(),
        "settling_frame_s",
        rule->settling_frame_s >= 0 ? json_real(rule->settling_frame_s) : json_null(),
        "whole_frame_s", rule->whole_frame_s >= 0 ? json_real(rule->whole_frame_s) : json_null(),
        "how",
        "the job's first run draws its first warm-up frame in slices (each piece measured: a "
        "one-pixel probe for what every tile pays, samples, then tiles sized by the dearest "
        "pixel) and, when that says a whole frame fits limit_s, its second warm-up frame whole "
        "(whole_frame_s; with fewer warm-up frames, frames of the harness's own stand in); the "
        "timed frames are drawn whole when that took at most limit_s (the guard then adds "
        "nothing to them), and else, only with accept_sliced_timing, in the tiles the measure "
        "gives (every figure marked sliced); a measure over the limit is taken again once; a "
        "measure given up at 4 times the limit is followed by the frame drawn through in "
        "slices, unjudged (settling_frame_s: work done once, such as OSL's first shading, "
        "must not decide), and a new measure; decided once a job, for all its runs");
    /* For the duration estimate (job_eta.h): what of a frame scales with
     * its pixels. */
    json_object_set_new(o, "pixel_share", json_real(rule->pixel_share));
    json_object_set_new(o, "largest_piece",
                        json_pack("{s:s, s:f}", "pass", rule->largest[0] ? rule->largest : "",
                                  "whole_s", rule->largest_s));
    return o;
}

void outputs_mark_sliced(json_t *result)
{
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    json_object_set_new(result, "sliced", json_true());
    for (size_t i = 0; i < sizeof(series) / sizeof(series[0]); i++) {
        json_t *s = json_object_get(result, series[i]);
        if (json_is_object(s))
            json_object_set_new(s, "sliced", json_true());
    }
    const char *key;
    json_t *v;
    json_object_foreach(json_object_get(result, "gpu_sections_ms"), key, v)
        if (json_is_object(v))
            json_object_set_new(v, "sliced", json_true());
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
    used += (size_t)snprintf(csv + used, cap - used, ",drawn_whole\n");
    for (int i = 0; i < n; i++) {
        used += (size_t)snprintf(csv + used, cap - used, "%d,%.6f,%.6f,%.6f", i + 1, gpu[i],
                                 run->cpu_ms[i], run->frame_ms[i]);
        for (int o = 0; o < sections; o++)
            used += (size_t)snprintf(csv + used, cap - used, ",%.6f",
                                     gpu_timer_ms(run->timer, w0 + i, order[o]));
        used += (size_t)snprintf(csv + used, cap - used, ",%d\n", run->drawn_whole[i] ? 1 : 0);
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
        "gpu_ms: the frame's GPU time, the sum of its passes (gpu_sections_ms; see "
        "gpu_pass_timing), from a ring of 8 frames of queries read back a ring later; cpu_ms: CLOCK_MONOTONIC around the frame's submission and glFlush; "
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
    json_object_set_new(
        result, "gpu_pass_timing",
        json_pack("{s:s, s:s}", "method",
                  gpu_timer_timestamps(run->timer) ? "timestamps" : "elapsed", "rule",
                  gpu_timer_timestamps(run->timer)
                      ? "a GL_TIMESTAMP at each pass's start and at the frame's end: a pass is "
                        "the time from its start to the next pass's, so that the passes of a "
                        "frame add up to its gpu_ms exactly and no pass absorbs another's work"
                      : "a GL_TIME_ELAPSED query a pass (the driver has no GL_TIMESTAMP); "
                        "gpu_ms is their sum"));
    json_object_set_new(result, "gpu_budget",
                        json_pack("{s:f, s:I, s:I, s:s}", "slice_s", gpu_budget_slice(),
                                  "pieces_sliced", (json_int_t)run->pieces_sliced, "waits",
                                  (json_int_t)run->budget.waits, "rule",
                                  "untimed work (each run's measuring frame, the look's set-up, "
                                  "the reference) is drawn in tiles of about slice_s wherever "
                                  "a piece's measure says it takes a slice or more, so that a "
                                  "cancel, a timeout or a stop acts within about a slice; the "
                                  "timed frames are drawn as result.timing says; pieces_sliced "
                                  "counts the runs of a piece drawn in more than one tile in "
                                  "the timed frames"));
    json_object_set_new(result, "timing", outputs_timing_json(run));
    if (run->rule && run->rule->mode == GPU_BUDGET_SLICED)
        outputs_mark_sliced(result);
    json_object_set_new(result, "timer_query_implausible",
                        json_integer((json_int_t)gpu_timer_implausible(run->timer, w0)));
    json_object_set_new(result, "look", look_spec_to_json(&spec->look));
    if (run->look == &run->look_unlit)
        json_object_set_new(result, "look_not_made",
                            json_pack("{s:b, s:b, s:s}", "shadows", spec->look.shadows.enabled,
                                      "ibl", spec->look.ibl.enabled, "why",
                                      "the technique reads no light: neither the look's shadow "
                                      "maps nor its probes are made for it"));
    json_object_set_new(result, RK_NONFINITE, nonfinite_summary(run));
    look_stages_describe(&run->stages, result);
    json_object_set_new(result, "targets_bytes", json_real(gpu_targets_bytes(run->gl->targets)));
    bool software = json_is_true(json_object_get(run->gl->device_json, "software"));
    json_object_set_new(result, "compile", gl_build_log_json(&run->builds));
    json_object_set_new(result, "gpu_memory",
                        gpu_memory_run_json(run->gpu_memory, gpu_targets_bytes(run->gl->targets),
                                            software));
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
