#define _DEFAULT_SOURCE /* timegm */
#include "daemon/api/job_filter.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "daemon/store/records.h"

void job_filter_init(struct store_query *q, enum store_kind kind)
{
    memset(q, 0, sizeof(*q));
    q->kind = kind;
    q->limit = STORE_LIMIT_DEFAULT;
}

void job_filter_format_time(int64_t ms, char out[32])
{
    time_t t = (time_t)(ms / 1000);
    struct tm tm;
    gmtime_r(&t, &tm);
    char buf[80];
    snprintf(buf, sizeof(buf), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
             tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, (int)(ms % 1000));
    snprintf(out, 32, "%.31s", buf);
}

bool job_filter_parse_time(const char *text, int64_t *out)
{
    char *end;
    double secs = strtod(text, &end);
    if (end != text && *end == '\0' && strchr(text, '-') == NULL) {
        if (!(secs >= 0 && secs < 1e11))
            return false;
        time_t t = (time_t)secs;
        *out = (int64_t)t * 1000 + (int)((secs - (double)t) * 1000) % 1000;
        return true;
    }
    int y, mo, d, h = 0, mi = 0, s = 0, ms = 0, n = 0;
    if (sscanf(text, "%4d-%2d-%2d%n", &y, &mo, &d, &n) != 3)
        return false;
    const char *p = text + n;
    if (*p == 'T' || *p == ' ') {
        int m = 0;
        if (sscanf(p + 1, "%2d:%2d%n", &h, &mi, &m) != 2)
            return false;
        p += 1 + m;
        if (*p == ':') {
            if (sscanf(p + 1, "%2d%n", &s, &m) != 1)
                return false;
            p += 1 + m;
            if (*p == '.') {
                int digits = 0;
                p++;
                while (isdigit((unsigned char)*p)) {
                    if (digits < 3)
                        ms = ms * 10 + (*p - '0');
                    digits++;
                    p++;
                }
                if (!digits)
                    return false;
                for (; digits < 3; digits++)
                    ms *= 10;
            }
        }
        if (*p == 'Z')
            p++;
    }
    if (*p || mo < 1 || mo > 12 || d < 1 || d > 31 || h < 0 || h > 23 || mi < 0 || mi > 59 ||
        s < 0 || s > 60)
        return false;
    if (y < 1970 || y > 9999)
        return false;
    struct tm tm = {.tm_year = y - 1900, .tm_mon = mo - 1, .tm_mday = d, .tm_hour = h,
                    .tm_min = mi, .tm_sec = s};
    *out = (int64_t)timegm(&tm) * 1000 + ms;
    return true;
}

static bool add_term(struct store_query *q, enum store_term_kind kind, const char *label,
                     const char *value, const char *key, struct job_error *err)
{
    if (q->nterms == STORE_MAX_TERMS)
        return job_error_set(err, key, "at most %d filters", STORE_MAX_TERMS);
    if (strlen(value) >= sizeof(q->terms[0].value))
        return job_error_set(err, key, "must be at most %zu bytes", sizeof(q->terms[0].value) - 1);
    struct store_term *t = &q->terms[q->nterms++];
    t->kind = kind;
    snprintf(t->label, sizeof(t->label), "%s", label ? label : "");
    snprintf(t->value, sizeof(t->value), "%s", value);
    return true;
}

/* The page: limit and cursor, which every list takes. */
static bool add_page(struct store_query *q, const char *key, const char *value, bool *taken,
                     struct job_error *err)
{
    *taken = true;
    if (!strcmp(key, "limit")) {
        char *end;
        long n = strtol(value, &end, 10);
        if (!*value || *end || n < 1 || n > STORE_LIMIT_MAX)
            return job_error_set(err, key, "must be an integer from 1 to %d", STORE_LIMIT_MAX);
        q->limit = (int)n;
        return true;
    }
    if (!strcmp(key, "cursor")) {
        /* Opaque to clients; an id to the store, checked as one. */
        if (!record_id_valid(value))
            return job_error_set(err, key, "must be the cursor of a next link, as given");
        snprintf(q->after, sizeof(q->after), "%s", value);
        return true;
    }
    if (!strcmp(key, "order")) {
        if (strcmp(value, "oldest") && strcmp(value, "newest"))
            return job_error_set(err, key, "must be oldest (the default) or newest");
        q->newest = !strcmp(value, "newest");
        return true;
    }
    *taken = false;
    return true;
}

bool job_filter_add(struct store_query *q, const char *key, const char *value,
                    struct job_error *err)
{
    value = value ? value : "";
    bool taken;
    bool ok = add_page(q, key, value, &taken, err);
    if (taken)
        return ok;
    if (q->kind != STORE_JOBS) {
        char field[64];
        snprintf(field, sizeof(field), "%s", key);
        return job_error_set(err, field, "unknown argument: the sweep list takes limit=, "
                             "cursor= and order=");
    }
    if (!strcmp(key, "technique"))
        return add_term(q, STORE_TERM_TECHNIQUE, NULL, value, key, err);
    if (!strcmp(key, "status")) {
        static const char *const names[] = {"queued", "running", "done", "failed",
                                            "cancelled", "interrupted", NULL};
        for (const char *const *n = names; *n; n++)
            if (!strcmp(*n, value))
                return add_term(q, STORE_TERM_STATUS, NULL, value, key, err);
        char list[160];
        jf_list_choices(names, list, sizeof(list));
        return job_error_set(err, key, "must be one of: %s", list);
    }
    if (!strcmp(key, "since")) {
        if (!job_filter_parse_time(value, &q->since_ms))
            return job_error_set(err, key, "must be a UTC time like 2026-11-21, "
                                 "2026-11-21T10:00:00Z, or seconds since 1970");
        return true;
    }
    if (!strncmp(key, "label.", 6)) {
        const char *name = key + 6;
        size_t len = strlen(name);
        bool ok = len >= 1 && len <= 32;
        for (size_t i = 0; ok && i < len; i++)
            ok = isalnum((unsigned char)name[i]) || name[i] == '_' || name[i] == '-' ||
                 name[i] == '.';
        if (!ok)
            return job_error_set(err, key, "label names are 1 to 32 characters of A-Z, a-z, "
                                 "0-9, '_', '-' and '.'");
        return add_term(q, STORE_TERM_LABEL, name, value, key, err);
    }
    char field[64];
    snprintf(field, sizeof(field), "%s", key);
    return job_error_set(err, field, "unknown filter: the job list takes technique=, status=, "
                         "label.NAME=, since=, limit=, cursor= and order=");
}
