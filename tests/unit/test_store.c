/* The record store: rows in and out, ordered writes, every filter and the
 * cursor against a reference, retention's choice and its removals, a child
 * killed mid-write losing nothing it was told was stored, a damaged
 * database rebuilt from the directories, directories imported, and a state
 * directory of the earlier version (job.json files) migrated by the job
 * queue. Runs in fresh temporary directories. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "common/fsutil.h"
#include "common/log.h"
#include "daemon/spec/job_figures.h"
#include "daemon/jobs/queue.h"
#include "daemon/store/store.h"
#include "daemon/store/store_reserve.h"
#include "tests/unit/catalog_fixture.h"
#include "tests/unit/check.h"

static bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static int count_entries(const char *dir, const char *containing)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (e->d_name[0] != '.' && (!containing || strstr(e->d_name, containing)))
            n++;
    if (d)
        closedir(d);
    return n;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

static char *make_state(void)
{
    char tmpl[] = "/tmp/test-store-XXXXXX";
    char *dir = mkdtemp(tmpl);
    return dir ? strdup(dir) : NULL;
}

static void remove_state(char *state)
{
    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", state);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", state);
    free(state);
}

/* The synthetic jobs: i decides everything, so that the reference answer
 * of each question is computed the same way. */
#define NJOBS 60
static const char *const TECHS[] = {"forward", "osl", "unlit"};
static const char *tech_of(int i) { return TECHS[i % 3]; }
static enum job_status status_of(int i) { return i % 10 == 9 ? JOB_FAILED : JOB_DONE; }
static const char *commit_of(int i) { return i % 4 == 0 ? "aaa" : i % 4 == 1 ? "bbb" : "ccc"; }
static const char *branch_of(int i) { return i < 30 ? "main" : "topic"; }
static double created_of(int i) { return 1.8e9 + 100.0 * i; }

static void id_of(int i, char id[RECORD_ID_LEN])
{
    /* Time-ordered as the daemon's: the stamp of created, then a serial. */
    time_t t = (time_t)created_of(i);
    struct tm tm;
    gmtime_r(&t, &tm);
    char stamp[20];
    strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &tm);
    snprintf(id, RECORD_ID_LEN, "%.15s-%04d", stamp, i % 10000);
}

static void fill_row(int i, struct store_row *r)
{
    store_row_init(r, STORE_JOBS);
    id_of(i, r->id);
    r->status = status_of(i);
    snprintf(r->technique, sizeof(r->technique), "%s", tech_of(i));
    r->created = created_of(i);
    r->started = r->created + 1;
    r->finished = r->created + 2 + i % 7; /* not in id order: retention reads finish times */
    r->done = r->total = 10;
    if (r->status == JOB_FAILED)
        snprintf(r->error, sizeof(r->error), "failed on purpose %d", i);
    r->labels = json_pack("{s:s, s:s}", "commit", commit_of(i), "branch", branch_of(i));
    r->figures = json_pack("{s:{s:f}}", "frame_ms", "median", 10.0 + i);
    r->spec = json_pack("{s:s, s:i}", "technique", tech_of(i), "frames", 10);
}

/* A question's answer, walked page by page: the ids in order, each page at
 * most limit long, as a client following next sees them. */
struct walk {
    char ids[NJOBS * 2][RECORD_ID_LEN];
    int n;
    bool figures_ok, labels_ok;
};

static void collect(void *ctx, const struct store_row *row)
{
    struct walk *w = ctx;
    if (w->n < NJOBS * 2)
        snprintf(w->ids[w->n++], RECORD_ID_LEN, "%s", row->id);
    w->labels_ok = w->labels_ok && json_is_string(json_object_get(row->labels, "commit"));
    w->figures_ok = w->figures_ok && json_object_get(row->figures, "frame_ms") && !row->spec;
}

static int walk_all(struct store *s, struct store_query *q, struct walk *w, int *pages)
{
    w->n = 0;
    w->figures_ok = w->labels_ok = true;
    *pages = 0;
    char next[RECORD_ID_LEN], err[512];
    q->after[0] = '\0';
    for (;;) {
        int before = w->n;
        if (!store_list(s, q, collect, w, next, err, sizeof(err)))
            return -1;
        (*pages)++;
        if (w->n - before > q->limit)
            return -1;
        if (!next[0] || *pages > 200)
            break;
        snprintf(q->after, sizeof(q->after), "%s", next);
    }
    return w->n;
}

typedef bool (*pred_fn)(int i);

/* Does walking q (in pages of limit) give exactly the jobs pred selects, in
 * id order, each once? */
static bool answers(struct store *s, struct store_query *q, pred_fn pred, int limit)
{
    struct walk *w = calloc(1, sizeof(*w));
    int pages;
    q->limit = limit;
    int n = walk_all(s, q, w, &pages);
    bool ok = n >= 0 && w->figures_ok && w->labels_ok;
    int k = 0;
    for (int i = 0; ok && i < NJOBS; i++) {
        if (!pred(i))
            continue;
        char id[RECORD_ID_LEN];
        id_of(i, id);
        ok = k < n && strcmp(w->ids[k], id) == 0;
        k++;
    }
    /* The last page has no next link: exactly ceil(n / limit) pages (one,
     * empty, when nothing matches). */
    ok = ok && k == n && pages == (n == 0 ? 1 : (n + limit - 1) / limit);
    if (!ok)
        fprintf(stderr, "  walk: %d rows in %d pages, want %d\n", n, pages, k);
    free(w);
    return ok;
}

