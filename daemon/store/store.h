#ifndef SHADEBENCH_STORE_H
#define SHADEBENCH_STORE_H

/* The record store of jobs and sweeps: one SQLite database,
 * STATE_DIR/store.db, in write-ahead-log mode with synchronous=FULL, so that
 * a write that returned survives kill -9 and a power cut. One row per record
 * holds what lists show and filters read (status, technique, times,
 * progress, labels, a job's headline figures, the error) and what its owner
 * needs to bring it back (an unfinished job's spec; a sweep's table), with
 * indexes for the
 * list filters; labels have a table of their own. Everything else a record
 * owns stays in its directory, STATE_DIR/<kind>/<ID>/ (records.h): its
 * spec.json, written once when it is accepted, and a job's result.json,
 * timings.csv and images. Why SQLite and not an index of our own: see
 * docs/store.md.
 *
 * The directories alone are enough to rebuild the rows (store_import): that
 * is how a state directory of an earlier version (job.json and sweep.json,
 * no database) is imported on first start, and how a damaged database is
 * recovered (moved to quarantine, then rebuilt).
 *
 * Threads: any, unless said. Writes go through one connection under one
 * lock, held across the commit and nothing else; reads take a connection of
 * their own from a small pool, so that a list never waits for a commit's
 * fsync. The store holds none of its owners' locks and never calls back
 * into its owner with one of its own held, except store_list (see there).
 * GL-free. Unit-tested in tests/unit/test_store.c. */

#include <jansson.h>
#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/store/records.h"

#define STORE_FILE "store.db"

/* The states of a job, and of a sweep. */
enum job_status { JOB_QUEUED, JOB_RUNNING, JOB_DONE, JOB_FAILED, JOB_CANCELLED, JOB_INTERRUPTED };
#define JOB_STATUS_COUNT 6

const char *job_status_name(enum job_status s);
bool job_status_parse(const char *name, enum job_status *out);
static inline bool job_status_finished(enum job_status s)
{
    return s != JOB_QUEUED && s != JOB_RUNNING;
}

enum store_kind { STORE_JOBS, STORE_SWEEPS };
#define STORE_KINDS 2

/* One record as a row. init/finish pair; finish releases the JSON. */
struct store_row {
    enum store_kind kind;
    char id[RECORD_ID_LEN];
    enum job_status status;
    char technique[64];  /* a job's technique; a sweep's kind ("vary", "find") */
    double created, started, finished; /* unix seconds; 0: not yet */
    int done, total;     /* progress: a job's frames, a sweep's points */
    char error[1024];
    /* Where its files are: STATE_DIR/<kind>/<ID>, unless the record was
     * given a directory of its own (--once), which the row then keeps. */
    char dir[PATH_MAX];
    bool dir_given;
    json_t *labels;  /* object of strings, or NULL */
    json_t *figures; /* a job's headline figures (job_figures.h), or NULL */
    json_t *spec;    /* a job's spec (NULL once finished: see queue.c); a sweep's body */
    json_t *extra;   /* a sweep's table and result; NULL for jobs */
};

void store_row_init(struct store_row *r, enum store_kind kind);
void store_row_finish(struct store_row *r);

/* What jobs and sweeps share in memory (queue.c, sweeps.c): the records
 * that can still change, and the numbering of their writes. Both live
 * under the owner's lock, never the store's. */

/* The live records, in id order: pointers to the owner's structs, each of
 * which begins with its id (char id[RECORD_ID_LEN]). */
struct store_live {
    void **items;
    size_t count, cap;
};
bool store_live_insert(struct store_live *l, void *item); /* false: out of memory */
void *store_live_find(const struct store_live *l, const char *id);
void store_live_remove(struct store_live *l, const void *item);
void store_live_finish(struct store_live *l); /* frees the array, not the items */

/* Ordered writes of one live record: each state taken under the owner's
 * lock is numbered, written with no lock held (store_put, which keeps
 * written), then counted back. */
