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

/* The sweep's report, with its verdict written out (sweep_verdict_json,
 * on the same copy of the table as its charts, with each point job's noise
 * read from its result.json through job_dir). */
char *report_sweep_html(const json_t *sweep, const json_t *device, report_job_dir_fn job_dir,
                        void *ctx, size_t *len);

/* A job's report: its figures, frame times over the run (from timings.csv
 * in dir), the technique's own figures, runs, quality and captures. */
char *report_job_html(const json_t *job, const char *dir, const json_t *device, size_t *len);

#endif
