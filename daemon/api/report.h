#ifndef SHADEBENCH_REPORT_H
#define SHADEBENCH_REPORT_H

/* Self-contained HTML reports of a sweep or a job: charts and thumbnails are
 * embedded (base64 PNG), so a saved page reads without the daemon. No
 * scripts. GL-free; any thread (each call works on its own buffers; the
 * sweep and job JSON are only read). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* Finds a point job's directory and its last captured frame. */
typedef bool (*report_job_dir_fn)(void *ctx, const char *job_id, char *dir, size_t cap,
                                  int *last_frame);

/* The sweep's report, with its verdict written out (report_sweep_verdict). */
char *report_sweep_html(const json_t *sweep, const json_t *device, report_job_dir_fn job_dir,
                        void *ctx, size_t *len);

/* A job's report: its figures, frame times over the run (from timings.csv
 * in dir), the technique's own figures, runs, quality and captures. */
char *report_job_html(const json_t *job, const char *dir, const json_t *device, size_t *len);

/* What a sweep says, for people: the largest value passing PerceptualDiff
 * and the breaking point (when the sweep has them); crossovers, where two
 * techniques' times cross along the first swept numeric parameter on the
 * same workload ({"faster_below", "faster_above", "param", "between": [a,
 * b], "at" (linear interpolation), "workload"}); and per workload the
 * reference technique's time against the fastest point and the fastest
 * point passing PerceptualDiff ({"workload", "reference", "reference_ms",
 * "fastest": {"technique", "values", "ms", "ratio"}, "fastest_passing"}).
 * series is the timing series compared. New reference. */
json_t *report_sweep_verdict(const json_t *sweep, const char *series);

#endif
