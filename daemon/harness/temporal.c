#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/temporal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/harness/reference.h"
#include "daemon/status/render_state.h"
#include "daemon/quality/flicker.h"

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

static bool one_capture(struct harness_run *run, int k, uint8_t **tech, uint8_t **ref,
                        struct flicker_result *out, enum job_status *status)
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
    for (int j = 0; ok && j < count; j++) {
        uint8_t *cur = ref[j & 1], *prev = ref[(j + 1) & 1];
        ok = frame_source_frame(run, &src, (int64_t)k + j, j == 0, cur, status);
        if (ok && j > 0)
            flicker_add(out, flicker_pair(tech[j - 1], tech[j], prev, cur, pixels, 4));
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
        if (!(ok = one_capture(run, k, tech, ref, &f, status)))
            break;
        json_object_set_new(
            capture, RK_TEMPORAL,
            json_pack("{s:[i, i], s:f, s:{s:[i, i], s:f}}", "frames", k, k + count - 1,
                      "flicker", f.mean, "worst_pair", "frames", k + f.max_pair,
                      k + f.max_pair + 1, "flicker", f.max));
    }
    if (ok)
        json_object_set_new(result, RK_TEMPORAL,
                            json_pack("{s:i, s:s, s:i, s:s}", "frames", count, "reference",
                                      spec->reference, "reference_supersample",
                                      spec->reference_supersample, "measure", TEMPORAL_MEASURE));
    for (int j = 0; j < count; j++)
        free(tech[j]);
    free(ref[0]);
    free(ref[1]);
    return ok;
}
