#define _POSIX_C_SOURCE 200809L
#include "daemon/store/store.h"

#include <errno.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

#include "common/log.h"
#include "daemon/store/store_reserve.h"
#include "daemon/store/store_db.h"

/* Read connections open at once: more than the HTTP pool, the sweep thread
 * and the watcher ask at the same moment, each holding one for a page. */
#define STORE_READERS 8
/* 1: records, labels, removals. 2: assets (issue 21). */
#define STORE_SCHEMA_VERSION 2

/* The schema. Status is text, so that the database reads plainly in the
 * sqlite3 shell and in the tests. Rows are WITHOUT ROWID, keyed by (kind,
 * id): ids are time-ordered, so the key is also submission order, which is
 * the list's order and its cursor. finished is 0 until a record finishes,
 * so that retention reads the finished ones from its index alone. */
static const char SCHEMA[] =
    "CREATE TABLE IF NOT EXISTS records ("
    " kind INTEGER NOT NULL, id TEXT NOT NULL, status TEXT NOT NULL,"
    " technique TEXT NOT NULL, created REAL NOT NULL, started REAL NOT NULL,"
    " finished REAL NOT NULL, done INTEGER NOT NULL, total INTEGER NOT NULL,"
    " error TEXT, labels TEXT, figures TEXT, spec TEXT, extra TEXT, dir TEXT,"
    " PRIMARY KEY (kind, id)) WITHOUT ROWID;"
    "CREATE INDEX IF NOT EXISTS records_status ON records (kind, status, id);"
    "CREATE INDEX IF NOT EXISTS records_technique ON records (kind, technique, id);"
    "CREATE INDEX IF NOT EXISTS records_finished ON records (kind, finished);"
    "CREATE TABLE IF NOT EXISTS labels ("
    " kind INTEGER NOT NULL, id TEXT NOT NULL, key TEXT NOT NULL, value TEXT NOT NULL,"
    " PRIMARY KEY (kind, id, key)) WITHOUT ROWID;"
    "CREATE INDEX IF NOT EXISTS labels_value ON labels (kind, key, value, id);"
    /* Records whose rows are gone and whose directories may not be yet. */
    "CREATE TABLE IF NOT EXISTS removals ("
    " kind INTEGER NOT NULL, id TEXT NOT NULL, PRIMARY KEY (kind, id)) WITHOUT ROWID;";

/* The migrations, MIGRATIONS[v - 1] taking a store of schema v - 1 to v.
 * Schema 1 is written with IF NOT EXISTS and applied at every start (the
 * stores before user_version was kept); each later one runs once, in the
 * transaction that sets user_version, so a crash leaves the old schema whole.
 * A daemon older than a store's schema refuses to open it (open_writer). */
static const char MIGRATION_2[] =
    /* Assets by name (daemon/jobs/assets.h): the file's SHA-256 names its
     * files, STATE_DIR/assets/SHA256.{glb,gltf,sbasset}; several names may
     * share one. source is "upload" or "dir" (--asset-dir, read-only over
     * HTTP); description is the converter's JSON. */
    "CREATE TABLE IF NOT EXISTS assets ("
    " name TEXT NOT NULL PRIMARY KEY, sha256 TEXT NOT NULL, ext TEXT NOT NULL,"
    " size INTEGER NOT NULL, created REAL NOT NULL, updated REAL NOT NULL,"
    " source TEXT NOT NULL, description TEXT) WITHOUT ROWID;"
    "CREATE INDEX IF NOT EXISTS assets_sha256 ON assets (sha256);";
static const char *const MIGRATIONS[STORE_SCHEMA_VERSION] = {SCHEMA, MIGRATION_2};

static const char PUT_ROW[] =
    "INSERT INTO records (kind, id, status, technique, created, started, finished, done, total,"
    " error, labels, figures, spec, extra, dir)"
    " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15)"
    " ON CONFLICT (kind, id) DO UPDATE SET status = excluded.status,"
    " technique = excluded.technique, created = excluded.created, started = excluded.started,"
    " finished = excluded.finished, done = excluded.done, total = excluded.total,"
    " error = excluded.error, labels = excluded.labels, figures = excluded.figures,"
    " spec = excluded.spec, extra = excluded.extra, dir = excluded.dir";