static void add_term(struct store_query *q, enum store_term_kind kind, const char *label,
                     const char *value)
{
    struct store_term *t = &q->terms[q->nterms++];
    t->kind = kind;
    snprintf(t->label, sizeof(t->label), "%s", label ? label : "");
    snprintf(t->value, sizeof(t->value), "%s", value);
}

static bool p_all(int i) { (void)i; return true; }
static bool p_osl(int i) { return !strcmp(tech_of(i), "osl"); }
static bool p_osl_or_unlit(int i) { return strcmp(tech_of(i), "forward") != 0; }
static bool p_failed(int i) { return status_of(i) == JOB_FAILED; }
static bool p_commit_aaa(int i) { return !strcmp(commit_of(i), "aaa"); }
static bool p_aaa_or_bbb(int i) { return strcmp(commit_of(i), "ccc") != 0; }
static bool p_aaa_topic(int i) { return p_commit_aaa(i) && !strcmp(branch_of(i), "topic"); }
static bool p_aaa_topic_osl(int i) { return p_aaa_topic(i) && p_osl(i); }
static bool p_since_45(int i) { return i >= 45; }
static bool p_since_45_done_unlit(int i) { return i >= 45 && !p_failed(i) && !strcmp(tech_of(i), "unlit"); }
static bool p_none(int i) { (void)i; return false; }

