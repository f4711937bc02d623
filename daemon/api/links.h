#ifndef SHADEBENCH_LINKS_H
#define SHADEBENCH_LINKS_H

/* Adds the URLs to a job's or a sweep's JSON just before the API serves it.
 * The store and the harness record ids and file names only, so that the
 * URL space lives in the API layer (routes.c) and a stored record is never
 * tied to it. HTTP threads; GL-free. */

#include <jansson.h>

#include "daemon/api/routes.h"
#include "daemon/store/store.h"

/* job.url; per capture (result.captures) url from its frame, and
 * reference_url, ssim_map_url and flip_map_url where the capture names
 * that file; each heat map capture's url. Takes a job as GET /v1/jobs/ID
 * or an item of the job list shows it; ignores what it does not know. */
void links_add_job(json_t *job);

/* sweep.url and, for each point, job_url. */
void links_add_sweep(json_t *sweep);

/* Each item of {"jobs": [...]} or {"sweeps": [...]}. */
void links_add_job_list(json_t *list);
void links_add_sweep_list(json_t *list);

/* list.next: the URL of the page after this one, the same question (kind
 * ROUTE_JOBS or ROUTE_SWEEPS, q's filters and limit) from cursor next;
 * nothing when next is "" (this page is the last). */
void links_add_next(json_t *list, enum route_kind kind, const struct store_query *q,
                    const char *next);

#endif
