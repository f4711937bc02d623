/* The records' directories shared by jobs and sweeps: ids that never
 * clash, quarantine that moves and never deletes, leftover temporary files
 * removed at load, directories the store knows left unopened. Runs in a
 * fresh temporary directory. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/fsutil.h"
#include "common/log.h"
#include "daemon/store/records.h"
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

struct seen {
    char ids[8][RECORD_ID_LEN];
    int n;
    char known[RECORD_ID_LEN];
};

static bool is_known(void *ctx, const char *id)
{
    const struct seen *s = ctx;
    return strcmp(s->known, id) == 0;
}

static void collect(void *ctx, const char *id, const char *dir)
{
    struct seen *s = ctx;
    (void)dir;
    if (s->n < 8)
        snprintf(s->ids[s->n++], RECORD_ID_LEN, "%s", id);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

int main(void)
{
    log_set_level(LOG_ERROR);
    char tmpl[] = "/tmp/test-records-XXXXXX";
    const char *state = mkdtemp(tmpl);
    CHECK(state != NULL);
    if (!state)
        return check_finish("test_records");

    CHECK(record_id_valid("20261122-061200-0001"));
    CHECK(!record_id_valid("../etc"));
    CHECK(!record_id_valid(""));
    CHECK(!record_id_valid("123456789012345678901234"));

    /* Ids: fresh directories in order; a restart continues after loaded ids. */
    struct record_kind k;
    record_kind_init(&k, state, "jobs");
    char id1[RECORD_ID_LEN], id2[RECORD_ID_LEN], dir1[PATH_MAX], dir2[PATH_MAX], err[512];
    CHECK(record_create_dir(&k, NULL, id1, dir1, sizeof(dir1), err, sizeof(err)));
    CHECK(record_create_dir(&k, NULL, id2, dir2, sizeof(dir2), err, sizeof(err)));
    CHECK(strcmp(id1, id2) < 0 && exists(dir1) && exists(dir2));
    struct record_kind again;
    record_kind_init(&again, state, "jobs");
    record_note_id(&again, id2);
    char id3[RECORD_ID_LEN], dir3[PATH_MAX];
    CHECK(record_create_dir(&again, NULL, id3, dir3, sizeof(dir3), err, sizeof(err)));
    CHECK(strcmp(id3, id2) > 0);

    char path[PATH_MAX + 32], why[256];
    /* Reading says why it cannot. */
    snprintf(path, sizeof(path), "%s/empty.json", dir2);
    write_text(path, "");
    CHECK(!record_read(path, why, sizeof(why)) && strcmp(why, "empty file") == 0);
    write_text(path, "{\"id\": \"x\", tru");
    CHECK(!record_read(path, why, sizeof(why)) && strstr(why, "not JSON (line 1"));
    write_text(path, "[1, 2]");
    CHECK(!record_read(path, why, sizeof(why)) && strstr(why, "not a JSON object"));
    snprintf(path, sizeof(path), "%s/absent.json", dir2);
    CHECK(!record_read(path, why, sizeof(why)) && strstr(why, "No such file"));

    /* Scanning: *.tmp files go, odd entries are quarantined, records are
     * handed over in id order. */
    snprintf(path, sizeof(path), "%s/job.json.tmp", dir1);
    write_text(path, "half a reco");
    char stray[PATH_MAX + 32], notid[PATH_MAX + 32], top_tmp[PATH_MAX + 32];
    snprintf(stray, sizeof(stray), "%s/jobs/stray-file", state);
    write_text(stray, "what is this");
    snprintf(notid, sizeof(notid), "%s/jobs/not-an-id", state);
    mkdir(notid, 0755);
    snprintf(top_tmp, sizeof(top_tmp), "%s/jobs/x.tmp", state);
    write_text(top_tmp, "");
    /* A directory the store knows is left unopened: its *.tmp stays. */
    char known_tmp[PATH_MAX + 32];
    snprintf(known_tmp, sizeof(known_tmp), "%s/result.json.tmp", dir2);
    write_text(known_tmp, "half");
    struct seen seen = {0};
    snprintf(seen.known, sizeof(seen.known), "%s", id2);
    int n = record_scan(&again, is_known, collect, &seen, err, sizeof(err));
    CHECK(n == 2 && seen.n == 2);
    CHECK(strcmp(seen.ids[0], id1) == 0 && strcmp(seen.ids[1], id3) == 0);
    CHECK(!exists(path) && !exists(top_tmp) && exists(known_tmp));
    unlink(known_tmp);
    /* Without the store's say, every directory is handed over. */
    struct seen all = {0};
    CHECK(record_scan(&again, NULL, collect, &all, err, sizeof(err)) == 3 && all.n == 3 &&
          strcmp(all.ids[1], id2) == 0);
    CHECK(!exists(stray) && !exists(notid));
    char qdir[PATH_MAX + 32];
    snprintf(qdir, sizeof(qdir), "%s/quarantine", state);
    CHECK(count_entries(qdir, "stray-file") == 2); /* the file and its .reason */
    CHECK(count_entries(qdir, ".reason") == 2);

    /* Quarantine moves a record's directory and keeps what is there already. */
    char moved[PATH_MAX];
    CHECK(record_quarantine(&again, id2, dir2, "a test reason", moved, sizeof(moved)));
    CHECK(!exists(dir2) && exists(moved));
    char reason_path[PATH_MAX + 16];
    snprintf(reason_path, sizeof(reason_path), "%s.reason", moved);
    size_t len = 0;
    char *reason = fs_read_file(reason_path, 4096, &len);
    CHECK(reason && strstr(reason, "a test reason") && strstr(reason, dir2));
    free(reason);
    /* The same name again (same second) gets a new name, never replaces it. */
    CHECK(mkdir(dir2, 0755) == 0);
    char moved2[PATH_MAX];
    CHECK(record_quarantine(&again, id2, dir2, "again", moved2, sizeof(moved2)));
    CHECK(strcmp(moved, moved2) != 0 && exists(moved) && exists(moved2));
    struct record_kind none;
    record_kind_init(&none, NULL, "jobs");
    CHECK(!record_quarantine(&none, id1, dir1, "no state dir", NULL, 0) && exists(dir1));

    /* Removing a finished record's directory. */
    CHECK(record_remove_dir(dir3) && !exists(dir3));

    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", state);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", state);
    return check_finish("test_records");
}
