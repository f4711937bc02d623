#define _POSIX_C_SOURCE 200809L
/* The record store: lists (a page under filters, by the best index),
 * counts, the unfinished rows (store.h). */
#include "daemon/store/store_db.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

static bool same_group(const struct store_term *a, const struct store_term *b)
{
    return a->kind == b->kind && strcmp(a->label, b->label) == 0;
}

static bool first_of_group(const struct store_query *q, size_t i)
{
    for (size_t k = 0; k < i; k++)
        if (same_group(&q->terms[k], &q->terms[i]))
            return false;
    return true;
}

/* "(?, ?, ?)": the values of the group that starts at term i. */
static void add_values(struct sql *sql, const struct store_query *q, size_t i)
{
    sql_add(sql, "(");
    bool first = true;
    for (size_t k = i; k < q->nterms; k++)
        if (same_group(&q->terms[k], &q->terms[i])) {
            sql_add(sql, first ? "?" : ", ?");
            sql_text(sql, q->terms[k].value);
            first = false;
        }
    sql_add(sql, ")");
}

/* The lower bound on ids: the cursor, or what since allows. Ids are
 * stamped with the second of their submission before created is taken,
 * so a record created at or after since has an id at or after since's
 * stamp; an hour's margin keeps it true whatever happened between the two
 * clock reads. The bound only narrows the scan: created is still compared. */
static void id_bound(const struct store_query *q, char bound[RECORD_ID_LEN], bool *strict)
{
    bound[0] = '\0';
    *strict = false;
    char prefix[32] = "";
    if (q->since_ms > 0) {
        time_t t = (time_t)(q->since_ms / 1000) - 3600;
        struct tm tm;
        if (t > 0 && gmtime_r(&t, &tm))
            strftime(prefix, sizeof(prefix), "%Y%m%d-%H%M%S", &tm);
    }
    /* Newest first, the cursor is an upper bound (the caller adds it). */
    if (!q->newest && q->after[0] && strcmp(q->after, prefix) >= 0) {
        snprintf(bound, RECORD_ID_LEN, "%s", q->after);
        *strict = true;
    } else if (prefix[0]) {
        snprintf(bound, RECORD_ID_LEN, "%s", prefix);
    }
}

/* Of the label groups, the one with the fewest rows past the bound (counted
 * up to a cap, so that asking costs little) drives the query: its index
 * gives ids in order, and the others are checked per row. -1: no label. */
static int driving_label(sqlite3 *db, const struct store_query *q, const char *bound, bool strict)
{
    int best = -1;
    long best_count = 0;
    int groups = 0;
    for (size_t i = 0; i < q->nterms; i++)
        groups += q->terms[i].kind == STORE_TERM_LABEL && first_of_group(q, i);
    for (size_t i = 0; i < q->nterms; i++) {
        if (q->terms[i].kind != STORE_TERM_LABEL || !first_of_group(q, i))
            continue;
        if (groups == 1)
            return (int)i;
        struct sql sql = {.n = 0};
        sql_add(&sql, "SELECT count(*) FROM (SELECT 1 FROM labels WHERE kind = ? AND key = ? "
                      "AND value IN ");
        sql_int(&sql, q->kind);
        sql_text(&sql, q->terms[i].label);
        add_values(&sql, q, i);
        if (bound[0]) {
            sql_add(&sql, strict ? " AND id > ?" : " AND id >= ?");
            sql_text(&sql, bound);
        }
        sql_add(&sql, " LIMIT 5000)");
        sqlite3_stmt *st = NULL;
        long count = 5000;
        if (!sql.overflow && sqlite3_prepare_v2(db, sql.text, -1, &st, NULL) == SQLITE_OK) {
            sql_bind(&sql, st);
            if (sqlite3_step(st) == SQLITE_ROW)
                count = (long)sqlite3_column_int64(st, 0);
        }
        sqlite3_finalize(st);
        if (best < 0 || count < best_count) {
            best = (int)i;
            best_count = count;
        }
    }
    return best;
}

