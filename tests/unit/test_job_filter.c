/* The lists' query arguments: filters, limit and cursor read into the
 * store's question, with rejections naming the argument and its rule. What
 * the question selects is tested on the store itself (test_store.c). */
#include <stdio.h>
#include <string.h>

#include "daemon/api/job_filter.h"
#include "tests/unit/check.h"

static void rejects_kind(enum store_kind kind, const char *key, const char *value,
                         const char *field)
{
    struct store_query q;
    struct job_error err;
    job_filter_init(&q, kind);
    bool ok = job_filter_add(&q, key, value, &err);
    CHECK(!ok && strcmp(err.field, field) == 0 && strlen(err.message) > 10);
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  %s=%s: got '%s' (%s)\n", key, value, err.field, err.message);
}

static void rejects(const char *key, const char *value, const char *field)
{
    rejects_kind(STORE_JOBS, key, value, field);
}

/* parse then format: the canonical form of a time. */
static bool time_is(const char *text, const char *want)
{
    int64_t ms;
    char t[32];
    if (!job_filter_parse_time(text, &ms))
        return false;
    job_filter_format_time(ms, t);
    if (strcmp(t, want) != 0)
        fprintf(stderr, "  %s: got %s, want %s\n", text, t, want);
    return strcmp(t, want) == 0;
}

int main(void)
{
    int64_t ms;
    CHECK(time_is("2026-11-21", "2026-11-21T00:00:00.000Z"));
    CHECK(time_is("2026-11-21T10:05", "2026-11-21T10:05:00.000Z"));
    CHECK(time_is("2026-11-21T10:05:07.5Z", "2026-11-21T10:05:07.500Z"));
    CHECK(time_is("0", "1970-01-01T00:00:00.000Z"));
    CHECK(time_is("1700000000", "2023-11-14T22:13:20.000Z"));
    CHECK(job_filter_parse_time("1700000000.25", &ms) && ms == 1700000000250);
    CHECK(!job_filter_parse_time("yesterday", &ms) && !job_filter_parse_time("2026-13-01", &ms) &&
          !job_filter_parse_time("2026-11-21T10", &ms) && !job_filter_parse_time("-5", &ms));

    rejects("techniqe", "forward", "techniqe");
    rejects("status", "finished", "status");
    rejects("since", "last week", "since");
    rejects("label.bad name", "x", "label.bad name");
    rejects("label.", "x", "label.");
    /* The page. */
    rejects("limit", "0", "limit");
    rejects("limit", "1001", "limit");
    rejects("limit", "ten", "limit");
    rejects("limit", "", "limit");
    rejects("limit", "5x", "limit");
    rejects("cursor", "../etc", "cursor");
    rejects("cursor", "", "cursor");
    rejects("cursor", "123456789012345678901234567", "cursor");
    /* Sweeps take the page only. */
    rejects_kind(STORE_SWEEPS, "technique", "forward", "technique");
    rejects_kind(STORE_SWEEPS, "limit", "0", "limit");

    struct store_query q;
    struct job_error err;
    job_filter_init(&q, STORE_JOBS);
    CHECK(q.kind == STORE_JOBS && q.limit == STORE_LIMIT_DEFAULT && q.nterms == 0 &&
          !q.after[0] && q.since_ms == 0);
    CHECK(job_filter_add(&q, "technique", "osl", &err));
    CHECK(job_filter_add(&q, "technique", "forward", &err)); /* alternatives */
    CHECK(job_filter_add(&q, "status", "done", &err));
    CHECK(job_filter_add(&q, "label.branch", "main", &err));
    CHECK(job_filter_add(&q, "since", "2026-11-22", &err));
    CHECK(job_filter_add(&q, "limit", "1000", &err));
    CHECK(job_filter_add(&q, "cursor", "20261122-101010-0003", &err));
    CHECK(q.nterms == 4 && q.terms[0].kind == STORE_TERM_TECHNIQUE &&
          !strcmp(q.terms[1].value, "forward") && q.terms[2].kind == STORE_TERM_STATUS &&
          q.terms[3].kind == STORE_TERM_LABEL && !strcmp(q.terms[3].label, "branch") &&
          !strcmp(q.terms[3].value, "main"));
    CHECK(q.limit == 1000 && !strcmp(q.after, "20261122-101010-0003"));
    char t[32];
    job_filter_format_time(q.since_ms, t);
    CHECK(!strcmp(t, "2026-11-22T00:00:00.000Z"));
    /* At most STORE_MAX_TERMS filters. */
    job_filter_init(&q, STORE_JOBS);
    bool all = true;
    for (int i = 0; i < STORE_MAX_TERMS; i++)
        all = all && job_filter_add(&q, "label.k", "v", &err);
    CHECK(all && !job_filter_add(&q, "label.k", "v", &err) && !strcmp(err.field, "label.k"));

    job_filter_init(&q, STORE_SWEEPS);
    CHECK(job_filter_add(&q, "limit", "2", &err) && job_filter_add(&q, "cursor", "1-2", &err) &&
          q.limit == 2 && !strcmp(q.after, "1-2"));
    return check_finish("test_job_filter");
}
