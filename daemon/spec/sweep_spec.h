#ifndef SHADEBENCH_SWEEP_H
#define SHADEBENCH_SWEEP_H

/* Sweep specifications (GL-free): a base job and one or two job fields to
 * vary over listed values (a grid), or one numeric field to bisect for the
 * largest value at which a quality criterion still holds, or the thesis's
 * experiment as a preset. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/spec/job_spec.h"

#define SWEEP_MAX_POINTS 256
/* Fields a grid may vary at once. */
#define SWEEP_MAX_PARAMS 2

enum sweep_kind { SWEEP_VARY, SWEEP_FIND };

enum sweep_criterion { CRITERION_PDIFF_PASS, CRITERION_SSIM_MIN, CRITERION_FLIP_MAX, CRITERION_STABLE,
                       CRITERION_FINITE,     /* no capture had NaN or infinite HDR pixels */
                       CRITERION_NO_OVERFLOW, /* no light list overflowed, no shadow dropped */
                       CRITERION_SSIM_MEAN,   /* "ssim >= X": the worst capture's mean SSIM */
                       CRITERION_FLICKER_MAX  /* "flicker_max <= X": the worst capture run's
                                               * flicker (temporal.frames) */ };

struct sweep_spec {
    enum sweep_kind kind;
    json_t *base;           /* the base job, as given */
    int nparams;
    char params[SWEEP_MAX_PARAMS][64]; /* dotted paths, in the order vary gives them */
    json_t *values[SWEEP_MAX_PARAMS]; /* arrays, for SWEEP_VARY */
    size_t npoints;         /* the grid, then the timed reference points */
    size_t ngrid;           /* SWEEP_VARY: points of the grid itself */
    json_t *reference_values; /* SWEEP_VARY: values of each timed reference point */
    /* SWEEP_FIND */
    double from, to;
    bool integer;
    int step;               /* integer fields: probes are from + k step */
    int max_probes;
    enum sweep_criterion criterion;
    double threshold;
    char criterion_text[64];
    /* Why a result cannot be judged by the criterion, when it lacks what
     * the criterion reads (sweep_criterion_unjudged). */
    char unjudged_text[320];
    bool thesis; /* {"preset": "thesis"}: the thesis's experiment */
    const struct technique_catalog *catalog; /* the one parsed with: it outlives the sweep */
};

/* The thesis preset's size at its body's "scale" (1, 0.5, 0.25 or 0.125; 1
 * when absent): the frame (1080x720 at 1) and OSL's tiles (256 texels a
 * side at 1) shrink alike, keeping the thesis's texels per pixel. false
 * with err naming "scale" for any other value. */
struct thesis_size {
    double scale;
    int width, height, osl_resolution;
};
bool sweep_thesis_size(const json_t *body, struct thesis_size *out, struct job_error *err);

/* Fills out, or returns false with err naming the field and out holding
 * nothing (sweep_spec_finish on it is harmless). */
bool sweep_spec_parse(const json_t *body, const struct technique_catalog *techniques, struct sweep_spec *out,
                      struct job_error *err);
void sweep_spec_finish(struct sweep_spec *s);

/* Every path a sweep may vary, with its kind ("integer", "number", "boolean",
 * "choice"), for /v1/info. New reference. */
json_t *sweep_params_json(const struct technique_catalog *techniques);

/* The job of grid point index (row-major over the parameters); *values gets
 * {"path": value, ...}. Indices from ngrid on are the timed reference
 * points: the reference technique (the catalogue's baseline unless the
 * base names another)
 * on each workload of the grid (each combination of swept scene.*, frames
 * and warmup_frames values), timed like the others and not judged, so that
 * charts and reports place it beside them. A sweep adds none when the
 * reference is already among its techniques, or with "time_reference":
 * false. New references. */
json_t *sweep_point_job(const struct sweep_spec *s, size_t index, json_t **values);

/* The job of a find probe at value v. New reference. */
json_t *sweep_probe_job(const struct sweep_spec *s, double v);

/* Does a finished job's result meet the criterion? */
bool sweep_criterion_holds(const struct sweep_spec *s, const json_t *result);

/* NULL when the result carries what the criterion reads; otherwise why it
 * cannot be judged (no_overflow on a technique without bounded light lists
 * and a look without shadows would hold everywhere and find nothing). */
const char *sweep_criterion_unjudged(const struct sweep_spec *s, const json_t *result);

/* The frames of a result in which the technique's bounded light lists
 * overflowed (result[technique].overflow.frames) and in which the shadow
 * atlas dropped lights (result.shadows.overflow.frames_with_drops); -1 for
 * a record the result does not have (a technique without light lists, a
 * look without shadows). */
void sweep_overflow_frames(const json_t *result, json_int_t *light_lists, json_int_t *shadows);

/* Bisection for the largest value in [from, to] at which holds() is true,
 * for a criterion that holds below some boundary and fails above it. Probes
 * both ends first. Stops when the interval is one step wide (integers) or
 * 1/1000 of the range, or after max_probes probes. */
enum bisect_outcome { BISECT_BOUNDARY, BISECT_HOLDS_EVERYWHERE, BISECT_FAILS_EVERYWHERE, BISECT_ABORTED };
struct bisect_result {
    enum bisect_outcome outcome;
    double value; /* the largest value seen to hold (BOUNDARY, HOLDS_EVERYWHERE) */
    double first_failing;
    int probes;
};
/* holds returns 1 (holds), 0 (fails) or -1 (abort: cancelled or failed). */
void sweep_bisect(double from, double to, bool integer, int max_probes,
                  int (*holds)(double v, void *ctx), void *ctx, struct bisect_result *out);

#endif
