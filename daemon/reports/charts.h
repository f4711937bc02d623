#ifndef SHADEBENCH_CHARTS_H
#define SHADEBENCH_CHARTS_H

/* Charts of sweeps and jobs, drawn with cairo as SVG or PNG, made so that
 * they cannot mislead:
 *  speed_accuracy: x = median frame time with its interval, y = worst SSIM
 *                  (or worst mean FLIP), one series per technique, the
 *                  reference technique as a point of its own (timed on the
 *                  same workload; its quality is exact by definition), a
 *                  Pareto front only among comparable points (the same
 *                  workload: scene and light count, frames), labels placed
 *                  so that none overlaps another or a point;
 *  time_vs_param:  median frame time against the first swept parameter, one
 *                  line per technique, the reference as a line or a level;
 *  distribution:   each point's (or job's) frame-time percentiles.
 * Intervals never cross zero (clamped, and marked so); the time axis is
 * logarithmic when the values span more than a decade. The series defaults
 * to the one meaningful on the device (frame_ms on llvmpipe, whose gpu_ms
 * covers rasterization only; gpu_ms on GPUs) and the chart says which.
 * SVG output carries the chart's layout as JSON in <metadata
 * id="shadebench-chart"> (points, intervals, fronts, label boxes), so that
 * tests and tools can check what was drawn.
 * GL-free; any thread (each call draws on its own surface). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

enum chart_format { CHART_SVG, CHART_PNG };

struct chart_options {
    const char *series;    /* frame_ms, gpu_ms or cpu_ms; NULL: the device's */
    bool flip;             /* speed_accuracy: FLIP instead of SSIM on y */
    const json_t *device;  /* sweeps: the device that measured them (may be NULL) */
};

/* frame_ms on software renderers (llvmpipe, softpipe, SwiftShader) or
 * without a device, gpu_ms on GPUs. */
const char *charts_default_series(const json_t *device);

/* Renders chart name of a sweep (its JSON, as GET /v1/sweeps/ID answers).
 * Returns a malloc'ed buffer, or NULL with err filled (unknown name: err
 * says so). */
char *charts_sweep(const json_t *sweep, const char *name, enum chart_format format,
                   const struct chart_options *o, size_t *len, char *err, size_t errlen);

/* The distribution chart of one job's result. */
char *charts_job(const json_t *job, const char *name, enum chart_format format,
                 const struct chart_options *o, size_t *len, char *err, size_t errlen);

/* A job's frame times over its run: samples is {"frame_ms": [...],
 * "gpu_ms": [...], ...} as read from timings.csv. */
char *charts_job_timeline(const json_t *job, const json_t *samples, enum chart_format format,
                          const struct chart_options *o, size_t *len, char *err, size_t errlen);

#endif
