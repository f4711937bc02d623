#ifndef SHADEBENCH_QUEUE_H
#define SHADEBENCH_QUEUE_H

/* The jobs: the queue between HTTP threads and the render thread, on top of
 * the record store (store.h). GL-free. Every change of a job's state is
 * written to the store before it is shown, so that a restarted daemon
 * finds every job again; a job is accepted only once it is stored.
 *
 * Only the jobs that can still change live in memory as struct job: queued
 * and running ones (and a finished one while its last write is in flight).
 * A finished job leaves memory once stored, and is read back from the store
 * (its row) and its directory (result.json) when asked for; so a box with
 * 100,000 finished jobs holds none of them. A job pointer handed to the
 * render or metrics thread stays valid until queue_finish returns.
 *
 * Locking, for timings nothing disturbs: the queue's lock guards the live
 * jobs and is never held across file I/O or a store write (a snapshot of
 * the job is taken under it and written after it is released, in order per
 * job). The render thread's timed loop takes no lock at all: progress is an
 * atomic. Any thread may call any function unless its comment says
 * otherwise. */

#include <jansson.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdbool.h>

#include "daemon/spec/job_spec.h"
#include "daemon/store/records.h"
#include "daemon/store/store.h"

/* id (first: store_live), spec, dir and frames_total never change once the
 * job is accepted;
 * frames_done and cancel are atomics; the rest is the store's, read through
 * queue_job_json. */
struct job {
    char id[RECORD_ID_LEN];
    struct job_spec spec;
    enum job_status status;
    const char *phase; /* while running: "rendering", "reference" or "metrics" */
    atomic_int frames_done;
    /* When its first frame was counted done (clock_unix_s; 0 before): the
     * time left is read from the frames drawn since (job_eta_left). */
    _Atomic double frames_began;
    int frames_total;
    atomic_bool cancel;
    char error[1024];
    json_t *result;
    char dir[PATH_MAX]; /* result.json, timings.csv and frames live here */
    double created, started, finished;
    /* The queue's own, under its lock. */
    struct store_version version; /* ordered writes; it stays in memory until stored */
    bool user_cancel;     /* DELETE asked for it: a stop then does not requeue */
    bool requeue_on_stop; /* cancelled by a stop: back to the queue, not failed */
    bool dir_given;       /* --once: dir is the caller's */
};

struct queue;

/* QUEUE_IO_ERROR: the job could not be persisted, so it was not accepted
 * (nothing of it is left behind); queue_submit_error says why. */
/* QUEUE_REFUSED: the job names an asset the resolver refused
 * (queue_submit_error says which field and why). */
enum queue_submit_result { QUEUE_OK, QUEUE_FULL, QUEUE_STOPPING, QUEUE_IO_ERROR, QUEUE_REFUSED };

/* On store (a store in memory for --once, where queue_submit's dir_override
 * names the single job's directory); the store outlives the queue. */
struct queue *queue_create(struct store *store, int max_queued);
struct store *queue_store(const struct queue *q);

/* Retention of finished jobs: keep at most keep_jobs of them (0: all) and
 * none finished more than keep_days ago (0: forever). Their rows and
 * directories are removed, the earliest finished first; nothing else is
 * ever deleted. It runs at startup and after each job finishes, a batch at
 * a time, between jobs. */
void queue_set_retention(struct queue *q, int keep_jobs, double keep_days);

/* Retention settings, for the sweeps that share them. */
void queue_retention(struct queue *q, int *keep_jobs, double *keep_days);

/* Retention asks needed(ctx, id) before it removes a finished job, and
 * keeps it while the answer is true (the sweeps: a point of a queued or
 * running sweep). needed is called with no lock of the queue held. Set
 * once, before serving. */
void queue_set_retention_guard(struct queue *q, bool (*needed)(void *ctx, const char *id),
                               void *ctx);

/* Startup, before other threads use the queue. Imports the job directories
 * the store has no row for (a state directory of an earlier version, with
 * job.json files; a submission cut short; every job after a damaged
 * database was recovered): a damaged job.json is quarantined and the job
 * rebuilt from spec.json and result.json where they are intact, a record
 * that cannot be read is logged and quarantined (records.h). Then queued
 * jobs run (a job SIGTERM stopped is queued), and one that was running when
 * the daemon died is marked interrupted, or done when its result.json is
 * complete. Returns the number of jobs in the store, or -1 with err. */
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

