#ifndef SHADEBENCH_JOB_H
#define SHADEBENCH_JOB_H

/* Job specifications: parsing, validation and defaults. GL-free so that it is
 * unit-tested plainly; the techniques and their options come from the
 * catalogue the caller hands in. Any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "common/options.h"
#include "daemon/lighting/look_spec.h"
#include "daemon/quality/metrics.h"
#include "daemon/spec/fidelity_spec.h"
#include "daemon/scene/scene_spec.h"
#include "daemon/techniques/catalog.h"

#define JOB_MAX_BODY_BYTES (64 * 1024)
/* What a job that names neither gets: sized for a first try on any
 * renderer (at the default 1080x720 over the grid's 10 lights, seconds to
 * a minute on a 2-core CPU renderer: docs/api.md); a benchmark names its
 * own. */
#define JOB_DEFAULT_FRAMES 60
#define JOB_DEFAULT_WARMUP_FRAMES 5
#define JOB_MAX_CAPTURE_BYTES (1024.0 * 1024.0 * 1024.0)
#define JOB_MAX_CAPTURES 1000

/* labels: free-form tags for history (commit, branch, driver version). Keys
 * are 1 to 32 characters of [A-Za-z0-9_.-] so that they fit a query
 * (?label.KEY=VALUE); values are strings of at most 128 bytes without
 * control characters. They never change what is measured. */
#define JOB_MAX_LABELS 16
#define JOB_LABEL_KEY_MAX 32
#define JOB_LABEL_VALUE_MAX 128

/* reference.supersample: the reference renders at N times the job's width
 * and height and is box-filtered down to them (reference.c), so that
 * accuracy is measured against the pixel's true colour rather than one
 * sample of it. 1 to 4: 4 is 16 samples a pixel, past which the box filter's
 * estimate of a pixel's mean moves by less than an 8-bit level on the
 * scenes here, while the cost grows with N squared. */
#define JOB_MAX_SUPERSAMPLE 4
/* ... and the supersampled size within GL 4.5's minimum GL_MAX_TEXTURE_SIZE
 * and GL_MAX_VIEWPORT_DIMS. */
#define JOB_SUPERSAMPLE_MAX_SIDE 16384
/* temporal.frames: consecutive frames compared at each capture for the
 * flicker measure (quality/flicker.h). */
#define JOB_MIN_TEMPORAL_FRAMES 2
#define JOB_MAX_TEMPORAL_FRAMES 16

struct job_label {
    char key[JOB_LABEL_KEY_MAX + 1];
    char value[JOB_LABEL_VALUE_MAX + 1];
};

struct job_spec {
    char technique[32];
    int frames;
    int warmup_frames;
    int capture_interval;
    struct scene_spec scene;
    struct look_spec look;
    /* The look the reference renders with: the job's look unless the body
     * gave reference_look (for scoring an effect itself). */
    struct look_spec reference_look;
    bool reference_look_given;
    int repeat;                    /* runs of the job; with repeat_auto, the most */
    bool repeat_auto;              /* stop once the 95% interval is within 2.5% */
    char reference[32];            /* technique to compare captures with; "" for none */
    int reference_supersample;     /* 1 to JOB_MAX_SUPERSAMPLE: "reference": {"supersample": N} */
    int temporal_frames;           /* 0, or frames compared at each capture for flicker */
    struct metrics_options metrics; /* used when reference is set */
    /* Every catalogued technique's options, by catalogue index, so that a
     * sweep over techniques keeps each one's settings. */
    const struct technique_catalog *catalog;
    int technique_index, reference_index; /* reference_index -1 without one */
    unsigned options_given;               /* bit i: the body gave technique i's object,
                                           * and i is neither technique nor reference */
    struct opt_values options[TECHNIQUE_MAX];
    int nlabels;                   /* sorted by key */
    struct job_label labels[JOB_MAX_LABELS];
    double timeout_s;              /* running time allowed, all phases; 0: no limit */
    int msaa;                      /* samples a pixel of the output (1, 2, 4, 8); the
                                    * reference renders at the same count */
    struct fidelity_spec fidelity; /* compared with the Khronos viewer (fidelity_spec.h) */
    /* A whole frame over the render thread's bound (job_spec_max_frame_seconds)
     * is timed in slices, every figure marked so, instead of failing before
     * timing ("accept_sliced_timing": true; false by default). */
    bool accept_sliced_timing;
};

