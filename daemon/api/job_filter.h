#ifndef SHADEBENCH_JOB_FILTER_H
#define SHADEBENCH_JOB_FILTER_H

/* The filters of the job list, GET /v1/jobs?technique=&status=&label.KEY=
 * VALUE&since=, and the headline figures each listed job carries (median
 * frame_ms, gpu_ms and cpu_ms with their intervals, worst SSIM, device), so
 * that history needs one request. Repeating a filter accepts any of its
 * values (technique=forward&technique=osl); different filters must all
 * hold. GL-free, without HTTP; a filter is built and read by one request
 * thread; unit-tested in tests/unit/test_job_filter.c. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"

#define JOB_FILTER_MAX_TERMS 32

enum job_filter_kind { FILTER_TECHNIQUE, FILTER_STATUS, FILTER_LABEL };

struct job_filter_term {
    enum job_filter_kind kind;
    char label[40];  /* FILTER_LABEL: the label's name */
    char value[160];
};

struct job_filter {
    size_t nterms;
    struct job_filter_term terms[JOB_FILTER_MAX_TERMS];
    char since[32]; /* "" or the ISO 8601 UTC instant jobs must be created at or after */
};

void job_filter_init(struct job_filter *f);

/* Adds one query argument. False, with err naming the argument and the
 * rule, for an unknown argument or a bad value (a status that does not
 * exist, a label name that cannot be one, a time that cannot be read). */
bool job_filter_add(struct job_filter *f, const char *key, const char *value,
                    struct job_error *err);

/* Does a job match? entry is its list entry: "technique", "status",
 * "labels" and "created" (as written by the store). */
bool job_filter_match(const struct job_filter *f, const json_t *entry);

/* The headline figures of a result (NULL: the job has none yet). New
 * reference, or NULL. */
json_t *job_filter_figures(const json_t *result);

/* The store's list visitor (queue_list_json_with): keeps entries that
 * match the filter passed as ctx, adding their figures; frees the others. */
json_t *job_filter_visit(json_t *entry, const json_t *result, void *ctx);

/* "2026-11-21", "2026-11-21T10:00", "2026-11-21T10:00:05Z" or seconds since
 * 1970 into the store's form, "2026-11-21T10:00:05.000Z". */
bool job_filter_parse_time(const char *text, char out[32]);

#endif