static void test_rows_and_lists(void)
{
    char *state = make_state();
    char err[PATH_MAX + 300];
    struct store *s = store_open(state, err, sizeof(err));
    CHECK(s != NULL);
    if (!s) {
        fprintf(stderr, "  %s\n", err);
        return;
    }
    char db[PATH_MAX + 32];
    snprintf(db, sizeof(db), "%s/%s", state, STORE_FILE);
    CHECK(exists(db));
    /* Inserted out of order: the list's order is the ids'. */
    for (int k = 0; k < NJOBS; k++) {
        int i = (k * 37) % NJOBS;
        struct store_row r;
        fill_row(i, &r);
        CHECK(store_put(s, &r, 0, NULL, err, sizeof(err)));
        store_row_finish(&r);
    }
    struct store_row got;
    char id7[RECORD_ID_LEN];
    id_of(7, id7);
    CHECK(store_get(s, STORE_JOBS, id7, true, &got) == STORE_FOUND);
    CHECK(!strcmp(got.technique, "osl") && got.status == JOB_DONE && got.created == created_of(7) &&
          got.done == 10 && !strcmp(json_string_value(json_object_get(got.labels, "commit")), "ccc") &&
          json_object_get(got.figures, "frame_ms") && got.spec && !got.dir_given);
    char want_dir[PATH_MAX + 64];
    snprintf(want_dir, sizeof(want_dir), "%s/jobs/%s", state, id7);
    CHECK(!strcmp(got.dir, want_dir));
    store_row_finish(&got);
    CHECK(store_get(s, STORE_JOBS, id7, false, &got) == STORE_FOUND && !got.spec && !got.labels);
    store_row_finish(&got);
    CHECK(store_get(s, STORE_SWEEPS, id7, false, &got) == STORE_MISSING);
    store_row_finish(&got);
    CHECK(store_get(s, STORE_JOBS, "19990101-000000-0001", true, &got) == STORE_MISSING);
    store_row_finish(&got);

    /* Ordered writes: a stale state arriving late never replaces a newer. */
    struct store_row r;
    fill_row(3, &r);
    uint64_t written = 0;
    r.status = JOB_CANCELLED;
    CHECK(store_put(s, &r, 2, &written, err, sizeof(err)) && written == 2);
    r.status = JOB_RUNNING;
    CHECK(store_put(s, &r, 1, &written, err, sizeof(err)) && written == 2);
    store_row_finish(&r);
    char id3[RECORD_ID_LEN];
    id_of(3, id3);
    CHECK(store_get(s, STORE_JOBS, id3, false, &got) == STORE_FOUND && got.status == JOB_CANCELLED);
    store_row_finish(&got);
    fill_row(3, &r); /* back as it was */
    CHECK(store_put(s, &r, 3, &written, err, sizeof(err)));
    store_row_finish(&r);

    size_t counts[JOB_STATUS_COUNT];
    CHECK(store_count(s, STORE_JOBS, counts) && counts[JOB_DONE] == 54 && counts[JOB_FAILED] == 6 &&
          counts[JOB_QUEUED] == 0);

    /* Every question, walked in pages of several sizes. */
    struct store_query q = {.kind = STORE_JOBS};
    CHECK(answers(s, &q, p_all, 100));
    CHECK(answers(s, &q, p_all, 7));
    CHECK(answers(s, &q, p_all, 1));
    CHECK(answers(s, &q, p_all, 60)); /* exactly one page: no next */
    add_term(&q, STORE_TERM_TECHNIQUE, NULL, "osl");
    CHECK(answers(s, &q, p_osl, 4));
    add_term(&q, STORE_TERM_TECHNIQUE, NULL, "unlit"); /* alternatives */
    CHECK(answers(s, &q, p_osl_or_unlit, 9));
    q.nterms = 0;
    add_term(&q, STORE_TERM_STATUS, NULL, "failed");
    CHECK(answers(s, &q, p_failed, 2));
    q.nterms = 0;
    add_term(&q, STORE_TERM_LABEL, "commit", "aaa");
    CHECK(answers(s, &q, p_commit_aaa, 5));
    add_term(&q, STORE_TERM_LABEL, "commit", "bbb");
    CHECK(answers(s, &q, p_aaa_or_bbb, 11));
    q.nterms = 0;
    add_term(&q, STORE_TERM_LABEL, "branch", "topic"); /* two label groups, either drives */
    add_term(&q, STORE_TERM_LABEL, "commit", "aaa");
    CHECK(answers(s, &q, p_aaa_topic, 2));
    add_term(&q, STORE_TERM_TECHNIQUE, NULL, "osl");
    CHECK(answers(s, &q, p_aaa_topic_osl, 1));
    q.nterms = 0;
    add_term(&q, STORE_TERM_LABEL, "commit", "nobody");
    CHECK(answers(s, &q, p_none, 10));
    q.nterms = 0;
    q.since_ms = (int64_t)created_of(45) * 1000;
    CHECK(answers(s, &q, p_since_45, 4));
    add_term(&q, STORE_TERM_STATUS, NULL, "done");
    add_term(&q, STORE_TERM_TECHNIQUE, NULL, "unlit");
    CHECK(answers(s, &q, p_since_45_done_unlit, 1));
    q.nterms = 0;
    q.since_ms = (int64_t)(created_of(NJOBS) + 1e6) * 1000;
    CHECK(answers(s, &q, p_none, 10));
    q.since_ms = 0;

    /* The cursor is a position, stable under inserts: a page taken, a job
     * inserted (a later id), the next page goes on where the first ended
     * and ends with the new job. */
    q.limit = 50;
    q.after[0] = '\0';
    struct walk *w = calloc(1, sizeof(*w));
    char next[RECORD_ID_LEN];
    w->figures_ok = w->labels_ok = true;
    CHECK(store_list(s, &q, collect, w, next, err, sizeof(err)) && w->n == 50 && next[0]);
    fill_row(NJOBS, &r);
    CHECK(store_put(s, &r, 0, NULL, err, sizeof(err)));
    store_row_finish(&r);
    snprintf(q.after, sizeof(q.after), "%s", next);
    CHECK(store_list(s, &q, collect, w, next, err, sizeof(err)) && w->n == NJOBS + 1 && !next[0]);
    char last[RECORD_ID_LEN], id49[RECORD_ID_LEN], id50[RECORD_ID_LEN];
    id_of(NJOBS, last);
    id_of(49, id49);
    id_of(50, id50);
    CHECK(!strcmp(w->ids[NJOBS], last) && !strcmp(w->ids[49], id49) && !strcmp(w->ids[50], id50));
    free(w);

    /* Retention: the earliest finished beyond keep; finish times 2..8 s
     * after creation at 100 s steps keep the order of the ids. */
    char ids[64][RECORD_ID_LEN];
    int n = store_retention_victims(s, STORE_JOBS, NJOBS + 1 - 5, 0, 0, ids, 64);
    CHECK(n == 5);
    for (int i = 0; i < n && i < 5; i++) {
        char id[RECORD_ID_LEN];
        id_of(i, id);
        CHECK(!strcmp(ids[i], id));
    }
    CHECK(store_retention_victims(s, STORE_JOBS, NJOBS + 1 - 5, 0, 0, ids, 2) == 2);
    CHECK(store_retention_victims(s, STORE_JOBS, 0, 0, 0, ids, 64) == 0);
    /* keep_days: those finished before now - 1 day. */
    double now = created_of(10) + 86400.0;
    n = store_retention_victims(s, STORE_JOBS, 0, 1, now, ids, 64);
    CHECK(n == 10);
    /* Both: the union, earliest first. */
    n = store_retention_victims(s, STORE_JOBS, NJOBS + 1 - 3, 1, now, ids, 64);
    CHECK(n == 10);
    /* A queued row is never a victim: it has not finished. */
    fill_row(0, &r);
    r.status = JOB_QUEUED;
    CHECK(store_put(s, &r, 0, NULL, err, sizeof(err)));
    store_row_finish(&r);
    n = store_retention_victims(s, STORE_JOBS, 1, 0, 0, ids, 64);
    char id0[RECORD_ID_LEN];
    id_of(0, id0);
    bool has0 = false;
    for (int i = 0; i < n; i++)
        has0 = has0 || !strcmp(ids[i], id0);
    CHECK(n == NJOBS - 1 && !has0);

    /* Removal: rows, labels and directories. */
    char dir1[PATH_MAX + 64], id1[RECORD_ID_LEN];
    id_of(1, id1);
    snprintf(dir1, sizeof(dir1), "%s/jobs/%s", state, id1);
    CHECK(fs_mkdir_p(dir1));
    char file1[PATH_MAX + 80];
    snprintf(file1, sizeof(file1), "%s/result.json", dir1);
    write_text(file1, "{}");
    snprintf(ids[0], RECORD_ID_LEN, "%s", id1);
    snprintf(ids[1], RECORD_ID_LEN, "%s", id3);
    CHECK(store_remove(s, STORE_JOBS, ids, 2));
    CHECK(!exists(dir1));
    CHECK(store_get(s, STORE_JOBS, id1, false, &got) == STORE_MISSING);
    store_row_finish(&got);
    q.nterms = 0;
    add_term(&q, STORE_TERM_LABEL, "commit", "bbb"); /* job 1's commit: its label is gone */
    q.after[0] = '\0';
    q.limit = 100;
    w = calloc(1, sizeof(*w));
    w->figures_ok = w->labels_ok = true;
    CHECK(store_list(s, &q, collect, w, next, err, sizeof(err)) && w->n == 14 &&
          strcmp(w->ids[0], id1) != 0);
    free(w);
    store_close(s);

    /* A removal cut short (rows gone, directory not yet) is finished by the
     * next open. */
    snprintf(dir1, sizeof(dir1), "%s/jobs/%s", state, id3);
    CHECK(fs_mkdir_p(dir1));
    sqlite3 *raw;
    CHECK(sqlite3_open(db, &raw) == SQLITE_OK);
    char sql[200];
    snprintf(sql, sizeof(sql), "INSERT INTO removals (kind, id) VALUES (0, '%s')", id3);
    CHECK(sqlite3_exec(raw, sql, NULL, NULL, NULL) == SQLITE_OK);
    sqlite3_close(raw);
    s = store_open(state, err, sizeof(err));
    CHECK(s && !exists(dir1));
    store_close(s);
    remove_state(state);
}