static const char PUT_LABEL[] = "INSERT OR IGNORE INTO labels (kind, id, key, value) VALUES (?, ?, ?, ?)";

const char *const KIND_DIRS[STORE_KINDS] = {"jobs", "sweeps"};

const char *job_status_name(enum job_status s)
{
    static const char *const names[JOB_STATUS_COUNT] = {"queued", "running", "done",
                                                        "failed", "cancelled", "interrupted"};
    return (unsigned)s < JOB_STATUS_COUNT ? names[s] : "failed";
}

bool job_status_parse(const char *name, enum job_status *out)
{
    for (int s = 0; s < JOB_STATUS_COUNT; s++)
        if (name && strcmp(name, job_status_name((enum job_status)s)) == 0) {
            *out = (enum job_status)s;
            return true;
        }
    return false;
}

void store_row_init(struct store_row *r, enum store_kind kind)
{
    memset(r, 0, sizeof(*r));
    r->kind = kind;
}

void store_row_finish(struct store_row *r)
{
    json_decref(r->labels);
    json_decref(r->figures);
    json_decref(r->spec);
    json_decref(r->extra);
    r->labels = r->figures = r->spec = r->extra = NULL;
}

bool store_live_insert(struct store_live *l, void *item)
{
    if (l->count == l->cap) {
        size_t cap = l->cap ? l->cap * 2 : 16;
        void **items = realloc(l->items, cap * sizeof(*items));
        if (!items)
            return false;
        l->items = items;
        l->cap = cap;
    }
    /* New records have the newest ids: the end, almost always. */
    const char *id = item;
    size_t at = l->count;
    while (at > 0 && strcmp(l->items[at - 1], id) > 0)
        at--;
    memmove(l->items + at + 1, l->items + at, (l->count - at) * sizeof(*l->items));
    l->items[at] = item;
    l->count++;
    return true;
}

void *store_live_find(const struct store_live *l, const char *id)
{
    size_t lo = 0, hi = l->count;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        int c = strcmp(l->items[mid], id);
        if (c == 0)
            return l->items[mid];
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return NULL;
}

void store_live_remove(struct store_live *l, const void *item)
{
    for (size_t i = 0; i < l->count; i++)
        if (l->items[i] == item) {
            memmove(l->items + i, l->items + i + 1, (l->count - i - 1) * sizeof(*l->items));
            l->count--;
            return;
        }
}

void store_live_finish(struct store_live *l)
{
    free(l->items);
    memset(l, 0, sizeof(*l));
}

uint64_t store_version_take(struct store_version *v)
{
    v->pending++;
    return ++v->seq;
}

bool store_version_back(struct store_version *v, uint64_t seq, bool ok)
{
    v->pending--;
    if (ok && seq > v->saved)
        v->saved = seq;
    return store_version_stored(v);
}

const char *store_state_dir(const struct store *s) { return s->state_dir; }

struct record_kind *store_record_kind(struct store *s, enum store_kind kind)
{
    return &s->kinds[kind];
}

/* "cannot WHAT STATE_DIR/store.db: SQLite's message (the system's)". */
void db_error(const struct store *s, sqlite3 *db, const char *what, char *err,
              size_t errlen)
{
    int sys = db ? sqlite3_system_errno(db) : 0;
    snprintf(err, errlen, "cannot %s %s: %s%s%s%s", what,
             s->memory ? "the store in memory" : s->path, db ? sqlite3_errmsg(db) : "out of memory",
             sys ? " (" : "", sys ? strerror(sys) : "", sys ? ")" : "");
}

static bool exec(struct store *s, sqlite3 *db, const char *sql, char *err, size_t errlen)
{
    if (sqlite3_exec(db, sql, NULL, NULL, NULL) == SQLITE_OK)
        return true;
    db_error(s, db, "write", err, errlen);
    return false;
}

/* Is this error a database that cannot be read (rather than one that
 * cannot be reached: permissions, a full disk)? */
static bool damaged_code(int code)
{
    code &= 0xff;
    return code == SQLITE_NOTADB || code == SQLITE_CORRUPT;
}

