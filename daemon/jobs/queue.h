#ifndef SHADEBENCH_QUEUE_H
#define SHADEBENCH_QUEUE_H

/* The job store and the queue between HTTP threads and the render thread.
 * GL-free. Every change of a job's state is written to its directory
 * (job.json: temporary file, fsync, rename; records.h) so that a restarted
 * daemon finds every job again. Only finished jobs are ever freed (by
 * retention), so a job pointer handed to the render or metrics thread stays
 * valid.
 *
 * Locking, for timings nothing disturbs: the store lock guards the jobs'
 * state and is never held across file I/O (a snapshot of the job is taken
 * under it and written after it is released, in order per job). The render
 * thread's timed loop takes no lock at all: progress is an atomic. Any
 * thread may call any function unless its comment says otherwise. */

#include <jansson.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdbool.h>

#include "daemon/jobs/job_spec.h"
#include "daemon/jobs/records.h"

enum job_status { JOB_QUEUED, JOB_RUNNING, JOB_DONE, JOB_FAILED, JOB_CANCELLED, JOB_INTERRUPTED };

/* id, spec, dir and frames_total never change once the job is accepted;
 * frames_done and cancel are atomics; the rest is the store's, read through
 * queue_job_json. */
struct job {
    char id[RECORD_ID_LEN];
    struct job_spec spec;
    enum job_status status;
    const char *phase; /* while running: "rendering", "reference" or "metrics" */
    atomic_int frames_done;
    int frames_total;
    atomic_bool cancel;
    char error[1024];
    json_t *result;
    char dir[PATH_MAX]; /* result.json, timings.csv and frames live here */
    double created, started, finished;
    /* The store's own, under its lock. */
    uint64_t seq;         /* number of the newest state, for ordered writes */
    unsigned pending;     /* snapshots not yet written: retention waits */
    bool user_cancel;     /* DELETE asked for it: a stop then does not requeue */
    bool requeue_on_stop; /* cancelled by a stop: back to the queue, not failed */
    struct record_writer writer;
};

struct queue;

/* QUEUE_IO_ERROR: the job could not be persisted, so it was not accepted
 * (nothing of it is left behind); queue_submit_error says why. */
enum queue_submit_result { QUEUE_OK, QUEUE_FULL, QUEUE_STOPPING, QUEUE_IO_ERROR };

/* state_dir may be NULL for --once, where out_dir names the single job's dir. */
struct queue *queue_create(const char *state_dir, int max_queued);

/* Retention of finished jobs: keep at most keep_jobs of them (0: all) and
 * none finished more than keep_days ago (0: forever). Their directories are
 * removed; nothing else is ever deleted. */
void queue_set_retention(struct queue *q, int keep_jobs, double keep_days);

/* Retention settings, for the sweeps that share them. */
void queue_retention(struct queue *q, int *keep_jobs, double *keep_days);
/* "" for --once. */
const char *queue_state_dir(const struct queue *q);

/* Startup, before other threads use the store. Reloads the jobs under
 * state_dir/jobs: finished ones are served as before, queued ones run
 * (a job SIGTERM stopped is queued), and one that was running when the
 * daemon died is marked interrupted. Leftover *.tmp files are removed; a
 * record that cannot be read is logged and quarantined (records.h); a
 * damaged job.json is rebuilt from spec.json and result.json where they are
 * intact. Returns the number of jobs loaded, or -1 with err filled. */
int queue_load(struct queue *q, const struct technique_catalog *techniques, char *err, size_t errlen);
/* After every thread using it has stopped: writes any state a full disk
 * held back, then frees. Accepts NULL. */
void queue_destroy(struct queue *q);
int queue_max_queued(const struct queue *q);

/* Accepts a job only once its spec.json and job.json are on disk. */
enum queue_submit_result queue_submit(struct queue *q, const struct job_spec *spec,
                                      const char *dir_override, char id_out[24]);
/* Why the calling thread's last queue_submit (or sweeps_submit) returned
 * QUEUE_IO_ERROR: names the state directory, the file and the errno text. */
const char *queue_submit_error(void);

/* Render thread: blocks until a job is queued (marks it running) or the
 * queue is stopping (returns NULL). */
struct job *queue_next(struct queue *q);
/* Render thread, from the timed loop: an atomic store, no lock. */
void queue_progress(struct queue *q, struct job *job, int frames_done);
/* phase must be a string literal. */
void queue_set_phase(struct queue *q, struct job *job, const char *phase);
/* Takes ownership of result. A job cancelled because the daemon is
 * stopping (queue_stop) goes back to the head of the queue instead, and is
 * persisted as queued. */
void queue_finish(struct queue *q, struct job *job, enum job_status status,
                  const char *error, json_t *result);
/* No more jobs start; a running job is asked to stop at its next frame and
 * will be requeued, unless a DELETE had already asked to cancel it. */
void queue_stop(struct queue *q);

enum queue_cancel_result { CANCEL_DONE, CANCEL_REQUESTED, CANCEL_FINISHED, CANCEL_NOT_FOUND };
enum queue_cancel_result queue_cancel(struct queue *q, const char *id);

/* Snapshot of the job as JSON; with wait_s > 0, first waits until it ends
 * or wait_s pass. NULL when there is no such job. */
json_t *queue_job_json(struct queue *q, const char *id, double wait_s);
json_t *queue_list_json(struct queue *q);

/* The list with a say per job, for filters and figures: fn gets the job's
 * list entry with its "labels" (its own reference) and its result
 * (borrowed, NULL until done), under the store's lock, so it must be quick
 * and must not keep result. It returns the entry to list (it may add to it)
 * or NULL to leave the job out (releasing the entry). */
typedef json_t *(*queue_list_fn)(json_t *entry, const json_t *result, void *ctx);
json_t *queue_list_json_with(struct queue *q, queue_list_fn fn, void *ctx);

/* Copies the job's directory; false when there is no such job. */
bool queue_job_dir(struct queue *q, const char *id, char *dir, size_t cap,
                   enum job_status *status);

const char *job_status_name(enum job_status s);

/* fn(ctx) is called whenever a job finishes or is cancelled, and when the
 * queue stops, with the queue's lock held: it must return at once and take
 * no lock (the HTTP layer writes to an eventfd). Set once, before serving. */
void queue_set_listener(struct queue *q, void (*fn)(void *ctx), void *ctx);

#endif