/* A child stores rows and says so on a pipe after each store_put returns;
 * the parent kills it with SIGKILL mid-way. Every row the child was told
 * was stored must be there after reopening. */
static void test_kill_loses_nothing(void)
{
    char *state = make_state();
    char err[PATH_MAX + 300];
    int fds[2];
    CHECK(pipe(fds) == 0);
    pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        struct store *s = store_open(state, err, sizeof(err));
        if (!s)
            _exit(2);
        for (int i = 0; i < 100000; i++) {
            struct store_row r;
            fill_row(i % NJOBS, &r);
            snprintf(r.id, sizeof(r.id), "20300101-%06d-%04d", i / 10000, i % 10000);
            r.status = i % 2 ? JOB_QUEUED : JOB_DONE;
            bool ok = store_put(s, &r, 0, NULL, err, sizeof(err));
            store_row_finish(&r);
            if (!ok || write(fds[1], &i, sizeof(i)) != sizeof(i))
                _exit(3);
        }
        _exit(0);
    }
    close(fds[1]);
    int acked = -1, i;
    while (acked < 40 && read(fds[0], &i, sizeof(i)) == sizeof(i))
        acked = i;
    kill(pid, SIGKILL);
    int status;
    waitpid(pid, &status, 0);
    /* What it said after the kill was sent may still be in the pipe. */
    while (read(fds[0], &i, sizeof(i)) == sizeof(i))
        acked = i;
    close(fds[0]);
    CHECK(WIFSIGNALED(status) && acked >= 40);
    struct store *s = store_open(state, err, sizeof(err));
    CHECK(s != NULL);
    int missing = 0;
    for (int k = 0; s && k <= acked; k++) {
        char id[RECORD_ID_LEN];
        snprintf(id, sizeof(id), "20300101-%06d-%04d", k / 10000, k % 10000);
        struct store_row got;
        if (store_get(s, STORE_JOBS, id, true, &got) != STORE_FOUND ||
            got.status != (k % 2 ? JOB_QUEUED : JOB_DONE) || !got.labels)
            missing++;
        store_row_finish(&got);
    }
    CHECK(missing == 0);
    if (missing)
        fprintf(stderr, "  %d of %d acknowledged rows lost\n", missing, acked + 1);
    store_close(s);
    remove_state(state);
}

/* store_import's test double: a directory with a "state" file becomes a
 * done job; one with "bad" is refused (as a damaged record would be). */
struct imported {
    int calls;
    char ids[8][RECORD_ID_LEN];
};

static bool import_fake(void *ctx, const char *id, const char *dir, struct store_row *row)
{
    struct imported *im = ctx;
    if (im->calls < 8)
        snprintf(im->ids[im->calls], RECORD_ID_LEN, "%s", id);
    im->calls++;
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/bad", dir);
    if (exists(path))
        return false;
    row->status = JOB_DONE;
    snprintf(row->technique, sizeof(row->technique), "forward");
    row->created = row->finished = 1.9e9;
    row->spec = json_object();
    return true;
}

