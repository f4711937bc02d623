#ifndef SHADEBENCH_RESULT_KEYS_H
#define SHADEBENCH_RESULT_KEYS_H

/* The keys of a job's result (GET /v1/jobs/ID -> "result") that code other
 * than their writer reads, in one place: the harness writes them
 * (runner.c, metrics_stage.c); sweeps, reports, charts, the job list's
 * filters and the client read them. A key renamed here is renamed for every
 * reader, and a reader cannot misspell one without a compile error. Keys
 * only their writer touches stay literal there; the metrics inside a
 * capture are the metrics' own (daemon/quality). The README's result table
 * documents each one. Constants only; any thread, daemon and client. */

#define RK_RESULT "result"

/* Timing series, each a stats object (RK_MEDIAN, RK_P95, RK_CI95, ...). */
#define RK_FRAME_MS "frame_ms"
#define RK_GPU_MS "gpu_ms"
#define RK_CPU_MS "cpu_ms"
#define RK_FPS "fps"
#define RK_RUNS "runs"     /* per-run summaries when a job repeats */
#define RK_REPEAT "repeat" /* the repeat's outcome: runs, stable, ... */
#define RK_STABLE "stable"
#define RK_WALL_S "wall_s"
/* When the job started running (unix seconds): with spec.json, what a row
 * rebuilt from the job's directory takes its start time from. */
#define RK_STARTED_UNIX "started_unix"
#define RK_REFERENCE_MS "reference_ms"
#define RK_WORKLOAD "workload"
#define RK_INTERFERENCE "interference"

/* A series' statistics (common/stats.h computes them). */
#define RK_N "n"
#define RK_MEAN "mean"
#define RK_MEDIAN "median"
#define RK_STDDEV "stddev"
#define RK_MIN "min"
#define RK_MAX "max"
#define RK_P5 "p5"
#define RK_P95 "p95"
#define RK_P99 "p99"
#define RK_CV "cv"
#define RK_CI95 "ci95"               /* over runs: the mean's interval */
#define RK_MEDIAN_CI95 "median_ci95" /* over frames: the median's interval */

/* Captures and their quality against the reference. */
#define RK_CAPTURES "captures"
#define RK_HEATMAP "heatmap"
#define RK_QUALITY "quality"
#define RK_WORST_SSIM "worst_ssim"
#define RK_WORST_SSIM_MIN "worst_ssim_min"
#define RK_WORST_FLIP "worst_flip"
#define RK_WORST_FLICKER "worst_flicker" /* temporal.frames: {value, frame} */
#define RK_TEMPORAL "temporal"           /* a capture's flicker run, and the job's summary */
#define RK_PDIFF_FAILED_CAPTURES "pdiff_failed_captures"
#define RK_PDIFF_FAILED_FRAMES "pdiff_failed_frames"

/* Where a method breaks, for sweeps' criteria and rows. */
#define RK_TECHNIQUE "technique"     /* result[technique]: the technique's own figures */
#define RK_NONFINITE "nonfinite"     /* {pixels_max, finite, ...} over the captures */
#define RK_PIXELS_MAX "pixels_max"
#define RK_FINITE "finite"
#define RK_OVERFLOW "overflow"       /* result[technique].overflow: bounded light lists */
#define RK_OVERFLOW_FRAMES "frames"  /* ... frames in which a list overflowed */
#define RK_SHADOWS "shadows"         /* result.shadows.overflow: the shadow atlas */
#define RK_FRAMES_WITH_DROPS "frames_with_drops"

#endif