struct store_version {
    uint64_t seq;     /* the newest state */
    uint64_t saved;   /* the newest state stored */
    unsigned pending; /* states taken, not yet written */
    uint64_t written; /* the store's, under its write lock (store_put) */
};
/* A new state to write: its number. */
uint64_t store_version_take(struct store_version *v);
/* Its write returned ok or not. True when every state is stored: a
 * finished record may then leave memory. */
bool store_version_back(struct store_version *v, uint64_t seq, bool ok);
static inline bool store_version_stored(const struct store_version *v)
{
    return !v->pending && v->saved == v->seq;
}

struct store;

/* Opens (creating it) STATE_DIR/store.db; state_dir NULL or "" keeps the
 * rows in memory, for --once. A database that cannot be read (not a
 * database, or its integrity check fails) is moved to STATE_DIR/quarantine
 * with the reason beside it and a new one started, which store_import then
 * fills from the directories. Finishes removals that a stop cut short. NULL
 * with err (naming the file and the reason) when it cannot open one at
 * all. Main thread, before other threads use it. */
struct store *store_open(const char *state_dir, char *err, size_t errlen);
/* After every thread using it has stopped. Accepts NULL. */
void store_close(struct store *s);

/* "" for a store in memory. */
const char *store_state_dir(const struct store *s);
/* Where the kind's directories are and which ids they have; for
 * record_create_dir and record_quarantine. */
struct record_kind *store_record_kind(struct store *s, enum store_kind kind);

/* Inserts or updates the row (labels never change once inserted). Ordered
 * writes: with written non-NULL, a row numbered seq is written only when
 * *written < seq, and *written (guarded by the store's write lock, so only
 * read it through here) becomes seq; an older snapshot that arrives late
 * never replaces a newer one. false with err naming the database and the
 * system's reason ("No space left on device"). */
bool store_put(struct store *s, const struct store_row *r, uint64_t seq, uint64_t *written,
               char *err, size_t errlen);

/* A full disk (store_reserve.h): when a write fails for want of space,
 * the state it could not store is noted in STATE_DIR/store.reserve and the
 * reserve's room released for one more try. store_has_room is false from
 * then until the room can be taken back (tried at most once a second) with
 * some free space beside it (STORE_RESERVE_HEADROOM): no job should start
 * or be accepted meanwhile. A store in memory always has room. Any thread. */
bool store_has_room(struct store *s);
/* The reserve is released (no attempt to take it back). Any thread. */
bool store_disk_full(struct store *s);
/* Startup: the state an earlier run could not store for kind/id, even
 * with the reserve's room (its status and error); false when none. */
bool store_unrecorded(struct store *s, enum store_kind kind, const char *id,
                      enum job_status *status, char *error, size_t cap);
/* Startup: those states are stored now; their notes go. */
void store_unrecorded_done(struct store *s);

enum store_found { STORE_FOUND, STORE_MISSING, STORE_ERROR };
/* One row; with full false, without labels, figures, spec and extra (for
 * the cheap questions: status, directory). STORE_ERROR is logged. out is
 * initialised in every case (store_row_finish it). */
enum store_found store_get(struct store *s, enum store_kind kind, const char *id, bool full,
                           struct store_row *out);

/* A list's question: filters, and the page. Terms of one kind (and one
 * label name) are alternatives; different ones must all hold. */
#define STORE_MAX_TERMS 32
#define STORE_LIMIT_DEFAULT 100
#define STORE_LIMIT_MAX 1000
enum store_term_kind { STORE_TERM_TECHNIQUE, STORE_TERM_STATUS, STORE_TERM_LABEL };
struct store_term {
    enum store_term_kind kind;
    char label[40]; /* STORE_TERM_LABEL: the label's name */
    char value[160];
};
struct store_query {
    enum store_kind kind;
    size_t nterms;
    struct store_term terms[STORE_MAX_TERMS];
    int64_t since_ms;          /* created at or after (ms since 1970); 0: any */
    char after[RECORD_ID_LEN]; /* the cursor: ids after this one (before it when
                                  newest); "": from the start */
    int limit;                 /* 1 to STORE_LIMIT_MAX */
    bool newest;               /* newest first (the dashboard's order), else oldest */
};