static void test_import_and_damage(void)
{
    char *state = make_state();
    char err[PATH_MAX + 300], path[PATH_MAX + 64];
    struct store *s = store_open(state, err, sizeof(err));
    CHECK(s != NULL);
    if (!s)
        return;
    struct store_row r;
    fill_row(1, &r);
    CHECK(store_put(s, &r, 0, NULL, err, sizeof(err)));
    store_row_finish(&r);
    char known[RECORD_ID_LEN];
    id_of(1, known);
    const char *fresh[] = {"20300101-000000-0001", "20300101-000000-0002", "20300101-000000-0003"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof(path), "%s/jobs/%s", state, fresh[i]);
        CHECK(fs_mkdir_p(path));
        snprintf(path, sizeof(path), "%s/jobs/%s/job.json", state, fresh[i]);
        write_text(path, "{}");
        snprintf(path, sizeof(path), "%s/jobs/%s/result.json.tmp", state, fresh[i]);
        write_text(path, "half");
    }
    snprintf(path, sizeof(path), "%s/jobs/%s/bad", state, fresh[2]);
    write_text(path, "");
    snprintf(path, sizeof(path), "%s/jobs/%s", state, known);
    CHECK(fs_mkdir_p(path));
    snprintf(path, sizeof(path), "%s/jobs/not-a-record", state);
    write_text(path, "?");
    struct imported im = {0};
    int n = store_import(s, STORE_JOBS, "job.json", import_fake, &im, err, sizeof(err));
    CHECK(n == 2 && im.calls == 3 && !strcmp(im.ids[0], fresh[0]) && !strcmp(im.ids[2], fresh[2]));
    for (int i = 0; i < 3; i++) {
        struct store_row got;
        CHECK(store_get(s, STORE_JOBS, fresh[i], false, &got) == (i < 2 ? STORE_FOUND : STORE_MISSING));
        store_row_finish(&got);
        /* The legacy state file goes once its row is committed; *.tmp always. */
        snprintf(path, sizeof(path), "%s/jobs/%s/job.json", state, fresh[i]);
        CHECK(exists(path) == (i == 2));
        snprintf(path, sizeof(path), "%s/jobs/%s/result.json.tmp", state, fresh[i]);
        CHECK(!exists(path));
    }
    char qdir[PATH_MAX + 32];
    snprintf(qdir, sizeof(qdir), "%s/quarantine", state);
    CHECK(count_entries(qdir, "not-a-record") == 2); /* it and its .reason */
    /* Imported once: the next start knows them. */
    im.calls = 0;
    CHECK(store_import(s, STORE_JOBS, "job.json", import_fake, &im, err, sizeof(err)) == 0 &&
          im.calls == 1); /* only the refused one again */
    store_close(s);

    /* A database that is not one goes to quarantine with its reason, and a
     * new one is started, which the import fills from the directories. */
    char db[PATH_MAX + 32];
    snprintf(db, sizeof(db), "%s/%s", state, STORE_FILE);
    write_text(db, "this is not an SQLite database, just text long enough to look like a header");
    s = store_open(state, err, sizeof(err));
    CHECK(s != NULL);
    if (!s)
        fprintf(stderr, "  %s\n", err);
    CHECK(count_entries(qdir, "store-" STORE_FILE) >= 2);
    im.calls = 0;
    n = s ? store_import(s, STORE_JOBS, "job.json", import_fake, &im, err, sizeof(err)) : -1;
    CHECK(n == 3 && im.calls == 4); /* known, fresh[0], fresh[1] and the refused one */
    struct store_row got;
    CHECK(s && store_get(s, STORE_JOBS, known, false, &got) == STORE_FOUND);
    store_row_finish(&got);
    store_close(s);
    remove_state(state);
}

/* --once keeps its one job in memory, with its own directory. */
static void test_memory(void)
{
    char err[256];
    struct store *s = store_open(NULL, err, sizeof(err));
    CHECK(s != NULL && store_state_dir(s)[0] == '\0');
    if (!s)
        return;
    struct store_row r;
    fill_row(2, &r);
    snprintf(r.dir, sizeof(r.dir), "/some/where/out");
    r.dir_given = true;
    CHECK(store_put(s, &r, 0, NULL, err, sizeof(err)));
    store_row_finish(&r);
    struct store_row got;
    char id[RECORD_ID_LEN];
    id_of(2, id);
    CHECK(store_get(s, STORE_JOBS, id, true, &got) == STORE_FOUND && got.dir_given &&
          !strcmp(got.dir, "/some/where/out"));
    store_row_finish(&got);
    struct store_query q = {.kind = STORE_JOBS, .limit = 10};
    struct walk *w = calloc(1, sizeof(*w));
    char next[RECORD_ID_LEN];
    CHECK(store_list(s, &q, collect, w, next, err, sizeof(err)) && w->n == 1);
    free(w);
    store_close(s);
}

static void test_figures(void)
{
    json_t *single = json_loads("{\"frame_ms\":{\"median\":12.5,\"median_ci95\":[12,13]},"
                                "\"gpu_ms\":{\"median\":2.0,\"median_ci95\":[1.9,2.1]},"
                                "\"quality\":{\"worst_ssim\":{\"value\":0.99,\"frame\":10}},"
                                "\"device\":{\"gl_renderer\":\"llvmpipe\",\"gl_version\":\"4.5\"}}",
                                0, NULL);
    json_t *fig = job_figures(single);
    CHECK(json_real_value(json_object_get(json_object_get(fig, "frame_ms"), "median")) == 12.5);
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(fig, "frame_ms"), "over")),
                  "frames"));
    CHECK(json_real_value(json_object_get(fig, "worst_ssim")) == 0.99 &&
          !strcmp(json_string_value(json_object_get(fig, "gl_renderer")), "llvmpipe") &&
          json_integer_value(json_object_get(fig, "runs")) == 1);
    CHECK(!json_object_get(fig, "cpu_ms"));
    json_decref(fig);
    json_t *repeated = json_loads("{\"frame_ms\":{\"median\":12.5},\"repeat\":{\"runs\":3,"
                                  "\"frame_ms\":{\"median\":13.0,\"ci95\":[12.0,14.0]}}}", 0, NULL);
    fig = job_figures(repeated);
    CHECK(json_real_value(json_object_get(json_object_get(fig, "frame_ms"), "median")) == 13.0 &&
          json_integer_value(json_object_get(fig, "runs")) == 3);
    json_decref(fig);
    CHECK(job_figures(NULL) == NULL);
    json_decref(single);
    json_decref(repeated);
}