static sqlite3 *open_connection(struct store *s, bool create, bool *damaged, char *err,
                                size_t errlen)
{
    sqlite3 *db = NULL;
    int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX | (create ? SQLITE_OPEN_CREATE : 0);
    int rc = sqlite3_open_v2(s->memory ? ":memory:" : s->path, &db, flags, NULL);
    if (damaged)
        *damaged = false;
    if (rc != SQLITE_OK) {
        db_error(s, db, "open", err, errlen);
        if (damaged)
            *damaged = damaged_code(sqlite3_extended_errcode(db));
        sqlite3_close_v2(db);
        return NULL;
    }
    /* A checkpoint can hold a reader back for a moment; never an error. */
    sqlite3_busy_timeout(db, 10000);
    sqlite3_extended_result_codes(db, 1);
    /* Every commit reaches the disk before it returns: kill -9 or a power
     * cut loses nothing a client was told is stored. */
    if (!exec(s, db, "PRAGMA synchronous = FULL", err, errlen)) {
        if (damaged)
            *damaged = damaged_code(sqlite3_extended_errcode(db));
        sqlite3_close_v2(db);
        return NULL;
    }
    return db;
}

/* The first question of a database that may be damaged: its answer, or
 * NULL with why. */
static char *pragma_text(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *st = NULL;
    char *out = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW) {
        const char *t = (const char *)sqlite3_column_text(st, 0);
        out = strdup(t ? t : "");
    }
    sqlite3_finalize(st);
    return out;
}

/* Opens the writer and readies the schema. *damaged tells a database that
 * cannot be read (moved to quarantine by the caller) from one that cannot
 * be opened at all (an error for the operator: permissions, a full disk). */
static bool open_writer(struct store *s, bool *damaged, char *err, size_t errlen)
{
    s->writer = open_connection(s, true, damaged, err, errlen);
    if (!s->writer)
        return false;
    char *mode = pragma_text(s->writer, s->memory ? "PRAGMA journal_mode = MEMORY"
                                                  : "PRAGMA journal_mode = WAL");
    if (!mode) {
        *damaged = damaged_code(sqlite3_extended_errcode(s->writer));
        db_error(s, s->writer, "read", err, errlen);
        return false;
    }
    bool wal = strcmp(mode, "wal") == 0 || s->memory;
    free(mode);
    if (!wal) {
        snprintf(err, errlen, "cannot put %s in write-ahead-log mode", s->path);
        return false;
    }
    char *version = pragma_text(s->writer, "PRAGMA user_version");
    int v = version ? atoi(version) : 0;
    free(version);
    if (v > STORE_SCHEMA_VERSION) {
        snprintf(err, errlen, "%s was written by a newer shadebenchd (schema %d; this one reads %d)",
                 s->path, v, STORE_SCHEMA_VERSION);
        return false;
    }
    if (!s->memory) {
        char *check = pragma_text(s->writer, "PRAGMA quick_check");
        if (!check || strcmp(check, "ok") != 0) {
            *damaged = true;
            if (check)
                snprintf(err, errlen, "%s fails its integrity check: %.300s", s->path, check);
            else
                db_error(s, s->writer, "check", err, errlen);
            free(check);
            return false;
        }
        free(check);
    }
    /* Schema 1 always (idempotent), then each migration the store lacks. */
    char sql[sizeof(SCHEMA) + sizeof(MIGRATION_2) + 64];
    int at = snprintf(sql, sizeof(sql), "BEGIN IMMEDIATE;%s", SCHEMA);
    for (int m = v < 1 ? 1 : v; m < STORE_SCHEMA_VERSION; m++)
        at += snprintf(sql + at, sizeof(sql) - (size_t)at, "%s", MIGRATIONS[m]);
    snprintf(sql + at, sizeof(sql) - (size_t)at, "PRAGMA user_version = %d;COMMIT",
             STORE_SCHEMA_VERSION);
    if (v < STORE_SCHEMA_VERSION && v > 0)
        LOG(LOG_INFO, "store: %s: schema %d to %d", s->path, v, STORE_SCHEMA_VERSION);
    /* Written only when it changes: a store opened as it is writes nothing
     * (a full disk's start, store_open). */
    if (v != STORE_SCHEMA_VERSION && !exec(s, s->writer, sql, err, errlen)) {
        *damaged = damaged_code(sqlite3_extended_errcode(s->writer));
        sqlite3_exec(s->writer, "ROLLBACK", NULL, NULL, NULL);
        return false;
    }
    if (sqlite3_prepare_v3(s->writer, PUT_ROW, -1, SQLITE_PREPARE_PERSISTENT, &s->put_row, NULL) !=
            SQLITE_OK ||
        sqlite3_prepare_v3(s->writer, PUT_LABEL, -1, SQLITE_PREPARE_PERSISTENT, &s->put_label,
                           NULL) != SQLITE_OK) {
        db_error(s, s->writer, "prepare statements on", err, errlen);
        return false;
    }
    return true;
}

