#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/temporal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/harness/reference.h"
#include "daemon/status/render_state.h"
#include "daemon/quality/flicker.h"
#include "daemon/quality/ghosting.h"

#define TEMPORAL_MEASURE                                                                      \
    "mean over the frame pairs (t-1, t) of the run of mean |(T_t - T_t-1) - (R_t - R_t-1)| "  \
    "on luma in [0, 1], T the technique's frames and R the reference's (a temporal-difference " \
    "error: the pixel-space form of Chu et al. 2020's tLP, with no warp since both share the " \
    "camera); 0 when the technique changes as the reference does"

/* The technique's frames k..k+K-1 into frames (K of them), one instance
 * going on from frame k as in the timed run. */
static bool draw_run(struct harness_run *run, struct frame_source *src, int k, int count,
                     uint8_t *const *frames, enum job_status *status)
{
    for (int j = 0; j < count; j++)
        if (!frame_source_frame(run, src, (int64_t)k + j, j == 0, frames[j], status))
            return false;
    return true;
}

#define GHOSTING_MEASURE                                                                      \
    "scene.mover: at each frame of the run, mean |T - R| on luma in [0, 1] over the band of "  \
    "pixels the mover covered in the 8 frames before (its silhouette discs, past positions "   \
    "seen by this frame's camera) and does not cover now (band_error), beside the same over "  \
    "the rest of the frame (rest_error); averaged over the run's frames"

/* The band behind the mover at frame k (ghosting.h). False without one. */
static bool mover_band(const struct harness_run *run, int64_t k, uint8_t *mask)
{
    const struct scene *s = &run->scene;
    int w = run->spec->scene.width, h = run->spec->scene.height;
    struct scene_camera cam;
    scene_camera_at(s, k, &cam);
    float now[3], past[GHOSTING_TRAIL][3];
    if (!scene_mover_disc(s, k, &cam, w, h, now))
        return false;
    int n = 0;
    for (int t = 1; t <= GHOSTING_TRAIL; t++)
        n += scene_mover_disc(s, k - t, &cam, w, h, past[n]);
    ghosting_band(mask, w, h, (const float (*)[3])past, n, now);
    return true;
}

static bool one_capture(struct harness_run *run, int k, uint8_t **tech, uint8_t **ref,
                        uint8_t *mask, struct flicker_result *out, struct ghosting_result *ghost,
                        enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    int count = spec->temporal_frames;
    size_t pixels = (size_t)spec->scene.width * (size_t)spec->scene.height;
    const struct technique *reference = technique_find(spec->reference);
    struct frame_source src;
    /* One source at a time (they share the pool's output targets): the
     * technique's run is kept whole, the reference's two frames at a time. */
    bool ok = frame_source_open(run, &src, "temporal", run->tech,
                                job_spec_technique_options(spec), &spec->look, 1) &&
              draw_run(run, &src, k, count, tech, status);
    frame_source_close(&src);
    if (!ok)
        return false;
    if (!reference) {
        snprintf(run->err, sizeof(run->err), "temporal: reference %s is not available",
                 spec->reference);
        return false;
    }
    ok = frame_source_open(run, &src, "temporal", reference, job_spec_reference_options(spec),
                           &spec->reference_look, spec->reference_supersample);
    flicker_init(out);
    ghosting_init(ghost);
    for (int j = 0; ok && j < count; j++) {
        uint8_t *cur = ref[j & 1], *prev = ref[(j + 1) & 1];
        ok = frame_source_frame(run, &src, (int64_t)k + j, j == 0, cur, status);
        if (ok && j > 0)
            flicker_add(out, flicker_pair(tech[j - 1], tech[j], prev, cur, pixels, 4));
        if (ok && mask && mover_band(run, (int64_t)k + j, mask))
            ghosting_add(ghost, tech[j], cur, mask, pixels, 4);
        render_progress();
    }
    frame_source_close(&src);
    return ok;
}

bool temporal_measure(struct harness_run *run, json_t *result, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    int count = spec->temporal_frames;
    size_t bytes = (size_t)spec->scene.width * (size_t)spec->scene.height * 4;
    uint8_t *tech[JOB_MAX_TEMPORAL_FRAMES] = {0}, *ref[2] = {0};
    bool ok = true;
    for (int j = 0; ok && j < count; j++)
        ok = (tech[j] = malloc(bytes)) != NULL;
    for (int j = 0; ok && j < 2; j++)
        ok = (ref[j] = malloc(bytes)) != NULL;
    uint8_t *mask = NULL;
    if (ok && run->scene.mover >= 0)
        ok = (mask = malloc(bytes / 4)) != NULL;
    double worst_ghosting = -1;
    int worst_ghosting_frame = 0;
    if (!ok)
        snprintf(run->err, sizeof(run->err), "temporal: out of memory for %d frames", count);
    json_t *captures = json_object_get(result, RK_CAPTURES);
    size_t i;
    json_t *capture;
    json_array_foreach(captures, i, capture) {
        if (!ok)
            break;
        int k = (int)json_integer_value(json_object_get(capture, "frame"));
        struct flicker_result f;
        struct ghosting_result g;
        if (!(ok = one_capture(run, k, tech, ref, mask, &f, &g, status)))
            break;
        json_t *t = json_pack("{s:[i, i], s:f, s:{s:[i, i], s:f}}", "frames", k, k + count - 1,
                              "flicker", f.mean, "worst_pair", "frames", k + f.max_pair,
                              k + f.max_pair + 1, "flicker", f.max);
        if (mask)
            json_object_set_new(
                t, "ghosting",
                g.frames ? json_pack("{s:f, s:f, s:f, s:i}", "band_error",
                                     g.band_error / g.frames, "rest_error",
                                     g.rest_error / g.frames, "band_pixels",
                                     g.band_pixels / g.frames, "frames", g.frames)
                         : json_null());
        if (g.frames && g.band_error / g.frames > worst_ghosting) {
            worst_ghosting = g.band_error / g.frames;
            worst_ghosting_frame = k;
        }
        json_object_set_new(capture, RK_TEMPORAL, t);
    }
    if (ok) {
        json_t *t = json_pack("{s:i, s:s, s:i, s:s}", "frames", count, "reference",
                              spec->reference, "reference_supersample",
                              spec->reference_supersample, "measure", TEMPORAL_MEASURE);
        if (mask)
            json_object_set_new(t, "ghosting",
                                json_pack("{s:s, s:o}", "measure", GHOSTING_MEASURE, "worst",
                                          worst_ghosting >= 0
                                              ? json_pack("{s:f, s:i}", "band_error",
                                                          worst_ghosting, "frame",
                                                          worst_ghosting_frame)
                                              : json_null()));
        json_object_set_new(result, RK_TEMPORAL, t);
    }
    for (int j = 0; j < count; j++)
        free(tech[j]);
    free(ref[0]);
    free(ref[1]);
    free(mask);
    return ok;
}