/* The timeout_s a job gets when it names none (--job-timeout). Set once at
 * start-up, before any thread parses jobs. */
void job_spec_set_default_timeout(double seconds);
double job_spec_default_timeout(void);

/* The most running time any job may take (--max-job-seconds; 0: no limit,
 * the default). A job's own timeout_s may be lower, never higher or 0; one
 * that names none gets the default, capped by this. Set once at start-up,
 * before any thread parses jobs. */
void job_spec_set_max_seconds(double seconds);
double job_spec_max_seconds(void);

/* The longest one whole frame may hold the render thread, seconds
 * (--max-frame-seconds; default JOB_DEFAULT_MAX_FRAME_S): a job whose frame
 * measures more fails before timing unless it accepts sliced timing
 * (daemon/harness/measure.c). Set once at start-up, before any job runs. */
#define JOB_DEFAULT_MAX_FRAME_S 2.0
void job_spec_set_max_frame_seconds(double seconds);
double job_spec_max_frame_seconds(void);

/* The most MSAA samples the device renders (gpu_caps.max_msaa), so that a
 * job over it is refused naming msaa at submission; 0 (the default, before
 * the render thread is up) checks only the rule 1, 2, 4 or 8, and the run
 * then fails naming msaa. Set once at start-up, before HTTP threads parse. */
void job_spec_set_max_msaa(int samples);
int job_spec_max_msaa(void);


/* Fills defaults, then applies and validates the body. techniques is the
 * catalogue of accepted techniques; it must outlive the spec. */
bool job_spec_parse(const json_t *body, const struct technique_catalog *techniques,
                    struct job_spec *out, struct job_error *err);

/* Same, from raw request text (reports JSON syntax errors with position). */
bool job_spec_parse_text(const char *text, size_t len,
                         const struct technique_catalog *techniques, struct job_spec *out,
                         struct job_error *err);

void job_spec_defaults(struct job_spec *out, const struct technique_catalog *techniques);

/* The options of the job's technique and of its reference (NULL without one). */
const void *job_spec_technique_options(const struct job_spec *spec);
const void *job_spec_reference_options(const struct job_spec *spec);

/* What the job's technique and look.post (reference: its reference and
 * reference_look.post) need of time (common/frame_needs.h). */
void job_spec_needs(const struct job_spec *spec, bool reference, struct frame_needs *out);

/* The canonical dotted path of a top-level job field that is an alias of a
 * technique's option ("async_distance" is "osl.async_distance"), or NULL.
 * A job may give either, or both with the same value; sweeps vary either. */
const char *job_spec_alias(const char *field);
/* The alias of a technique option's dotted path, or NULL: the other way. */
const char *job_spec_aliased(const char *path);

/* The job as understood, defaults filled in. New reference. */
json_t *job_spec_to_json(const struct job_spec *spec);

/* True when the job names a stored asset: scene.asset, or an environment
 * map as look.ibl.environment (or reference_look's) {"asset": NAME}. */
bool job_spec_names_asset(const struct job_spec *spec);

/* Number of timed frames that get captured. */
int job_spec_capture_count(const struct job_spec *spec);

/* Runs the job is planned for (the most, with automatic repeats). */
int job_spec_runs(const struct job_spec *spec);

/* True when timed frame (1-based) is captured. */
bool job_spec_is_capture_frame(const struct job_spec *spec, int frame);



#endif