/* A legacy job directory as the earlier version wrote it. */
static void legacy_job(const char *state, const char *id, const char *status, const char *job_json,
                       bool spec, const char *result)
{
    char dir[PATH_MAX + 64], path[PATH_MAX + 96], text[2048];
    snprintf(dir, sizeof(dir), "%s/jobs/%s", state, id);
    fs_mkdir_p(dir);
    const char *body = "{\"technique\": \"unlit\", \"frames\": 2, \"warmup_frames\": 0,"
                       " \"labels\": {\"commit\": \"old\"}}";
    if (job_json) {
        snprintf(path, sizeof(path), "%s/job.json", dir);
        write_text(path, job_json);
    } else if (status) {
        snprintf(text, sizeof(text),
                 "{\"id\": \"%s\", \"status\": \"%s\", \"technique\": \"unlit\", \"progress\":"
                 " {\"frames_done\": 2, \"frames_total\": 2}, \"created\": \"x\", \"spec\": %s,"
                 " \"times_unix\": [1900000000.5, 1900000001.0, %s]%s}",
                 id, status, body, strcmp(status, "queued") && strcmp(status, "running") ? "1900000002.0" : "0",
                 strcmp(status, "failed") ? "" : ", \"error\": \"it failed\"");
        snprintf(path, sizeof(path), "%s/job.json", dir);
        write_text(path, text);
    }
    if (spec) {
        snprintf(text, sizeof(text), "{\"id\": \"%s\", \"created_unix\": 1900000000.5, \"spec\": %s}",
                 id, body);
        snprintf(path, sizeof(path), "%s/spec.json", dir);
        write_text(path, text);
    }
    if (result) {
        snprintf(path, sizeof(path), "%s/result.json", dir);
        write_text(path, result);
    }
}

/* The queue imports a state directory of the earlier version: its
 * job.json files become rows (with labels and figures), the damaged ones
 * are quarantined and their jobs rebuilt, a queued job queues again, a
 * running one comes back interrupted (or done with a complete result). */