static void close_writer(struct store *s)
{
    sqlite3_finalize(s->put_row);
    sqlite3_finalize(s->put_label);
    s->put_row = s->put_label = NULL;
    sqlite3_close_v2(s->writer);
    s->writer = NULL;
}

/* A damaged database goes to quarantine with its log, never deleted: the
 * rows come back from the directories (store_import). */
static void quarantine_database(struct store *s, const char *reason)
{
    struct record_kind k;
    record_kind_init(&k, s->state_dir, "store");
    static const char *const suffixes[] = {"", "-wal", "-shm"};
    for (int i = 0; i < 3; i++) {
        char path[PATH_MAX + 32], name[32];
        snprintf(path, sizeof(path), "%s%s", s->path, suffixes[i]);
        snprintf(name, sizeof(name), "%s%s", STORE_FILE, suffixes[i]);
        if (access(path, F_OK) == 0)
            record_quarantine(&k, name, path, reason, NULL, 0);
    }
}

/* Lends a read connection: the writer itself for a store in memory (held
 * under the write lock), else one of the pool, opened when none is idle. */
sqlite3 *reader_take(struct store *s)
{
    if (s->memory) {
        pthread_mutex_lock(&s->write_lock);
        return s->writer;
    }
    pthread_mutex_lock(&s->pool_lock);
    while (!s->idle && s->readers >= STORE_READERS)
        pthread_cond_wait(&s->pool_free, &s->pool_lock);
    struct reader *r = s->idle;
    if (r) {
        s->idle = r->next;
        pthread_mutex_unlock(&s->pool_lock);
        sqlite3 *db = r->db;
        free(r);
        return db;
    }
    s->readers++;
    pthread_mutex_unlock(&s->pool_lock);
    char err[PATH_MAX + 200];
    sqlite3 *db = open_connection(s, false, NULL, err, sizeof(err));
    if (!db) {
        LOG(LOG_ERROR, "store: %s", err);
        pthread_mutex_lock(&s->pool_lock);
        s->readers--;
        pthread_cond_signal(&s->pool_free);
        pthread_mutex_unlock(&s->pool_lock);
    }
    return db;
}

void reader_give(struct store *s, sqlite3 *db)
{
    if (s->memory) {
        pthread_mutex_unlock(&s->write_lock);
        return;
    }
    struct reader *r = malloc(sizeof(*r));
    pthread_mutex_lock(&s->pool_lock);
    if (r) {
        r->db = db;
        r->next = s->idle;
        s->idle = r;
    } else {
        sqlite3_close_v2(db);
        s->readers--;
    }
    pthread_cond_signal(&s->pool_free);
    pthread_mutex_unlock(&s->pool_lock);
}

static void note_last_ids(struct store *s)
{
    sqlite3 *db = reader_take(s);
    sqlite3_stmt *st = NULL;
    if (db && sqlite3_prepare_v2(db, "SELECT max(id) FROM records WHERE kind = ?", -1, &st, NULL) ==
                  SQLITE_OK) {
        for (int k = 0; k < STORE_KINDS; k++) {
            sqlite3_bind_int(st, 1, k);
            if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0))
                record_note_id(&s->kinds[k], (const char *)sqlite3_column_text(st, 0));
            sqlite3_reset(st);
        }
    }
    sqlite3_finalize(st);
    if (db)
        reader_give(s, db);
}

