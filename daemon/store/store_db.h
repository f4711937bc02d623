#ifndef SHADEBENCH_STORE_DB_H
#define SHADEBENCH_STORE_DB_H

/* The record store's insides, shared by its files and by nothing outside
 * daemon/store/: store.c (the schema, the connections, a row's put and
 * get), store_query.c (lists, counts, the unfinished rows),
 * store_retention.c (retention and removals), store_import.c (the legacy
 * directories' import), store_assets.c (the assets table). Threads: as
 * store.h says of each public function. */

#include <limits.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdbool.h>

#include <jansson.h>

#include "daemon/store/store.h"

/* The columns every read takes, in this order; full reads add the JSON. */
#define ROW_COLUMNS "id, status, technique, created, started, finished, done, total, error, dir"
#define ROW_JSON_COLUMNS ", labels, figures, spec, extra"

struct reader {
    sqlite3 *db;
    struct reader *next;
};

struct store {
    char state_dir[PATH_MAX];
    char path[PATH_MAX + 16];
    bool memory; /* one connection, no file: --once */
    struct record_kind kinds[STORE_KINDS];
    /* The write connection and its statements; held across each commit. */
    pthread_mutex_t write_lock;
    sqlite3 *writer;
    sqlite3_stmt *put_row, *put_label;
    bool batch; /* store_import: puts join the open transaction */
    pthread_mutex_t pool_lock;
    pthread_cond_t pool_free;
    struct reader *idle;
    int readers; /* open, idle or lent */
    struct store_reserve *reserve; /* NULL in memory, or when it cannot be opened */
};

/* Each kind's folder under STATE_DIR ("jobs", "sweeps"). */
extern const char *const KIND_DIRS[STORE_KINDS];

/* store.c */
/* "cannot WHAT STATE_DIR/store.db: SQLite's message (the system's)". */
void db_error(const struct store *s, sqlite3 *db, const char *what, char *err, size_t errlen);
/* Lends a read connection (NULL when none can be opened), and takes it
 * back. */
sqlite3 *reader_take(struct store *s);
void reader_give(struct store *s, sqlite3 *db);
/* Reads ROW_COLUMNS (and, with json, ROW_JSON_COLUMNS) from the statement's
 * current row. */
void read_row(struct store *s, sqlite3_stmt *st, bool json, struct store_row *r);
json_t *column_json(sqlite3_stmt *st, int col);
void column_copy(sqlite3_stmt *st, int col, char *out, size_t cap);
/* Binds v's text (or NULL) to parameter i. */
void bind_json(sqlite3_stmt *st, int i, const json_t *v);
/* Under the write lock, inside a transaction: one row and its labels. */
bool put_locked(struct store *s, const struct store_row *r);

/* store_retention.c: at store_open, removals a stop cut short between the
 * rows and the files. */
void reap_noted(struct store *s);

/* A statement built piece by piece, with its parameters in order
 * (store_sql.c). */
struct sql {
    char text[12288];
    size_t len;
    bool overflow;
    int n;
    struct {
        enum { P_INT, P_DOUBLE, P_TEXT } type;
        int64_t i;
        double d;
        const char *t;
    } params[2 * STORE_MAX_TERMS + 16];
};
__attribute__((format(printf, 2, 3))) void sql_add(struct sql *q, const char *fmt, ...);
void sql_text(struct sql *q, const char *t);
void sql_int(struct sql *q, int64_t i);
void sql_double(struct sql *q, double d);
void sql_bind(const struct sql *q, sqlite3_stmt *st);

#endif
