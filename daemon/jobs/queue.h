#ifndef SHADEBENCH_QUEUE_H
#define SHADEBENCH_QUEUE_H

/* The job store and the queue between HTTP threads and the render thread.
 * GL-free. Every change of a job's state is written to its directory
 * (job.json: temporary file, fsync, rename) so that a restarted daemon finds
 * every job again. Only finished jobs are ever freed (by retention), so a
 * job pointer handed to the render or metrics thread stays valid. */

#include <jansson.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdbool.h>

#include "daemon/jobs/job_spec.h"

enum job_status { JOB_QUEUED, JOB_RUNNING, JOB_DONE, JOB_FAILED, JOB_CANCELLED, JOB_INTERRUPTED };

struct job {
    char id[24];
    struct job_spec spec;
    enum job_status status;
    const char *phase; /* while running: "rendering", "reference" or "metrics" */
    int frames_done, frames_total;
    atomic_bool cancel;
    char error[1024];
    json_t *result;
    char dir[PATH_MAX]; /* result.json, timings.csv and frames live here */
    double created, started, finished;
};

struct queue;

enum queue_submit_result { QUEUE_OK, QUEUE_FULL, QUEUE_STOPPING, QUEUE_IO_ERROR };

/* state_dir may be NULL for --once, where out_dir names the single job's dir. */
struct queue *queue_create(const char *state_dir, int max_queued);

/* Retention of finished jobs: keep at most keep_jobs of them (0: all) and
 * none finished more than keep_days ago (0: forever). Their directories are
 * removed; nothing else is ever deleted. */
void queue_set_retention(struct queue *q, int keep_jobs, double keep_days);

/* Reloads the jobs under state_dir/jobs: finished ones are served as before,
 * queued ones run, and one that was running when the daemon died is marked
 * interrupted. Returns the number of jobs loaded, or -1 with err filled. */
int queue_load(struct queue *q, const char *const *techniques, char *err, size_t errlen);
void queue_destroy(struct queue *q);
int queue_max_queued(const struct queue *q);

enum queue_submit_result queue_submit(struct queue *q, const struct job_spec *spec,
                                      const char *dir_override, char id_out[24]);

/* Render thread: blocks until a job is queued (marks it running) or the
 * queue is stopping (returns NULL). */
struct job *queue_next(struct queue *q);
void queue_progress(struct queue *q, struct job *job, int frames_done);
/* phase must be a string literal. */
void queue_set_phase(struct queue *q, struct job *job, const char *phase);
/* Takes ownership of result. */
void queue_finish(struct queue *q, struct job *job, enum job_status status,
                  const char *error, json_t *result);
/* No more jobs start; a running job is asked to stop at its next frame. */
void queue_stop(struct queue *q);

enum queue_cancel_result { CANCEL_DONE, CANCEL_REQUESTED, CANCEL_FINISHED, CANCEL_NOT_FOUND };
enum queue_cancel_result queue_cancel(struct queue *q, const char *id);

/* Snapshot of the job as JSON; with wait_s > 0, first waits until it ends
 * or wait_s pass. NULL when there is no such job. */
json_t *queue_job_json(struct queue *q, const char *id, double wait_s);
json_t *queue_list_json(struct queue *q);

/* Copies the job's directory; false when there is no such job. */
bool queue_job_dir(struct queue *q, const char *id, char *dir, size_t cap,
                   enum job_status *status);

const char *job_status_name(enum job_status s);

/* fn(ctx) is called whenever a job finishes or is cancelled, and when the
 * queue stops, with the queue's lock held: it must return at once and take
 * no lock (the HTTP layer writes to an eventfd). Set once, before serving. */
void queue_set_listener(struct queue *q, void (*fn)(void *ctx), void *ctx);

#endif
