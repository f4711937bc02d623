#ifndef SHADEBENCH_JOB_FILTER_H
#define SHADEBENCH_JOB_FILTER_H

/* The query arguments of the lists, read into the store's question
 * (store.h): GET /v1/jobs?technique=&status=&label.KEY=VALUE&since= with
 * limit= and cursor=, and GET /v1/sweeps?limit=&cursor=. Repeating a filter
 * accepts any of its values (technique=forward&technique=osl); different
 * filters must all hold. A page holds limit records (100 unless given, at
 * most 1000); cursor is the opaque value of a next link. GL-free, without
 * HTTP; a query is built and read by one request thread; unit-tested in
 * tests/unit/test_job_filter.c. */

#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "daemon/store/store.h"

/* An empty question about kind: every record, the first page. */
void job_filter_init(struct store_query *q, enum store_kind kind);

/* Adds one query argument. False, with err naming the argument and the
 * rule, for an unknown argument (the sweep list takes limit and cursor
 * only) or a bad value (a status that does not exist, a label name that
 * cannot be one, a time that cannot be read, a limit out of range, a
 * cursor no next link gave). */
bool job_filter_add(struct store_query *q, const char *key, const char *value,
                    struct job_error *err);

/* "2026-11-21", "2026-11-21T10:00", "2026-11-21T10:00:05Z" or seconds since
 * 1970 into milliseconds since 1970. */
bool job_filter_parse_time(const char *text, int64_t *ms);

/* Milliseconds since 1970 as "2026-11-21T10:00:05.000Z". */
void job_filter_format_time(int64_t ms, char out[32]);

#endif