/* Less free space than the store's reserve holds: too little to open a
 * store, and what the reserve can give back is needed. */
static bool disk_nearly_full(const char *state_dir)
{
    struct statvfs vfs;
    return statvfs(state_dir, &vfs) == 0 &&
           (uint64_t)vfs.f_bavail * vfs.f_frsize < STORE_RESERVE_BYTES;
}

struct store *store_open(const char *state_dir, char *err, size_t errlen)
{
    struct store *s = calloc(1, sizeof(*s));
    if (!s) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    s->memory = !state_dir || !*state_dir;
    if (!s->memory) {
        snprintf(s->state_dir, sizeof(s->state_dir), "%s", state_dir);
        snprintf(s->path, sizeof(s->path), "%s/%s", s->state_dir, STORE_FILE);
    }
    for (int k = 0; k < STORE_KINDS; k++)
        record_kind_init(&s->kinds[k], s->state_dir, KIND_DIRS[k]);
    pthread_mutex_init(&s->write_lock, NULL);
    pthread_mutex_init(&s->pool_lock, NULL);
    pthread_cond_init(&s->pool_free, NULL);
    bool damaged;
    bool opened = open_writer(s, &damaged, err, errlen);
    if (!opened && !damaged && !s->memory && disk_nearly_full(s->state_dir)) {
        /* A disk another user filled while the daemon was down: the
         * reserve's room (store_reserve.h) is what lets the store open (its
         * log and shared memory take a little), so it is given back, and the
         * daemon starts as on a full disk: reads served, nothing new
         * accepted (507) until the room can be taken again, which
         * store_reserve_ready tries each second. */
        close_writer(s);
        s->reserve = store_reserve_open(s->state_dir);
        if (s->reserve && store_reserve_release(s->reserve)) {
            LOG(LOG_WARN, "store: %s; the disk of %s is full: the store's reserve is given "
                "back so that it opens; nothing is accepted until there is room again", err,
                s->state_dir);
            opened = open_writer(s, &damaged, err, errlen);
        }
    }
    if (!opened) {
        close_writer(s);
        if (!damaged)
            goto fail;
        /* Nothing is lost by starting afresh: the directories hold every
         * record's spec and results, and store_import rebuilds the rows. */
        LOG(LOG_ERROR, "store: %s; it goes to quarantine and the records are rebuilt from "
            "their directories", err);
        quarantine_database(s, err);
        if (!open_writer(s, &damaged, err, errlen)) {
            close_writer(s);
            goto fail;
        }
    }
    note_last_ids(s);
    reap_noted(s);
    if (!s->memory && !s->reserve)
        s->reserve = store_reserve_open(s->state_dir);
    return s;

fail:
    store_reserve_close(s->reserve);
    pthread_cond_destroy(&s->pool_free);
    pthread_mutex_destroy(&s->pool_lock);
    pthread_mutex_destroy(&s->write_lock);
    free(s);
    return NULL;
}

void store_close(struct store *s)
{
    if (!s)
        return;
    while (s->idle) {
        struct reader *r = s->idle;
        s->idle = r->next;
        sqlite3_close_v2(r->db);
        free(r);
    }
    close_writer(s);
    store_reserve_close(s->reserve);
    pthread_cond_destroy(&s->pool_free);
    pthread_mutex_destroy(&s->pool_lock);
    pthread_mutex_destroy(&s->write_lock);
    free(s);
}

/* SQLite frees the text once the statement is done with it. */
void bind_json(sqlite3_stmt *st, int i, const json_t *v)
{
    char *text = v ? json_dumps(v, JSON_COMPACT) : NULL;
    if (text)
        sqlite3_bind_text(st, i, text, -1, free);
    else
        sqlite3_bind_null(st, i);
}