/* While the state directory's disk is full (store_has_room), its reserve
 * is for recording how the jobs already accepted end: nothing new (what: a
 * "job" or a "sweep") is accepted. false, with queue_submit_error's text
 * set, when it must be refused. */
bool queue_room_to_accept(struct queue *q, const char *what);

/* Render thread: blocks until a job is queued (marks it running) or the
 * queue is stopping (returns NULL). */
struct job *queue_next(struct queue *q);
/* Render thread, from the timed loop: an atomic store, no lock (and, at
 * the first frame counted, the time, once). */
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

/* At exit, when the render thread has not let go of its job in time (after
 * queue_stop): stores the running job as it would have ended, cancelled
 * when a DELETE asked for it, else queued again, so that a restart does not
 * find it running and call it interrupted. The render thread may still
 * finish it meanwhile: the store keeps the newer of the two. */
void queue_store_abandoned(struct queue *q);

enum queue_cancel_result { CANCEL_DONE, CANCEL_REQUESTED, CANCEL_FINISHED, CANCEL_NOT_FOUND };
enum queue_cancel_result queue_cancel(struct queue *q, const char *id);

/* Snapshot of the job as JSON, with its spec and, once done, its result
 * (read from result.json: a damaged one is quarantined and the job marked
 * failed, naming where the file went); with wait_s > 0, first waits until
 * it ends or wait_s pass. NULL when there is no such job. */
json_t *queue_job_json(struct queue *q, const char *id, double wait_s);

/* One page of the job list, {"jobs": [...]}: each job's state, "labels"
 * and, once done, "figures" (job_figures.h), never its result; query says
 * which jobs (filters) and where the page starts. next gets the cursor of
 * the next page, "" after the last. NULL with err on a store error. */
json_t *queue_list_page(struct queue *q, const struct store_query *query,
                        char next[RECORD_ID_LEN], char *err, size_t errlen);

/* Jobs in the store by status, for /metrics. */
bool queue_counts(struct queue *q, size_t counts[JOB_STATUS_COUNT]);

/* Copies the job's directory; false when there is no such job. */
bool queue_job_dir(struct queue *q, const char *id, char *dir, size_t cap,
                   enum job_status *status);

/* fn(ctx) is called whenever a job finishes or is cancelled, and when the
 * queue stops, with the queue's lock held: it must return at once and take
 * no lock (the HTTP layer writes to an eventfd). Set once, before serving. */
void queue_set_listener(struct queue *q, void (*fn)(void *ctx), void *ctx);

/* The pins of the assets a job names (daemon/jobs/assets.h: scene.asset and
 * look.ibl.environment's), so that no accepted job loses its asset:
 * queue_submit calls pin for a spec naming an asset (job_spec_names_asset;
 * any thread, no lock of the queue's held), which resolves each name to its
 * hash (filling the hashes and scene.asset_bytes) and pins it in one
 * step, or returns false with the field and the rule; once the job is live
 * (its queued or running state protects the hash from then on:
 * queue_asset_in_use) or refused, unpin lets that pin go. ended is called
 * once a job on an asset has finished (cancelled, failed, done), with no
 * lock of the queue's held, so that a hash no name points at any more goes
 * with the last job pinned to it. The hooks are called under a lock of
 * their own, so that once queue_set_asset_hooks(q, NULL) returns none is
 * running or will run. */
struct queue_asset_hooks {
    bool (*pin)(void *ctx, struct job_spec *spec, bool restore, char *field, size_t field_cap,
                char *message, size_t message_cap);
    void (*unpin)(void *ctx, const struct job_spec *spec);
    void (*ended)(void *ctx, const struct job_spec *spec);
    void *ctx;
};
void queue_set_asset_hooks(struct queue *q, const struct queue_asset_hooks *hooks);
/* A sweep's pin, through the same hooks, held for the sweep's life (all its
 * points run on that hash) until queue_asset_unpin. restore: a sweep
 * resumed at start-up, whose hash may have no name any more, pinned while
 * its files are there. false with queue_submit_error's text when refused;
 * true with nothing pinned when no hooks are set. */
bool queue_asset_pin(struct queue *q, struct scene_spec *scene, bool restore);
void queue_asset_unpin(struct queue *q, const struct scene_spec *scene);
/* Is a queued or running job using the asset of that name, or of that hash
 * (either may be NULL)? *id_out gets the first such job's id. Any thread. */
bool queue_asset_in_use(struct queue *q, const char *name, const char *sha256,
                        char id_out[RECORD_ID_LEN]);

#endif
