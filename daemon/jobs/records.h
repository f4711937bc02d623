#ifndef SHADEBENCH_RECORDS_H
#define SHADEBENCH_RECORDS_H

/* Records on disk, shared by the job store (queue.c) and the sweeps
 * (sweeps.c): one directory per record, STATE_DIR/<kind>/<ID>/, holding the
 * record's state file (job.json, sweep.json) and whatever else it owns.
 *
 * - Ids are time-ordered ("YYYYMMDD-HHMMSS-NNNN"): they sort by submission
 *   and stay unique across restarts, because each one is a fresh directory.
 * - Writes are snapshots: the owner builds the JSON under its own lock and
 *   numbers it, then writes it with no lock of its own held (temporary
 *   file, fsync, rename). The record's writer skips a snapshot older than
 *   the one on disk, so two threads racing to write never leave the older
 *   state behind.
 * - Loading removes leftover *.tmp files and moves whatever cannot be read
 *   to STATE_DIR/quarantine/, logging the reason. Nothing is ever deleted
 *   but temporary files and, by retention, finished records.
 *
 * GL-free. Each function says which thread may call it. */

#include <jansson.h>
#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define RECORD_ID_LEN 24

/* One kind of record: where they live and what their state file is called.
 * The caller owns the memory (record_kind_init; nothing to finish). */
struct record_kind {
    char state_dir[PATH_MAX]; /* "" when there is none (--once) */
    char root[PATH_MAX];      /* state_dir/name */
    char name[16];            /* "jobs", "sweeps" */
    char file[32];            /* "job.json", "sweep.json" */
    atomic_uint serial;       /* the last id's number */
};

void record_kind_init(struct record_kind *k, const char *state_dir, const char *name,
                      const char *file);

/* Ids are digits and dashes, shorter than RECORD_ID_LEN. */
bool record_id_valid(const char *id);

/* Any thread, no lock held: picks the next id and creates its directory
 * under root (an id whose directory exists is skipped). With dir_override
 * (--once), that directory is used as it is. false with err naming the
 * directory and errno. */
bool record_create_dir(struct record_kind *k, const char *dir_override, char id[RECORD_ID_LEN],
                       char *dir, size_t cap, char *err, size_t errlen);

/* Startup: ids created later continue after this loaded one. */
void record_note_id(struct record_kind *k, const char *id);

/* The ordered writer of one record. The owner embeds it and numbers its
 * snapshots under its own lock; init/finish pair with the record. */
struct record_writer {
    pthread_mutex_t lock; /* held across the write: by writers of this record only */
    uint64_t written;     /* number of the snapshot on disk, 0 for none */
};

void record_writer_init(struct record_writer *w);
void record_writer_finish(struct record_writer *w);

/* Any thread, holding no lock of the owner: writes snapshot number seq to
 * path atomically unless a snapshot numbered seq or later is already there
 * (then true without writing). false with err naming the file and errno. */
bool record_writer_write(struct record_writer *w, uint64_t seq, const char *path,
                         const json_t *snapshot, char *err, size_t errlen);

/* Reads a record file as JSON. NULL with why filled: the errno, "empty
 * file", or the JSON error with its line and column. Any thread. */
json_t *record_read(const char *path, char *why, size_t whylen);

/* Moves path (a record's directory or one of its files) to
 * STATE_DIR/quarantine/<kind>-<id>[-<file name>]-<UTC time>, with the reason
 * written beside it as <that name>.reason, and logs both. true when moved;
 * false (logged, with errno) leaves it where it was. Any thread. */
bool record_quarantine(const struct record_kind *k, const char *id, const char *path,
                       const char *reason, char *moved_to, size_t cap);

/* For each entry under root: a directory with a valid id has its *.tmp
 * files removed, then load(ctx, id, dir) decides about it; anything else
 * is quarantined. Returns the number of directories handed to load, 0 when
 * root does not exist, -1 with err when it cannot be read. Startup, before
 * other threads use the owner. */
typedef void (*record_load_fn)(void *ctx, const char *id, const char *dir);
int record_scan(struct record_kind *k, record_load_fn load, void *ctx, char *err,
                size_t errlen);

/* Why the calling thread's last submission (of a job or a sweep) could not
 * be persisted: the state directory, the file and the errno text. Each
 * thread has its own. */
const char *records_submit_error(void);
void records_set_submit_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Retention, a pure function: finished[i] is record i's finish time (unix
 * seconds), or negative while it has not finished. Marks victim[i] for
 * finished records beyond the newest keep (0: no limit), earliest finished
 * first, and those finished before now - keep_days (0: forever). Returns
 * the number of victims. */
size_t record_retention(const double *finished, size_t n, int keep, double keep_days, double now,
                        bool *victim);

/* Removes a record's directory: its files, then the directory. Any thread,
 * no owner lock held. false (logged) when something stays. */
bool record_remove_dir(const char *dir);

#endif