static void test_migration(void)
{
    char *state = make_state();
    char err[PATH_MAX + 300];
    const char *result = "{\"frame_ms\": {\"median\": 3.5, \"median_ci95\": [3, 4]},"
                         " \"device\": {\"gl_renderer\": \"llvmpipe\"}}";
    legacy_job(state, "20291231-235900-0001", "done", NULL, true, result);
    legacy_job(state, "20291231-235900-0002", "failed", NULL, false, NULL); /* no spec.json yet */
    legacy_job(state, "20291231-235900-0003", "queued", NULL, true, NULL);
    legacy_job(state, "20291231-235900-0004", "running", NULL, true, result);
    legacy_job(state, "20291231-235900-0005", "running", NULL, true, NULL);
    legacy_job(state, "20291231-235900-0006", NULL, "{\"id\": \"20291231-2", true, result);
    legacy_job(state, "20291231-235900-0007", NULL, "", false, NULL);
    legacy_job(state, "20291231-235900-0008", "done", NULL, true, "{\"frame_ms\": ");
    struct store *s = store_open(state, err, sizeof(err));
    struct queue *q = s ? queue_create(s, 8) : NULL;
    CHECK(q != NULL);
    if (!q)
        return;
    int n = queue_load(q, fixture_catalog(), err, sizeof(err));
    CHECK(n == 7);
    if (n != 7)
        fprintf(stderr, "  queue_load: %d (%s)\n", n, n < 0 ? err : "");
    struct {
        const char *id, *status;
        bool figures;
    } want[] = {
        {"20291231-235900-0001", "done", true},      {"20291231-235900-0002", "failed", false},
        {"20291231-235900-0003", "queued", false},   {"20291231-235900-0004", "done", true},
        {"20291231-235900-0005", "interrupted", false}, {"20291231-235900-0006", "done", true},
        {"20291231-235900-0008", "failed", false},
    };
    for (size_t i = 0; i < sizeof(want) / sizeof(want[0]); i++) {
        json_t *job = queue_job_json(q, want[i].id, 0);
        const char *st = json_string_value(json_object_get(job, "status"));
        CHECK(st && !strcmp(st, want[i].status));
        if (!st || strcmp(st, want[i].status))
            fprintf(stderr, "  %s: %s, want %s\n", want[i].id, st ? st : "(none)", want[i].status);
        CHECK(!!json_object_get(job, "result") == want[i].figures);
        json_decref(job);
        char path[PATH_MAX + 96];
        snprintf(path, sizeof(path), "%s/jobs/%s/job.json", state, want[i].id);
        CHECK(!exists(path)); /* imported, or quarantined */
        snprintf(path, sizeof(path), "%s/jobs/%s/spec.json", state, want[i].id);
        CHECK(exists(path));
    }
    json_t *job = queue_job_json(q, "20291231-235900-0002", 0);
    CHECK(!strcmp(json_string_value(json_object_get(job, "error")), "it failed"));
    json_decref(job);
    job = queue_job_json(q, "20291231-235900-0008", 0);
    CHECK(strstr(json_string_value(json_object_get(job, "error")), "quarantine") != NULL);
    json_decref(job);
    CHECK(queue_job_json(q, "20291231-235900-0007", 0) == NULL); /* nothing to rebuild it from */
    char qdir[PATH_MAX + 32];
    snprintf(qdir, sizeof(qdir), "%s/quarantine", state);
    CHECK(count_entries(qdir, "20291231-235900-0006-job.json") == 2);
    CHECK(count_entries(qdir, "jobs-20291231-235900-0007-") == 2);
    CHECK(count_entries(qdir, "20291231-235900-0008-result.json") == 2);

    /* Listed with labels and figures, the label filter included. */
    struct store_query query = {.kind = STORE_JOBS, .limit = 100};
    add_term(&query, STORE_TERM_LABEL, "commit", "old");
    char next[RECORD_ID_LEN];
    json_t *list = queue_list_page(q, &query, next, err, sizeof(err));
    json_t *jobs = json_object_get(list, "jobs");
    CHECK(json_array_size(jobs) == 7 && !next[0]);
    json_t *first = json_array_get(jobs, 0);
    CHECK(json_real_value(json_object_get(json_object_get(json_object_get(first, "figures"),
                                                          "frame_ms"), "median")) == 3.5);
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(first, "labels"), "commit")),
                  "old"));
    json_decref(list);
    size_t counts[JOB_STATUS_COUNT];
    CHECK(queue_counts(q, counts) && counts[JOB_QUEUED] == 1 && counts[JOB_DONE] == 3);
    /* The queued one is handed to the render thread first. */
    struct job *next_job = queue_next(q);
    CHECK(next_job && !strcmp(next_job->id, "20291231-235900-0003"));
    if (next_job)
        queue_finish(q, next_job, JOB_FAILED, "test", NULL);
    queue_destroy(q);
    store_close(s);

    /* The next start finds the store, nothing left to import. */
    s = store_open(state, err, sizeof(err));
    q = s ? queue_create(s, 8) : NULL;
    CHECK(q && queue_load(q, fixture_catalog(), err, sizeof(err)) == 7);
    job = q ? queue_job_json(q, "20291231-235900-0003", 0) : NULL;
    CHECK(job && !strcmp(json_string_value(json_object_get(job, "status")), "failed"));
    json_decref(job);
    queue_destroy(q);
    store_close(s);
    remove_state(state);
}

/* Damaged records (issue 26): a result.json that cannot be read is
 * quarantined wherever it is found, at start-up too (it was left in place
 * when its job was rebuilt or found running), and a job rebuilt from its
 * directory keeps the start time its result.json carries. */
static void test_rebuilt_records(void)
{
    char *state = make_state();
    char err[PATH_MAX + 300];
    const char *result = "{\"frame_ms\": {\"median\": 3.5}, \"started_unix\": 1900000001.0}";
    /* A damaged job.json, rebuilt from spec.json and result.json: done. */
    legacy_job(state, "20291231-235900-0001", NULL, "{\"id\": \"2029", true, result);
    /* Running when the daemon died, its result.json damaged. */
    legacy_job(state, "20291231-235900-0002", "running", NULL, true, "{\"frame_ms\": ");
    /* No row and no job.json (the store was rebuilt), result.json damaged. */
    legacy_job(state, "20291231-235900-0003", NULL, NULL, true, "[1, 2]");
    struct store *s = store_open(state, err, sizeof(err));
    struct queue *q = s ? queue_create(s, 8) : NULL;
    CHECK(q && queue_load(q, fixture_catalog(), err, sizeof(err)) == 3);
    if (!q)
        return;
    json_t *job = queue_job_json(q, "20291231-235900-0001", 0);
    const char *started = json_string_value(json_object_get(job, "started"));
    CHECK(!strcmp(json_string_value(json_object_get(job, "status")), "done") && started &&
          !strncmp(started, "2030-03-17T17:46:41", 19));
    json_decref(job);
    for (int i = 2; i <= 3; i++) {
        char id[RECORD_ID_LEN], prefix[64];
        snprintf(id, sizeof(id), "20291231-235900-000%d", i);
        job = queue_job_json(q, id, 0);
        const char *error = json_string_value(json_object_get(job, "error"));
        CHECK(!strcmp(json_string_value(json_object_get(job, "status")), "interrupted") && error &&
              strstr(error, "damaged") && strstr(error, "moved to") && strstr(error, "quarantine"));
        json_decref(job);
        char qdir[PATH_MAX + 32], path[PATH_MAX + 96];
        snprintf(qdir, sizeof(qdir), "%s/quarantine", state);
        snprintf(prefix, sizeof(prefix), "%s-result.json", id);
        CHECK(count_entries(qdir, prefix) == 2); /* the file and its .reason */
        snprintf(path, sizeof(path), "%s/jobs/%s/result.json", state, id);
        CHECK(!exists(path));
    }
    queue_destroy(q);
    store_close(s);
    remove_state(state);
}

