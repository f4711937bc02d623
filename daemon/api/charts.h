#ifndef SHADEBENCH_CHARTS_H
#define SHADEBENCH_CHARTS_H

/* Charts of sweeps and jobs, drawn with cairo as SVG or PNG. GL-free.
 *  speed_accuracy: x = median frame time with its interval, y = worst SSIM
 *                  (or worst mean FLIP), one series per technique, each point
 *                  labelled with its parameter values, the Pareto front marked;
 *  time_vs_param:  median frame time against the first swept parameter, one
 *                  line per technique;
 *  distribution:   each point's (or job's) frame-time percentiles. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

enum chart_format { CHART_SVG, CHART_PNG };

struct chart_options {
    const char *series; /* frame_ms (default), gpu_ms or cpu_ms */
    bool flip;          /* speed_accuracy: FLIP instead of SSIM on y */
};

/* Renders chart name of a sweep (its JSON, as GET /v1/sweeps/ID answers).
 * Returns a malloc'ed buffer, or NULL with err filled (unknown name: err
 * says so). */
char *charts_sweep(const json_t *sweep, const char *name, enum chart_format format,
                   const struct chart_options *o, size_t *len, char *err, size_t errlen);

/* The distribution chart of one job's result. */
char *charts_job(const json_t *job, const char *name, enum chart_format format,
                 const struct chart_options *o, size_t *len, char *err, size_t errlen);

#endif
