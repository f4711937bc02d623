#define _POSIX_C_SOURCE 200809L
/* The record store: a statement built piece by piece, with its parameters
 * in order, for the lists and retention (store_db.h). */
#include "daemon/store/store_db.h"

#include <stdarg.h>
#include <stdio.h>

void sql_add(struct sql *q, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(q->text + q->len, sizeof(q->text) - q->len, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof(q->text) - q->len)
        q->overflow = true;
    else
        q->len += (size_t)n;
}

void sql_text(struct sql *q, const char *t)
{
    if (q->n < (int)(sizeof(q->params) / sizeof(q->params[0])))
        q->params[q->n].type = P_TEXT, q->params[q->n++].t = t;
    else
        q->overflow = true;
}

void sql_int(struct sql *q, int64_t i)
{
    if (q->n < (int)(sizeof(q->params) / sizeof(q->params[0])))
        q->params[q->n].type = P_INT, q->params[q->n++].i = i;
    else
        q->overflow = true;
}

void sql_double(struct sql *q, double d)
{
    if (q->n < (int)(sizeof(q->params) / sizeof(q->params[0])))
        q->params[q->n].type = P_DOUBLE, q->params[q->n++].d = d;
    else
        q->overflow = true;
}

void sql_bind(const struct sql *q, sqlite3_stmt *st)
{
    for (int i = 0; i < q->n; i++) {
        if (q->params[i].type == P_INT)
            sqlite3_bind_int64(st, i + 1, q->params[i].i);
        else if (q->params[i].type == P_DOUBLE)
            sqlite3_bind_double(st, i + 1, q->params[i].d);
        else
            sqlite3_bind_text(st, i + 1, q->params[i].t, -1, SQLITE_STATIC);
    }
}