static long long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long long)st.st_size : -1;
}

/* The reserve a full disk draws on (store_reserve.h): its room is taken at
 * open and given back on release; a state noted and not stored is found by
 * the next open (the newest note of a record wins, a stored one goes), and
 * goes once applied. */
static void test_reserve(void)
{
    char *state = make_state();
    char path[PATH_MAX + 32], status[32], error[512];
    snprintf(path, sizeof(path), "%s/%s", state, STORE_RESERVE_FILE);
    struct store_reserve *r = store_reserve_open(state);
    CHECK(r && file_size(path) == STORE_RESERVE_BYTES && store_reserve_ready(r) &&
          !store_reserve_released(r));
    CHECK(!store_reserve_found(r, 0, "20260101-000000-0001", status, sizeof(status), error,
                               sizeof(error)));
    CHECK(store_reserve_note(r, 0, "20260101-000000-0001", "running", ""));
    CHECK(store_reserve_note(r, 0, "20260101-000000-0001", "failed", "cannot write\tit:\nfull"));
    CHECK(store_reserve_note(r, 0, "20260101-000000-0002", "failed", "stored after all"));
    CHECK(store_reserve_note(r, 1, "20260101-000000-0003", "cancelled", "a sweep"));
    store_reserve_unnote(r, 0, "20260101-000000-0002");
    CHECK(store_reserve_release(r) && file_size(path) == STORE_RESERVE_NOTES_BYTES &&
          store_reserve_released(r) && !store_reserve_release(r));
    store_reserve_close(r);

    r = store_reserve_open(state); /* the next start: room again, and the notes */
    CHECK(r && file_size(path) == STORE_RESERVE_BYTES && store_reserve_ready(r));
    CHECK(store_reserve_found(r, 0, "20260101-000000-0001", status, sizeof(status), error,
                              sizeof(error)) &&
          !strcmp(status, "failed") && !strcmp(error, "cannot write it: full"));
    CHECK(!store_reserve_found(r, 0, "20260101-000000-0002", status, sizeof(status), error,
                               sizeof(error)));
    CHECK(store_reserve_found(r, 1, "20260101-000000-0003", status, sizeof(status), error,
                              sizeof(error)) && !strcmp(status, "cancelled"));
    CHECK(!store_reserve_found(r, 1, "20260101-000000-0001", status, sizeof(status), error,
                               sizeof(error))); /* kinds apart */
    /* A state noted now, then the earlier notes applied: only the new one
     * is left for the next start. */
    CHECK(store_reserve_note(r, 0, "20260101-000000-0004", "queued", ""));
    store_reserve_found_done(r);
    store_reserve_close(r);
    r = store_reserve_open(state);
    CHECK(r && !store_reserve_found(r, 0, "20260101-000000-0001", status, sizeof(status), error,
                                    sizeof(error)) &&
          store_reserve_found(r, 0, "20260101-000000-0004", status, sizeof(status), error,
                              sizeof(error)));
    store_reserve_close(r);
    remove_state(state);
}

/* The live set keeps id order whatever the order of insertion; the
 * version says stored only when no state is left to write. */
static void test_live_and_version(void)
{
    struct item {
        char id[RECORD_ID_LEN];
    } items[5] = {{"3"}, {"1"}, {"4"}, {"2"}, {"5"}};
    struct store_live live = {0};
    for (int i = 0; i < 5; i++)
        CHECK(store_live_insert(&live, &items[i]));
    CHECK(live.count == 5);
    for (size_t i = 0; i + 1 < live.count; i++)
        CHECK(strcmp(live.items[i], live.items[i + 1]) < 0);
    CHECK(store_live_find(&live, "4") == &items[2] && !store_live_find(&live, "6"));
    store_live_remove(&live, &items[2]);
    CHECK(live.count == 4 && !store_live_find(&live, "4") && store_live_find(&live, "5"));
    store_live_finish(&live);
    CHECK(live.count == 0 && !live.items);

    struct store_version v = {0};
    CHECK(store_version_stored(&v));
    uint64_t a = store_version_take(&v), b = store_version_take(&v);
    CHECK(b > a && !store_version_stored(&v));
    CHECK(!store_version_back(&v, b, true)); /* a still in flight */
    CHECK(store_version_back(&v, a, true) && v.saved == b); /* the late older one changes nothing */
    uint64_t c = store_version_take(&v);
    CHECK(!store_version_back(&v, c, false) && v.saved == b); /* a failed write: not stored */
}

int main(void)
{
    log_set_level(getenv("TEST_VERBOSE") ? LOG_DEBUG : (enum log_level)(LOG_ERROR + 1));
    test_rows_and_lists();
    test_kill_loses_nothing();
    test_import_and_damage();
    test_memory();
    test_figures();
    test_live_and_version();
    test_migration();
    test_rebuilt_records();
    test_reserve();
    return check_finish("test_store");
}