/* Under the write lock, inside a transaction. */
bool put_locked(struct store *s, const struct store_row *r)
{
    sqlite3_stmt *st = s->put_row;
    sqlite3_bind_int(st, 1, r->kind);
    sqlite3_bind_text(st, 2, r->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 3, job_status_name(r->status), -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 4, r->technique, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 5, r->created);
    sqlite3_bind_double(st, 6, r->started);
    /* Retention reads finished > 0 as finished: a finished row always has
     * a time. */
    double finished = r->finished > 0 || !job_status_finished(r->status) ? r->finished
                      : r->created > 0                                    ? r->created
                                                                          : 1;
    sqlite3_bind_double(st, 7, job_status_finished(r->status) ? finished : 0);
    sqlite3_bind_int(st, 8, r->done);
    sqlite3_bind_int(st, 9, r->total);
    if (r->error[0])
        sqlite3_bind_text(st, 10, r->error, -1, SQLITE_STATIC);
    else
        sqlite3_bind_null(st, 10);
    bind_json(st, 11, r->labels);
    bind_json(st, 12, r->figures);
    bind_json(st, 13, r->spec);
    bind_json(st, 14, r->extra);
    if (!r->dir_given)
        sqlite3_bind_null(st, 15);
    else
        sqlite3_bind_text(st, 15, r->dir, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    sqlite3_reset(st);
    sqlite3_clear_bindings(st);
    if (rc != SQLITE_DONE)
        return false;
    const char *key;
    json_t *value;
    json_object_foreach(r->labels, key, value) {
        if (!json_is_string(value))
            continue;
        sqlite3_stmt *lb = s->put_label;
        sqlite3_bind_int(lb, 1, r->kind);
        sqlite3_bind_text(lb, 2, r->id, -1, SQLITE_STATIC);
        sqlite3_bind_text(lb, 3, key, -1, SQLITE_STATIC);
        sqlite3_bind_text(lb, 4, json_string_value(value), -1, SQLITE_STATIC);
        rc = sqlite3_step(lb);
        sqlite3_reset(lb);
        if (rc != SQLITE_DONE)
            return false;
    }
    return true;
}

/* Under the write lock: the row in a transaction of its own. On failure,
 * err says why and *full whether the disk had no room. */
static bool put_transaction(struct store *s, const struct store_row *r, bool *full, char *err,
                            size_t errlen)
{
    bool ok = sqlite3_exec(s->writer, "BEGIN IMMEDIATE", NULL, NULL, NULL) == SQLITE_OK &&
              put_locked(s, r) && sqlite3_exec(s->writer, "COMMIT", NULL, NULL, NULL) == SQLITE_OK;
    if (!ok) {
        int sys = sqlite3_system_errno(s->writer);
        *full = (sqlite3_extended_errcode(s->writer) & 0xff) == SQLITE_FULL || sys == ENOSPC ||
                sys == EDQUOT;
        db_error(s, s->writer, "write", err, errlen);
        if (!sqlite3_get_autocommit(s->writer))
            sqlite3_exec(s->writer, "ROLLBACK", NULL, NULL, NULL);
    }
    return ok;
}

bool store_put(struct store *s, const struct store_row *r, uint64_t seq, uint64_t *written,
               char *err, size_t errlen)
{
    bool ok = true, full = false;
    pthread_mutex_lock(&s->write_lock);
    /* A newer state got here first: this one is stale. */
    if (written && *written >= seq) {
        pthread_mutex_unlock(&s->write_lock);
        return true;
    }
    if (s->batch) {
        ok = put_locked(s, r);
        if (!ok)
            db_error(s, s->writer, "write", err, errlen);
        goto out;
    }
    ok = put_transaction(s, r, &full, err, errlen);
    if (!ok) {
        /* Noted in place first (store_reserve.h): should the retry fail
         * too, the next start still learns what this state was. */
        bool noted = store_reserve_note(s->reserve, (int)r->kind, r->id,
                                        job_status_name(r->status), r->error);
        if (full && store_reserve_release(s->reserve)) {
            LOG(LOG_ERROR, "store: the disk of %s is full: its reserve (%s, %d bytes) is "
                "released to store %s %s as %s; no job starts and none is accepted until there "
                "is room again", s->state_dir, STORE_RESERVE_FILE, STORE_RESERVE_BYTES,
                r->kind == STORE_JOBS ? "job" : "sweep", r->id, job_status_name(r->status));
            ok = put_transaction(s, r, &full, err, errlen);
        }
        if (ok && noted)
            store_reserve_unnote(s->reserve, (int)r->kind, r->id);
    } else {
        /* An older state of the record noted earlier is stale now. */
        store_reserve_unnote(s->reserve, (int)r->kind, r->id);
    }
out:
    if (ok && written)
        *written = seq;
    pthread_mutex_unlock(&s->write_lock);
    return ok;
}

bool store_has_room(struct store *s) { return store_reserve_ready(s->reserve); }

bool store_disk_full(struct store *s) { return store_reserve_released(s->reserve); }

bool store_unrecorded(struct store *s, enum store_kind kind, const char *id,
                      enum job_status *status, char *error, size_t cap)
{
    char name[32];
    return store_reserve_found(s->reserve, (int)kind, id, name, sizeof(name), error, cap) &&
           job_status_parse(name, status);
}

void store_unrecorded_done(struct store *s) { store_reserve_found_done(s->reserve); }

json_t *column_json(sqlite3_stmt *st, int col)
{
    const char *text = (const char *)sqlite3_column_text(st, col);
    return text ? json_loads(text, 0, NULL) : NULL;
}

void column_copy(sqlite3_stmt *st, int col, char *out, size_t cap)
{
    const char *text = (const char *)sqlite3_column_text(st, col);
    snprintf(out, cap, "%s", text ? text : "");
}

/* Reads ROW_COLUMNS (and, with json, ROW_JSON_COLUMNS) from the statement's
 * current row. */
void read_row(struct store *s, sqlite3_stmt *st, bool json, struct store_row *r)
{
    column_copy(st, 0, r->id, sizeof(r->id));
    const char *status = (const char *)sqlite3_column_text(st, 1);
    if (!job_status_parse(status, &r->status))
        r->status = JOB_FAILED;
    column_copy(st, 2, r->technique, sizeof(r->technique));
    r->created = sqlite3_column_double(st, 3);
    r->started = sqlite3_column_double(st, 4);
    r->finished = sqlite3_column_double(st, 5);
    r->done = sqlite3_column_int(st, 6);
    r->total = sqlite3_column_int(st, 7);
    column_copy(st, 8, r->error, sizeof(r->error));
    r->dir_given = sqlite3_column_type(st, 9) != SQLITE_NULL;
    if (r->dir_given)
        column_copy(st, 9, r->dir, sizeof(r->dir));
    else
        snprintf(r->dir, sizeof(r->dir), "%.*s/%s", (int)(sizeof(r->dir) - RECORD_ID_LEN - 2),
                 s->kinds[r->kind].root, r->id);
    if (json) {
        r->labels = column_json(st, 10);
        r->figures = column_json(st, 11);
        r->spec = column_json(st, 12);
        r->extra = column_json(st, 13);
    }
}

enum store_found store_get(struct store *s, enum store_kind kind, const char *id, bool full,
                           struct store_row *out)
{
    store_row_init(out, kind);
    sqlite3 *db = reader_take(s);
    if (!db)
        return STORE_ERROR;
    sqlite3_stmt *st = NULL;
    enum store_found found = STORE_ERROR;
    const char *sql = full ? "SELECT " ROW_COLUMNS ROW_JSON_COLUMNS
                             " FROM records WHERE kind = ? AND id = ?"
                           : "SELECT " ROW_COLUMNS " FROM records WHERE kind = ? AND id = ?";
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK) {
        sqlite3_bind_int(st, 1, kind);
        sqlite3_bind_text(st, 2, id, -1, SQLITE_STATIC);
        int rc = sqlite3_step(st);
        if (rc == SQLITE_ROW) {
            read_row(s, st, full, out);
            found = STORE_FOUND;
        } else if (rc == SQLITE_DONE) {
            found = STORE_MISSING;
        }
    }
    if (found == STORE_ERROR) {
        char err[PATH_MAX + 300];
        db_error(s, db, "read", err, sizeof(err));
        LOG(LOG_ERROR, "store: %s %s: %s", KIND_DIRS[kind], id, err);
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    return found;
}
