#ifndef SHADEBENCH_REPORT_H
#define SHADEBENCH_REPORT_H

/* Self-contained HTML reports of a sweep or a job: charts and thumbnails are
 * embedded (base64 PNG), so a saved page reads without the daemon. No
 * scripts. GL-free. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* Finds a point job's directory and its last captured frame. */
typedef bool (*report_job_dir_fn)(void *ctx, const char *job_id, char *dir, size_t cap,
                                  int *last_frame);

char *report_sweep_html(const json_t *sweep, const json_t *device, report_job_dir_fn job_dir,
                        void *ctx, size_t *len);
char *report_job_html(const json_t *job, const char *dir, const json_t *device, size_t *len);

#endif
