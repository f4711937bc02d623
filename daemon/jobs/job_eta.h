#ifndef SHADEBENCH_JOB_ETA_H
#define SHADEBENCH_JOB_ETA_H

/* How long a job will take, from its cost and this device's measured rate:
 * every job that ends done tells the table what one of its frames took
 * (the median timed frame) for its technique, pixels and lights, and what
 * its run took beyond its frames (set-up, measuring frames, reference,
 * metrics). A new job is estimated from the finished job of its technique
 * nearest in pixels and lights: its frame time, of which the pixels' share
 * (the measuring frame tells it apart) scales linearly by pixels and by the
 * square root of the light ratio while the rest stays (forward's loop is linear in lights, the
 * light-culling techniques far less: the square root sits between), times
 * its frames, plus the time that job took beyond its frames. No estimate
 * before the device has run a job of that technique.
 *
 * A submission over what its timeout_s allows by more than
 * JOB_ETA_REFUSE_FACTOR, or whose frame is projected past that factor
 * times the frame bound (job_spec_max_frame_seconds) without accepting
 * sliced timing, is refused with the figures. While a job runs, the time
 * left comes from the frames it has drawn (job_eta_left). GL-free; any
 * thread (a mutex guards the table); unit-tested in tests/unit/test_job.c. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"

struct job_spec;

/* A projection past its limit by this factor is refused: estimates err,
 * and a job that merely might not finish fails early in its run anyway. */
#define JOB_ETA_REFUSE_FACTOR 4.0
/* Observations kept a technique. */
#define JOB_ETA_SAMPLES 32

struct job_eta {
    bool known;          /* a job of this technique has run on this device */
    double frame_s;      /* one frame of the job */
    double duration_s;   /* the whole job: its frames, measuring frames and overhead */
    /* The finished job it was scaled from. */
    double basis_frame_s, basis_pixels, basis_lights, basis_overhead_s, basis_fixed_s;
};

/* A done job: its technique, pixels, lights, the median frame (seconds)
 * and the pixels' share of it (result.timing.pixel_share: the measuring
 * frame's tiled work above what every tile pays; the geometry, the shadow
 * maps and the frame's own overhead do not grow with the pixels), the
 * frames it drew in all (warm-up and timed, every run) and how long its run
 * took from start to end. */
void job_eta_observe(const char *technique, double pixels, int lights, double frame_s,
                     double pixel_share, double frames_drawn, double run_s);
/* Forgets every observation (tests). */
void job_eta_reset(void);

/* The estimate for spec (known false without a rate). */
void job_eta_estimate(const struct job_spec *spec, struct job_eta *out);
/* {"duration_s", "frame_s", "basis": {...}, "rule"} for the API; null when
 * unknown. New reference. */
json_t *job_eta_json(const struct job_eta *e);
/* false, with err naming the field and the figures, when the estimate puts
 * the job past JOB_ETA_REFUSE_FACTOR times its timeout_s, or its frame past
 * that factor times the frame bound (unless it accepts sliced timing). */
bool job_eta_admit(const struct job_spec *spec, const struct job_eta *e, struct job_error *err);

/* While it runs: seconds left by the frames drawn so far, frames_done of
 * frames_total in elapsed_s since its timed frames began; < 0 before the
 * first timed frame. */
double job_eta_left(int frames_done, int frames_total, double elapsed_s);

/* A done job's result (frame_ms, its spec's scene) as an observation. */
void job_eta_observe_result(const struct job_spec *spec, const json_t *result, double run_s);

#endif
