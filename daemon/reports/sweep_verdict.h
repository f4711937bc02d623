#ifndef SHADEBENCH_SWEEP_VERDICT_H
#define SHADEBENCH_SWEEP_VERDICT_H

/* One reading of a sweep's table that its verdict and its charts share, so
 * that they cannot contradict each other: every row as a point (its
 * workload, time with interval, quality, PerceptualDiff, status, noise),
 * the Pareto front decided on intervals, and which points are missing.
 *
 * The rules, all on the intervals the table carries:
 *  - a time is measurably faster than another only when their intervals
 *    separate (a.hi < b.lo); otherwise the two are not distinguishable at
 *    this noise;
 *  - a point is dominated by another of the same workload that is not
 *    measurably slower, at least as accurate, and measurably faster or
 *    more accurate (qualities are exact: frames are deterministic); the
 *    front is the points nothing dominates; front points whose times
 *    overlap another front point's are tied (their order is not known);
 *  - the reference, timed on each workload, is exact by definition (SSIM 1,
 *    FLIP 0).
 * A row may carry "interference" ({"other_cpu_share", "noisy"}, as the
 * point job's result has it): the report adds it, and the point is then
 * marked noisy. GL-free, no I/O; any thread (the view only reads the sweep
 * JSON, which must outlive it); unit-tested in tests/unit/test_charts.c. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

enum { SV_MAX_WORKLOADS = 32 };

/* json_dumps flags for numbers people read: reals to 9 significant digits
 * (0.1 and 22.6, not 0.10000000000000001 and 22.600000000000001). */
#define SV_DUMP_REALS JSON_REAL_PRECISION(9)

struct sv_point {
    const json_t *row;
    const char *technique;
    const char *status;     /* the point job's status, "done" when it ran */
    char label[96];         /* the swept values but the technique: "d=5, lights=8" */
    int workload;           /* index into sweep_view.workloads */
    bool reference;         /* the sweep's reference technique, timed */
    bool timed;             /* has a median of the series */
    double ms, lo, hi;      /* median and interval (lo cut at 0) */
    bool lo_clamped;        /* the interval reached below zero */
    bool has_ssim, has_flip;
    double ssim, flip;      /* worst SSIM and worst mean FLIP (reference: 1, 0) */
    bool judged;            /* PerceptualDiff ran on its captures */
    bool pdiff_pass;        /* every capture passed */
    bool noisy;             /* the row's interference says so */
    double other_share;     /* other processes' CPU share during it, NAN unknown */
    bool pareto, tied;      /* set by sweep_view_front */
};

struct sweep_view {
    const char *series;     /* frame_ms, gpu_ms or cpu_ms */
    const char *reference;  /* the reference technique */
    const char *status;     /* the sweep's */
    struct sv_point *pts;
    int n;
    char workloads[SV_MAX_WORKLOADS][128]; /* swept scene.*, frames, warm-up: "" when none */
    int nworkloads;
    long long points_total; /* as the sweep planned them */
    int not_run;            /* planned points with no row */
    int not_done;           /* rows whose job did not finish (failed, cancelled...) */
    bool partial;           /* not done, or points missing: the verdict covers what ran */
    const char *param;      /* the first numeric swept field (crossovers, x axis); NULL */
    bool numeric_param;     /* param's values are numbers (largest passing value) */
};

/* Reads the sweep (GET /v1/sweeps/ID's JSON) for series. False when out of
 * memory. */
bool sweep_view_init(struct sweep_view *v, const json_t *sweep, const char *series);
void sweep_view_finish(struct sweep_view *v);

/* The Pareto front per workload on speed and accuracy (worst SSIM, or
 * worst FLIP with flip), by the rules above: sets pareto and tied of the
 * points that have a time and a quality. */
void sweep_view_front(struct sweep_view *v, bool flip);

/* a measurably faster than b: the intervals separate. */
bool sv_faster(const struct sv_point *a, const struct sv_point *b);

/* The verdict, for the report and for tools:
 *  "series", "partial" (bool), "status", "points_total", "not_run",
 *  "missing": [{"technique", "values", "status", "error"}] (rows that did
 *  not finish), "noisy": [{"technique", "values", "other_cpu_share"}],
 *  "largest_pdiff_pass" (one numeric swept field: {"param", "value"}, value
 *  null when none passes), "pdiff_passing": [point names] and
 *  "pdiff_judged" (count), "breaking_point" (copied),
 *  "front": per workload [{"workload", "points": [{"name", "ms", "tied"}]}],
 *  "crossovers": [{"faster_below", "faster_above", "param", "between",
 *  "at", "workload", "distinguishable"}],
 *  "against_reference": [{"workload", "reference", "reference_ms",
 *  "reference_ci": [lo, hi], "fastest": {"technique", "values", "ms",
 *  "ratio", "ratio_ci": [lo, hi], "distinguishable", "tied_with": [...]},
 *  "fastest_passing": {...}, "winner": {"technique", "values" (null for
 *  the reference), "ms", "reference" (the reference is measurably faster
 *  than every point), "tied_with_reference"}}].
 * New reference. */
json_t *sweep_verdict_json(const json_t *sweep, const char *series);

#endif