bool store_list(struct store *s, const struct store_query *q, store_row_fn fn, void *ctx,
                char next[RECORD_ID_LEN], char *err, size_t errlen)
{
    next[0] = '\0';
    int limit = q->limit > 0 && q->limit <= STORE_LIMIT_MAX ? q->limit : STORE_LIMIT_DEFAULT;
    sqlite3 *db = reader_take(s);
    if (!db) {
        snprintf(err, errlen, "cannot open %s to read", s->path);
        return false;
    }
    char bound[RECORD_ID_LEN];
    bool strict;
    id_bound(q, bound, &strict);
    int driver = driving_label(db, q, bound, strict);
    struct sql *sql = calloc(1, sizeof(*sql));
    bool ok = false;
    sqlite3_stmt *st = NULL;
    if (!sql) {
        snprintf(err, errlen, "out of memory");
        goto out;
    }
    const char *columns = "r.id, r.status, r.technique, r.created, r.started, r.finished, r.done,"
                          " r.total, r.error, r.dir, r.labels, r.figures, NULL, ";
    const char *extra = q->kind == STORE_SWEEPS ? "r.extra" : "NULL";
    /* r stands for the row, k for the table whose id the order follows. */
    const char *k = driver >= 0 ? "l" : "r";
    if (driver >= 0) {
        sql_add(sql, "SELECT %s%s FROM labels l CROSS JOIN records r ON r.kind = l.kind "
                     "AND r.id = l.id WHERE l.kind = ? AND l.key = ? AND l.value IN ",
                columns, extra);
        sql_int(sql, q->kind);
        sql_text(sql, q->terms[driver].label);
        add_values(sql, q, (size_t)driver);
    } else {
        sql_add(sql, "SELECT %s%s FROM records r WHERE r.kind = ?", columns, extra);
        sql_int(sql, q->kind);
    }
    if (bound[0]) {
        sql_add(sql, strict ? " AND %s.id > ?" : " AND %s.id >= ?", k);
        sql_text(sql, bound);
    }
    if (q->newest && q->after[0]) {
        sql_add(sql, " AND %s.id < ?", k);
        sql_text(sql, q->after);
    }
    for (size_t i = 0; i < q->nterms; i++) {
        if ((int)i == driver || !first_of_group(q, i))
            continue;
        const struct store_term *t = &q->terms[i];
        if (t->kind == STORE_TERM_LABEL) {
            sql_add(sql, " AND EXISTS (SELECT 1 FROM labels x WHERE x.kind = r.kind AND "
                         "x.id = r.id AND x.key = ? AND x.value IN ");
            sql_text(sql, t->label);
            add_values(sql, q, i);
            sql_add(sql, ")");
        } else {
            sql_add(sql, t->kind == STORE_TERM_TECHNIQUE ? " AND r.technique IN "
                                                         : " AND r.status IN ");
            add_values(sql, q, i);
        }
    }
    if (q->since_ms > 0) {
        sql_add(sql, " AND r.created >= ?");
        sql_double(sql, (double)q->since_ms / 1000.0);
    }
    sql_add(sql, q->newest ? " ORDER BY %s.id DESC LIMIT ?" : " ORDER BY %s.id LIMIT ?", k);
    sql_int(sql, limit + 1); /* one more tells whether a next page exists */
    if (sql->overflow) {
        snprintf(err, errlen, "the list's question is too long");
        goto out;
    }
    if (sqlite3_prepare_v2(db, sql->text, -1, &st, NULL) != SQLITE_OK) {
        db_error(s, db, "read", err, errlen);
        goto out;
    }
    sql_bind(sql, st);
    int rows = 0, rc;
    char last[RECORD_ID_LEN] = "";
    struct store_row row;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        if (rows == limit) {
            snprintf(next, RECORD_ID_LEN, "%s", last);
            break;
        }
        store_row_init(&row, q->kind);
        read_row(s, st, false, &row);
        row.labels = column_json(st, 10);
        row.figures = column_json(st, 11);
        row.extra = column_json(st, 13);
        snprintf(last, sizeof(last), "%s", row.id);
        fn(ctx, &row);
        store_row_finish(&row);
        rows++;
    }
    ok = rc == SQLITE_ROW || rc == SQLITE_DONE;
    if (!ok)
        db_error(s, db, "read", err, errlen);
out:
    if (!ok)
        LOG(LOG_ERROR, "store: list of %s: %s", KIND_DIRS[q->kind], err);
    sqlite3_finalize(st);
    free(sql);
    reader_give(s, db);
    return ok;
}

bool store_count(struct store *s, enum store_kind kind, size_t counts[JOB_STATUS_COUNT])
{
    memset(counts, 0, JOB_STATUS_COUNT * sizeof(counts[0]));
    sqlite3 *db = reader_take(s);
    if (!db)
        return false;
    sqlite3_stmt *st = NULL;
    int rc = SQLITE_ERROR;
    if (sqlite3_prepare_v2(db, "SELECT status, count(*) FROM records WHERE kind = ? GROUP BY status",
                           -1, &st, NULL) == SQLITE_OK) {
        sqlite3_bind_int(st, 1, kind);
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            enum job_status status;
            if (job_status_parse((const char *)sqlite3_column_text(st, 0), &status))
                counts[status] = (size_t)sqlite3_column_int64(st, 1);
        }
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    return rc == SQLITE_DONE;
}

bool store_each_unfinished(struct store *s, enum store_kind kind, store_row_fn fn, void *ctx)
{
    sqlite3 *db = reader_take(s);
    if (!db)
        return false;
    sqlite3_stmt *st = NULL;
    struct store_row *rows = NULL;
    size_t n = 0, cap = 0;
    int rc = SQLITE_ERROR;
    /* Read them all first: fn may write, which a store in memory (one
     * connection) cannot do while this read is open. */
    if (sqlite3_prepare_v2(db, "SELECT " ROW_COLUMNS ROW_JSON_COLUMNS " FROM records WHERE "
                           "kind = ? AND status IN ('queued', 'running') ORDER BY id",
                           -1, &st, NULL) == SQLITE_OK) {
        sqlite3_bind_int(st, 1, kind);
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            if (n == cap) {
                size_t grown = cap ? cap * 2 : 16;
                struct store_row *more = realloc(rows, grown * sizeof(*rows));
                if (!more) {
                    rc = SQLITE_NOMEM;
                    break;
                }
                rows = more;
                cap = grown;
            }
            store_row_init(&rows[n], kind);
            read_row(s, st, true, &rows[n]);
            n++;
        }
    }
    if (rc != SQLITE_DONE) {
        char err[PATH_MAX + 300];
        db_error(s, db, "read", err, sizeof(err));
        LOG(LOG_ERROR, "store: unfinished %s: %s", KIND_DIRS[kind], err);
    }
    sqlite3_finalize(st);
    reader_give(s, db);
    for (size_t i = 0; i < n; i++) {
        if (rc == SQLITE_DONE)
            fn(ctx, &rows[i]);
        store_row_finish(&rows[i]);
    }
    free(rows);
    return rc == SQLITE_DONE;
}
