#define _POSIX_C_SOURCE 200809L
/* The record store: retention's victims, removals and the removals a stop cut short (store.h). */
#include "daemon/store/store_db.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"

int store_retention_victims(struct store *s, enum store_kind kind, int keep, double keep_days,
                            double now, char (*ids)[RECORD_ID_LEN], int max)
{
    if ((keep <= 0 && keep_days <= 0) || max <= 0)
        return 0;
    struct sql sql = {.n = 0};
    /* Both rules read the index on (kind, finished) alone. */
    sql_add(&sql, "SELECT id, finished FROM (");
    if (keep > 0) {
        sql_add(&sql, "SELECT id, finished FROM (SELECT id, finished FROM records WHERE kind = ? "
                      "AND finished > 0 ORDER BY finished DESC, id DESC LIMIT -1 OFFSET ?)");
        sql_int(&sql, kind);
        sql_int(&sql, keep);
    }
    if (keep_days > 0) {
        sql_add(&sql, "%sSELECT id, finished FROM records WHERE kind = ? AND finished > 0 AND "
                      "finished < ?", keep > 0 ? " UNION " : "");
        sql_int(&sql, kind);
        sql_double(&sql, now - keep_days * 86400.0);
    }
    sql_add(&sql, ") ORDER BY finished, id LIMIT ?");
    sql_int(&sql, max);
    sqlite3 *db = reader_take(s);
    if (!db)
        return -1;
    sqlite3_stmt *st = NULL;
    int n = 0, rc = SQLITE_ERROR;
    if (sqlite3_prepare_v2(db, sql.text, -1, &st, NULL) == SQLITE_OK) {
        sql_bind(&sql, st);
        while (n < max && (rc = sqlite3_step(st)) == SQLITE_ROW)
            column_copy(st, 0, ids[n++], RECORD_ID_LEN);
        if (rc == SQLITE_ROW)
            rc = SQLITE_DONE;
    }
    if (rc != SQLITE_DONE) {
        char err[PATH_MAX + 300];
        db_error(s, db, "read", err, sizeof(err));
        LOG(LOG_ERROR, "store: retention of %s: %s", KIND_DIRS[kind], err);
        n = -1;
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    return n;
}

/* Under the write lock. */
static bool run_each(struct store *s, const char *sql, enum store_kind kind,
                     char (*ids)[RECORD_ID_LEN], int n)
{
    sqlite3_stmt *st = NULL;
    bool ok = sqlite3_prepare_v2(s->writer, sql, -1, &st, NULL) == SQLITE_OK;
    for (int i = 0; ok && i < n; i++) {
        sqlite3_bind_int(st, 1, kind);
        sqlite3_bind_text(st, 2, ids[i], -1, SQLITE_STATIC);
        ok = sqlite3_step(st) == SQLITE_DONE;
        sqlite3_reset(st);
    }
    sqlite3_finalize(st);
    return ok;
}

static bool clear_notes(struct store *s, enum store_kind kind, char (*ids)[RECORD_ID_LEN], int n)
{
    pthread_mutex_lock(&s->write_lock);
    bool ok = sqlite3_exec(s->writer, "BEGIN IMMEDIATE", NULL, NULL, NULL) == SQLITE_OK &&
              run_each(s, "DELETE FROM removals WHERE kind = ? AND id = ?", kind, ids, n) &&
              sqlite3_exec(s->writer, "COMMIT", NULL, NULL, NULL) == SQLITE_OK;
    if (!ok && !sqlite3_get_autocommit(s->writer))
        sqlite3_exec(s->writer, "ROLLBACK", NULL, NULL, NULL);
    pthread_mutex_unlock(&s->write_lock);
    return ok;
}

static void remove_dirs(struct store *s, enum store_kind kind, char (*ids)[RECORD_ID_LEN], int n)
{
    for (int i = 0; i < n && !s->memory; i++) {
        char dir[PATH_MAX + RECORD_ID_LEN + 2];
        snprintf(dir, sizeof(dir), "%s/%s", s->kinds[kind].root, ids[i]);
        if (access(dir, F_OK) == 0)
            record_remove_dir(dir);
    }
}

bool store_remove(struct store *s, enum store_kind kind, char (*ids)[RECORD_ID_LEN], int n)
{
    if (n <= 0)
        return true;
    pthread_mutex_lock(&s->write_lock);
    bool ok = sqlite3_exec(s->writer, "BEGIN IMMEDIATE", NULL, NULL, NULL) == SQLITE_OK &&
              run_each(s, "INSERT OR IGNORE INTO removals (kind, id) VALUES (?, ?)", kind, ids,
                       n) &&
              run_each(s, "DELETE FROM records WHERE kind = ? AND id = ?", kind, ids, n) &&
              run_each(s, "DELETE FROM labels WHERE kind = ? AND id = ?", kind, ids, n) &&
              sqlite3_exec(s->writer, "COMMIT", NULL, NULL, NULL) == SQLITE_OK;
    if (!ok) {
        char err[PATH_MAX + 300];
        db_error(s, s->writer, "write", err, sizeof(err));
        LOG(LOG_ERROR, "retention: %s; nothing removed", err);
        if (!sqlite3_get_autocommit(s->writer))
            sqlite3_exec(s->writer, "ROLLBACK", NULL, NULL, NULL);
    }
    pthread_mutex_unlock(&s->write_lock);
    if (!ok)
        return false;
    /* Files are removed with no lock held. */
    remove_dirs(s, kind, ids, n);
    return clear_notes(s, kind, ids, n);
}

/* store_open: removals a stop cut short between the rows and the files. */
void reap_noted(struct store *s)
{
    for (int kind = 0; kind < STORE_KINDS; kind++) {
        char(*ids)[RECORD_ID_LEN] = NULL;
        int n = 0, cap = 0;
        sqlite3 *db = reader_take(s);
        sqlite3_stmt *st = NULL;
        if (db && sqlite3_prepare_v2(db, "SELECT id FROM removals WHERE kind = ?", -1, &st, NULL) ==
                      SQLITE_OK) {
            sqlite3_bind_int(st, 1, kind);
            while (sqlite3_step(st) == SQLITE_ROW) {
                if (n == cap) {
                    int grown = cap ? cap * 2 : 64;
                    char(*more)[RECORD_ID_LEN] = realloc(ids, (size_t)grown * RECORD_ID_LEN);
                    if (!more)
                        break;
                    ids = more;
                    cap = grown;
                }
                column_copy(st, 0, ids[n++], RECORD_ID_LEN);
            }
        }
        sqlite3_finalize(st);
        if (db)
            reader_give(s, db);
        if (n) {
            LOG(LOG_INFO, "store: finishing the removal of %d %s", n, KIND_DIRS[kind]);
            remove_dirs(s, (enum store_kind)kind, ids, n);
            clear_notes(s, (enum store_kind)kind, ids, n);
        }
        free(ids);
    }
}
