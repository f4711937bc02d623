#define _POSIX_C_SOURCE 200809L
/* The record store: the assets table (store.h). */
#include "daemon/store/store_db.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

/* Assets (issue 21). Few rows, written rarely (an upload, a delete, a
 * start with --asset-dir): each write is a transaction of its own under the
 * write lock, and a full disk is the caller's 507 (an asset is not a state
 * that must be recorded; the reserve stays for jobs). */

void store_asset_finish(struct store_asset *a)
{
    json_decref(a->description);
    a->description = NULL;
}

bool store_asset_put(struct store *s, const struct store_asset *a, char *err, size_t errlen)
{
    static const char sql[] =
        "INSERT INTO assets (name, sha256, ext, size, created, updated, source, description)"
        " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8) ON CONFLICT (name) DO UPDATE SET"
        " sha256 = excluded.sha256, ext = excluded.ext, size = excluded.size,"
        " updated = excluded.updated, source = excluded.source,"
        " description = excluded.description";
    pthread_mutex_lock(&s->write_lock);
    sqlite3_stmt *st = NULL;
    bool ok = sqlite3_prepare_v2(s->writer, sql, -1, &st, NULL) == SQLITE_OK;
    if (ok) {
        sqlite3_bind_text(st, 1, a->name, -1, SQLITE_STATIC);
        sqlite3_bind_text(st, 2, a->sha256, -1, SQLITE_STATIC);
        sqlite3_bind_text(st, 3, a->ext, -1, SQLITE_STATIC);
        sqlite3_bind_int64(st, 4, (sqlite3_int64)a->size);
        sqlite3_bind_double(st, 5, a->created);
        sqlite3_bind_double(st, 6, a->updated);
        sqlite3_bind_text(st, 7, a->from_dir ? "dir" : "upload", -1, SQLITE_STATIC);
        bind_json(st, 8, a->description);
        ok = sqlite3_step(st) == SQLITE_DONE;
    }
    if (!ok)
        db_error(s, s->writer, "write", err, errlen);
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->write_lock);
    return ok;
}

#define ASSET_COLUMNS "name, sha256, ext, size, created, updated, source, description"

static void read_asset(sqlite3_stmt *st, struct store_asset *a)
{
    column_copy(st, 0, a->name, sizeof(a->name));
    column_copy(st, 1, a->sha256, sizeof(a->sha256));
    column_copy(st, 2, a->ext, sizeof(a->ext));
    a->size = (uint64_t)sqlite3_column_int64(st, 3);
    a->created = sqlite3_column_double(st, 4);
    a->updated = sqlite3_column_double(st, 5);
    const char *source = (const char *)sqlite3_column_text(st, 6);
    a->from_dir = source && strcmp(source, "dir") == 0;
    a->description = column_json(st, 7);
}

enum store_found store_asset_get(struct store *s, const char *name, struct store_asset *out)
{
    memset(out, 0, sizeof(*out));
    sqlite3 *db = reader_take(s);
    if (!db)
        return STORE_ERROR;
    sqlite3_stmt *st = NULL;
    enum store_found found = STORE_ERROR;
    if (sqlite3_prepare_v2(db, "SELECT " ASSET_COLUMNS " FROM assets WHERE name = ?", -1, &st,
                           NULL) == SQLITE_OK) {
        sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
        int rc = sqlite3_step(st);
        if (rc == SQLITE_ROW) {
            read_asset(st, out);
            found = STORE_FOUND;
        } else if (rc == SQLITE_DONE) {
            found = STORE_MISSING;
        }
    }
    if (found == STORE_ERROR) {
        char err[PATH_MAX + 300];
        db_error(s, db, "read", err, sizeof(err));
        LOG(LOG_ERROR, "store: asset %s: %s", name, err);
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    return found;
}

bool store_asset_delete(struct store *s, const char *name, char *err, size_t errlen)
{
    pthread_mutex_lock(&s->write_lock);
    sqlite3_stmt *st = NULL;
    bool ok = sqlite3_prepare_v2(s->writer, "DELETE FROM assets WHERE name = ?", -1, &st, NULL) ==
              SQLITE_OK;
    if (ok) {
        sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
        ok = sqlite3_step(st) == SQLITE_DONE;
    }
    if (!ok)
        db_error(s, s->writer, "write", err, errlen);
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->write_lock);
    return ok;
}

int store_asset_hash_refs(struct store *s, const char *sha256)
{
    sqlite3 *db = reader_take(s);
    if (!db)
        return -1;
    sqlite3_stmt *st = NULL;
    int n = -1;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM assets WHERE sha256 = ?", -1, &st, NULL) ==
        SQLITE_OK) {
        sqlite3_bind_text(st, 1, sha256, -1, SQLITE_STATIC);
        if (sqlite3_step(st) == SQLITE_ROW)
            n = sqlite3_column_int(st, 0);
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    return n;
}

bool store_asset_list(struct store *s, const char *after, int limit, bool dir_only,
                      store_asset_fn fn, void *ctx, char next[STORE_ASSET_NAME_CAP], char *err,
                      size_t errlen)
{
    next[0] = '\0';
    sqlite3 *db = reader_take(s);
    if (!db) {
        snprintf(err, errlen, "cannot open a read connection to the store (see the log)");
        return false;
    }
    sqlite3_stmt *st = NULL;
    bool ok = sqlite3_prepare_v2(db,
                                 dir_only ? "SELECT " ASSET_COLUMNS " FROM assets WHERE name > ?"
                                            " AND source = 'dir' ORDER BY name LIMIT ?"
                                          : "SELECT " ASSET_COLUMNS " FROM assets WHERE name > ?"
                                            " ORDER BY name LIMIT ?",
                                 -1, &st, NULL) == SQLITE_OK;
    if (ok) {
        sqlite3_bind_text(st, 1, after ? after : "", -1, SQLITE_STATIC);
        sqlite3_bind_int(st, 2, limit + 1); /* one more: is there a next page? */
        int n = 0, rc;
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            struct store_asset a;
            memset(&a, 0, sizeof(a));
            read_asset(st, &a);
            if (n++ == limit) {
                store_asset_finish(&a);
                break;
            }
            fn(ctx, &a);
            snprintf(next, STORE_ASSET_NAME_CAP, "%s", a.name);
            store_asset_finish(&a);
        }
        ok = rc == SQLITE_ROW || rc == SQLITE_DONE;
        if (ok && n <= limit)
            next[0] = '\0';
    }
    if (!ok)
        db_error(s, db, "read", err, errlen);
    sqlite3_finalize(st);
    reader_give(s, db);
    return ok;
}
