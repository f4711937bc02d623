#ifndef SHADEBENCH_JOB_H
#define SHADEBENCH_JOB_H

/* Job specifications: parsing, validation and defaults. GL-free so that it is
 * unit-tested plainly; the technique names come from the caller. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "daemon/quality/metrics.h"
#include "daemon/scene/scene_spec.h"

#define JOB_MAX_BODY_BYTES (64 * 1024)
#define JOB_MAX_CAPTURE_BYTES (1024.0 * 1024.0 * 1024.0)
#define JOB_MAX_CAPTURES 1000

enum osl_reshade {
    OSL_RESHADE_TOUCHED, /* only objects a moving light reaches */
    OSL_RESHADE_ALL,     /* every due object, as the thesis measured */
};


struct osl_spec {
    int resolution; /* tile edge in texels; 0 means "auto" */
    double texel_density;
    enum osl_reshade reshade;
};

struct job_spec {
    char technique[32];
    int frames;
    int warmup_frames;
    int capture_interval;
    double async_distance;
    struct scene_spec scene;
    struct osl_spec osl;
    int repeat;                    /* runs of the job; with repeat_auto, the most */
    bool repeat_auto;              /* stop once the 95% interval is within 2.5% */
    char reference[32];            /* technique to compare captures with; "" for none */
    struct metrics_options metrics; /* used when reference is set */
    double timeout_s;              /* running time allowed, all phases; 0: no limit */
};

/* The timeout_s a job gets when it names none (--job-timeout). Set once at
 * start-up, before any thread parses jobs. */
void job_spec_set_default_timeout(double seconds);
double job_spec_default_timeout(void);


/* Fills defaults, then applies and validates the body. techniques is a
 * NULL-terminated list of accepted technique names. */
bool job_spec_parse(const json_t *body, const char *const *techniques,
                    struct job_spec *out, struct job_error *err);

/* Same, from raw request text (reports JSON syntax errors with position). */
bool job_spec_parse_text(const char *text, size_t len,
                         const char *const *techniques, struct job_spec *out,
                         struct job_error *err);

void job_spec_defaults(struct job_spec *out);

/* The job as understood, defaults filled in. New reference. */
json_t *job_spec_to_json(const struct job_spec *spec);

/* Number of timed frames that get captured. */
int job_spec_capture_count(const struct job_spec *spec);

/* Runs the job is planned for (the most, with automatic repeats). */
int job_spec_runs(const struct job_spec *spec);

/* True when timed frame (1-based) is captured. */
bool job_spec_is_capture_frame(const struct job_spec *spec, int frame);



#endif