/* Calls fn for each row of the page, in id order (submission order; newest
 * first with q->newest, when the cursor is the smallest id served), with
 * labels and figures (and a sweep's extra) but no spec. fn must be quick and
 * must not call the store: a read connection is held. next gets the cursor
 * of the following page, or "" when this page is the last. false (logged,
 * err filled) on a database error. */
typedef void (*store_row_fn)(void *ctx, const struct store_row *row);
bool store_list(struct store *s, const struct store_query *q, store_row_fn fn, void *ctx,
                char next[RECORD_ID_LEN], char *err, size_t errlen);

/* Rows by status, for /metrics. */
bool store_count(struct store *s, enum store_kind kind, size_t counts[JOB_STATUS_COUNT]);

/* Startup: fn for every queued or running row, whole, in id order; fn may
 * call the store. false when they cannot be read (logged). */
bool store_each_unfinished(struct store *s, enum store_kind kind, store_row_fn fn, void *ctx);

/* Retention's choice: the finished rows beyond the newest keep (by finish
 * time; 0: no limit) and those finished before now - keep_days (0:
 * forever), earliest finished first, at most max of them. Returns how many
 * (-1 on a database error, logged). */
int store_retention_victims(struct store *s, enum store_kind kind, int keep, double keep_days,
                            double now, char (*ids)[RECORD_ID_LEN], int max);

/* Removes records: their rows (with a note of the removal, in the same
 * transaction), then, with no lock held, their directories, then the note.
 * A removal cut short by a crash is finished by the next store_open, so a
 * removed record never comes back as an unknown directory. */
bool store_remove(struct store *s, enum store_kind kind, char (*ids)[RECORD_ID_LEN], int n);

/* Startup, before other threads use the store: for each directory under
 * the kind's root that has no row (a state directory of an earlier
 * version, a submission cut short, or every record after the database was
 * recovered), its *.tmp files are removed and import(ctx, id, dir, row)
 * decides: true inserts the row it filled, false skips it (import
 * quarantined it). Rows are committed in batches; after each commit the
 * legacy state file (legacy_file, "job.json" or "sweep.json") is removed
 * from the imported directories, the row now holding what it said.
 * Entries that are not record directories, and *.tmp files, are dealt with
 * as record_scan does. Returns the number imported, -1 with err. */
typedef bool (*store_import_fn)(void *ctx, const char *id, const char *dir, struct store_row *row);
int store_import(struct store *s, enum store_kind kind, const char *legacy_file,
                 store_import_fn import, void *ctx, char *err, size_t errlen);

/* Assets (daemon/jobs/assets.h), table assets (schema 2). A name is at most
 * SCENE_ASSET_NAME_MAX (128) bytes. */
#define STORE_ASSET_NAME_CAP 130
struct store_asset {
    char name[STORE_ASSET_NAME_CAP];
    char sha256[65];   /* of the uploaded file, lowercase hex */
    char ext[8];       /* "glb" or "gltf": the original's extension */
    uint64_t size;     /* the uploaded file's bytes */
    double created, updated; /* unix seconds: the first upload, the last */
    bool from_dir;     /* --asset-dir: read-only over HTTP */
    json_t *description; /* the converter's, or NULL */
};
void store_asset_finish(struct store_asset *a);
/* Inserts or replaces the asset of that name (created kept on replace). */
bool store_asset_put(struct store *s, const struct store_asset *a, char *err, size_t errlen);
/* out is zeroed in every case (store_asset_finish it). */
enum store_found store_asset_get(struct store *s, const char *name, struct store_asset *out);
bool store_asset_delete(struct store *s, const char *name, char *err, size_t errlen);
/* How many names point at that hash; -1 on a database error. */
int store_asset_hash_refs(struct store *s, const char *sha256);
/* A page of assets by name after `after` ("" from the start), at most
 * limit; dir_only: those of --asset-dir. fn must be quick and must not call
 * the store. next gets the cursor of the following page, "" when none. */
typedef void (*store_asset_fn)(void *ctx, const struct store_asset *a);
bool store_asset_list(struct store *s, const char *after, int limit, bool dir_only,
                      store_asset_fn fn, void *ctx, char next[STORE_ASSET_NAME_CAP], char *err,
                      size_t errlen);

#endif
