#ifndef SHADEBENCH_JOB_DIR_H
#define SHADEBENCH_JOB_DIR_H

/* A job's own files in its directory, STATE_DIR/jobs/ID/: spec.json,
 * written once when the job is accepted (a finished job's spec), and
 * result.json, the harness's (complete or not, damaged or not); and what a
 * job's row is rebuilt from when the store has none (store_import): a
 * job.json of the version before the store, or a directory whose row was
 * lost. Used by the job queue (queue.c). GL-free; any thread, the import
 * at startup. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/spec/job_spec.h"
#include "daemon/store/store.h"

/* The spec's labels as a JSON object of strings. New reference. */
json_t *job_dir_labels(const struct job_spec *spec);

/* spec.json (atomically); false with err naming the file and errno. */
bool job_dir_write_spec(const char *dir, const char *id, double created,
                          const struct job_spec *spec, char *err, size_t errlen);

/* The spec in the row's directory's spec.json; NULL (logged) when it cannot
 * be read. New reference. */
json_t *job_dir_read_spec(const struct store_row *row);

/* A complete result.json in dir makes the row done (finish time, progress,
 * figures, and the start time the harness wrote into it, so that a row
 * rebuilt from the directory keeps it); false leaves the row as it was,
 * with why "missing", "incomplete", or, for a file that cannot be read,
 * the reason and where it went: a damaged one is quarantined (records.h)
 * rather than left for the next reader to trip on. */
bool job_dir_done_from_result(struct store *store, struct store_row *row,
                              const struct job_spec *spec, const char *dir, char *why,
                              size_t whylen);

/* A job that was running when the daemon died, without a complete
 * result.json (result_why: job_dir_done_from_result's why): interrupted,
 * saying so. */
void job_dir_interrupted(struct store_row *row, const char *result_why);

/* A done job whose result.json at path cannot be read (why): the file goes
 * to quarantine (when it is there at all), the row becomes failed, naming
 * where it went, and is stored. The caller keeps two threads from
 * repairing one job at once. */
void job_dir_fail_result(struct store *store, struct store_row *row, const char *path,
                           const char *why);

/* store_import's decision about a job directory without a row: an earlier
 * version's job.json is read; without one, or with a damaged one
 * (quarantined), the job is rebuilt from spec.json and result.json; what
 * cannot be rebuilt is quarantined whole (false), never skipped silently. */
bool job_dir_import(struct store *store, const struct technique_catalog *techniques,
                      const char *id, const char *dir, struct store_row *row);

#endif
