#define _POSIX_C_SOURCE 200809L
/* The record store: importing the legacy state directories (store.h). */
#include "daemon/store/store_db.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"

/* Rows per transaction when importing directories. */
#define STORE_BATCH 256

/* store_import's scan: which directories have rows, and the batch. */
struct import {
    struct store *s;
    enum store_kind kind;
    const char *legacy_file;
    store_import_fn fn;
    void *ctx;
    char (*known)[RECORD_ID_LEN];
    size_t nknown;
    struct store_row *batch;
    size_t nbatch;
    int imported;
    bool failed;
    char err[PATH_MAX + 300];
};

static int by_id(const void *a, const void *b) { return strcmp(a, b); }

static bool import_known(void *ctx, const char *id)
{
    struct import *im = ctx;
    return im->nknown && bsearch(id, im->known, im->nknown, RECORD_ID_LEN, by_id) != NULL;
}

/* Commits the batch, then removes the legacy state files it replaced. */
static void import_flush(struct import *im)
{
    struct store *s = im->s;
    if (!im->nbatch)
        return;
    pthread_mutex_lock(&s->write_lock);
    bool ok = sqlite3_exec(s->writer, "BEGIN IMMEDIATE", NULL, NULL, NULL) == SQLITE_OK;
    for (size_t i = 0; ok && i < im->nbatch; i++)
        ok = put_locked(s, &im->batch[i]);
    ok = ok && sqlite3_exec(s->writer, "COMMIT", NULL, NULL, NULL) == SQLITE_OK;
    if (!ok) {
        db_error(s, s->writer, "write", im->err, sizeof(im->err));
        if (!sqlite3_get_autocommit(s->writer))
            sqlite3_exec(s->writer, "ROLLBACK", NULL, NULL, NULL);
        im->failed = true;
    }
    pthread_mutex_unlock(&s->write_lock);
    for (size_t i = 0; i < im->nbatch; i++) {
        if (ok && im->legacy_file && !im->batch[i].dir_given) {
            char path[PATH_MAX + 64];
            snprintf(path, sizeof(path), "%s/%s", im->batch[i].dir, im->legacy_file);
            if (unlink(path) != 0 && errno != ENOENT)
                LOG(LOG_WARN, "store: cannot remove the imported %s: %s", path, strerror(errno));
        }
        store_row_finish(&im->batch[i]);
    }
    if (ok)
        im->imported += (int)im->nbatch;
    im->nbatch = 0;
}

static void import_one(void *ctx, const char *id, const char *dir)
{
    struct import *im = ctx;
    if (im->failed)
        return;
    struct store_row *row = &im->batch[im->nbatch];
    store_row_init(row, im->kind);
    snprintf(row->id, sizeof(row->id), "%s", id);
    snprintf(row->dir, sizeof(row->dir), "%s", dir);
    if (!im->fn(im->ctx, id, dir, row)) {
        store_row_finish(row);
        return;
    }
    /* The import names the record by its directory, whatever it set. */
    snprintf(row->id, sizeof(row->id), "%s", id);
    snprintf(row->dir, sizeof(row->dir), "%s", dir);
    row->dir_given = false;
    record_note_id(&im->s->kinds[im->kind], id);
    if (++im->nbatch == STORE_BATCH)
        import_flush(im);
}

int store_import(struct store *s, enum store_kind kind, const char *legacy_file,
                 store_import_fn import, void *ctx, char *err, size_t errlen)
{
    if (s->memory)
        return 0;
    struct import im = {.s = s, .kind = kind, .legacy_file = legacy_file, .fn = import, .ctx = ctx};
    im.batch = calloc(STORE_BATCH, sizeof(*im.batch));
    if (!im.batch) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    /* The ids with rows, sorted, so that each directory is looked up
     * without a query and a known one is never opened. */
    sqlite3 *db = reader_take(s);
    sqlite3_stmt *st = NULL;
    size_t cap = 0;
    int rc = SQLITE_ERROR;
    if (db && sqlite3_prepare_v2(db, "SELECT id FROM records WHERE kind = ? ORDER BY id", -1, &st,
                                 NULL) == SQLITE_OK) {
        sqlite3_bind_int(st, 1, kind);
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            if (im.nknown == cap) {
                size_t grown = cap ? cap * 2 : 1024;
                char(*more)[RECORD_ID_LEN] = realloc(im.known, grown * RECORD_ID_LEN);
                if (!more) {
                    rc = SQLITE_NOMEM;
                    break;
                }
                im.known = more;
                cap = grown;
            }
            column_copy(st, 0, im.known[im.nknown++], RECORD_ID_LEN);
        }
    }
    if (rc != SQLITE_DONE)
        db_error(s, db, "read", err, errlen);
    sqlite3_finalize(st);
    if (db)
        reader_give(s, db);
    int n = -1;
    if (rc == SQLITE_DONE) {
        /* SQLite's order is memcmp's, as strcmp's: bsearch agrees with it. */
        n = record_scan(&s->kinds[kind], import_known, import_one, &im, err, errlen);
        import_flush(&im);
        if (im.failed) {
            snprintf(err, errlen, "%s", im.err);
            n = -1;
        } else if (n >= 0) {
            n = im.imported;
        }
    }
    free(im.known);
    free(im.batch);
    return n;
}
