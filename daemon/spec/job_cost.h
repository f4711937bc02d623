#ifndef SHADEBENCH_JOB_COST_H
#define SHADEBENCH_JOB_COST_H

/* What a job will cost, estimated from its spec alone, before it runs: the
 * memory it holds at its peak, by part, and whether the daemon admits it.
 * An estimate meant to bound, not to predict: its per-pixel figures were
 * measured on llvmpipe (result.targets_bytes of every technique and effect
 * at 256x256, fresh context) and rounded up, and it sums parts that a job
 * holds one after another.
 *
 * The admission limit is process-wide, set once at start-up before any
 * thread parses jobs (like job_spec_set_default_timeout): job_spec_parse
 * refuses a job over it, so that a submission, a sweep's point and a job
 * queued before a restart are held to the same rule. GL-free; any thread;
 * unit-tested in tests/unit/test_job.c. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"

struct job_spec;

struct job_cost {
    /* Memory, in bytes. */
    double targets_bytes;   /* framebuffers the driver holds: HDR colour, depth, the 8-bit
                             * resolve, the technique's planes (g-buffers, depth bounds),
                             * each post effect's; llvmpipe keeps them in the daemon's RSS */
    double look_bytes;      /* the shadow atlas and the light probes' cube maps */
    double captures_bytes;  /* captured frames (and light-count maps) kept until the run ends */
    double reference_bytes; /* the reference's own planes and its read-back frame */
    double metrics_bytes;   /* the metrics stage's images and maps (with a reference) */
    double series_bytes;    /* per-frame figures: CPU, frame and GPU times of every pass */
    double temporal_bytes;  /* temporal.frames: one capture point's frames of the technique */
    double asset_bytes;     /* scene.asset: its cache read in, its textures and geometry
                             * uploaded (scene.asset_bytes, known once the asset is pinned) */
    double memory_bytes;    /* their sum */
    const char *memory_field; /* the job field that drives the largest part */
    /* Work, in units no rate turns into seconds without the device: the
     * render thread's time is judged on the device, from a job's first
     * frames (a job that cannot finish within its timeout_s fails there). */
    double frames_total;          /* warm-up and timed frames of every run */
    double pixel_frames;          /* pixels x frames_total */
    double pixel_light_evaluations; /* x lights: forward's loop, the most any technique does */
    double ibl_samples;           /* probes' cube faces' texels x samples, once */
    double shadow_texels;         /* shadow atlas texels x frames_total */
    double metric_pixels;         /* captures x pixels scored against the reference */
};

/* Fills out from spec (which must be valid: job_spec_parse's). */
void job_cost_estimate(const struct job_spec *spec, struct job_cost *out);

/* {"memory_bytes", "targets_bytes", ..., "work": {...}}: the estimate as
 * the API states it. New reference. */
json_t *job_cost_json(const struct job_cost *c);

/* The most memory one job may take (bytes; 0: no limit, the default, as
 * for --once). Set once at start-up, before any thread parses jobs. */
void job_cost_set_memory_limit(double bytes);
double job_cost_memory_limit(void);

/* false, with err naming the field that drives the largest part and the
 * rule, when the estimate is over the limit. */
bool job_cost_admit(const struct job_cost *c, struct job_error *err);

#endif
