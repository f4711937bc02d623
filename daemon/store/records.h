#ifndef SHADEBENCH_RECORDS_H
#define SHADEBENCH_RECORDS_H

/* Records' directories, under the record store (store.h): one directory
 * per record, STATE_DIR/<kind>/<ID>/, holding its spec.json and whatever
 * else it owns (a job's result.json, timings.csv and images).
 *
 * - Ids are time-ordered ("YYYYMMDD-HHMMSS-NNNN"): they sort by submission
 *   and stay unique across restarts, because each one is a fresh directory.
 * - Loading removes leftover *.tmp files and moves whatever cannot be read
 *   to STATE_DIR/quarantine/, logging the reason. Nothing is ever deleted
 *   but temporary files and, by retention, finished records.
 *
 * GL-free. Each function says which thread may call it. */

#include <jansson.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define RECORD_ID_LEN 24

/* One kind of record: where they live. The caller owns the memory
 * (record_kind_init; nothing to finish). */
struct record_kind {
    char state_dir[PATH_MAX]; /* "" when there is none (--once) */
    char root[PATH_MAX];      /* state_dir/name */
    char name[16];            /* "jobs", "sweeps" */
    atomic_uint serial;       /* the last id's number */
};

void record_kind_init(struct record_kind *k, const char *state_dir, const char *name);

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

/* Reads a record file as JSON. NULL with why filled: the errno, "empty
 * file", or the JSON error with its line and column. Any thread. */
json_t *record_read(const char *path, char *why, size_t whylen);

/* Moves path (a record's directory or one of its files) to
 * STATE_DIR/quarantine/<kind>-<id>[-<file name>]-<UTC time>, with the reason
 * written beside it as <that name>.reason, and logs both. true when moved;
 * false (logged, with errno) leaves it where it was. Any thread. */
bool record_quarantine(const struct record_kind *k, const char *id, const char *path,
                       const char *reason, char *moved_to, size_t cap);

/* For each entry under root, in id order: a directory with a valid id that
 * known(ctx, id) does not claim (known may be NULL) has its *.tmp files
 * removed, then load(ctx, id, dir) decides about it; a known one is left
 * as it is, unopened (a store of 100,000 records starts without opening
 * them); anything else is quarantined, and *.tmp files directly under root
 * removed. Returns the number of directories handed to load, 0 when root
 * does not exist, -1 with err when it cannot be read. Startup, before
 * other threads use the owner. */
typedef void (*record_load_fn)(void *ctx, const char *id, const char *dir);
typedef bool (*record_known_fn)(void *ctx, const char *id);
int record_scan(struct record_kind *k, record_known_fn known, record_load_fn load, void *ctx,
                char *err, size_t errlen);

/* Removes *.tmp files in dir: what an interrupted atomic write leaves. */
void record_remove_tmp_files(const char *dir);

/* Why the calling thread's last submission (of a job or a sweep) could not
 * be persisted: the state directory, the file and the errno text. Each
 * thread has its own. */
const char *records_submit_error(void);
void records_set_submit_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Removes a record's directory: its files, then the directory. Any thread,
 * no owner lock held. false (logged) when something stays. */
bool record_remove_dir(const char *dir);

#endif
