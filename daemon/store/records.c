#define _POSIX_C_SOURCE 200809L
#include "daemon/store/records.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "common/fsutil.h"
#include "common/log.h"

static _Thread_local char submit_error[PATH_MAX + 300];

const char *records_submit_error(void) { return submit_error; }

void records_set_submit_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(submit_error, sizeof(submit_error), fmt, ap);
    va_end(ap);
}

void record_kind_init(struct record_kind *k, const char *state_dir, const char *name)
{
    memset(k, 0, sizeof(*k));
    snprintf(k->name, sizeof(k->name), "%s", name);
    if (state_dir && *state_dir) {
        snprintf(k->state_dir, sizeof(k->state_dir), "%s", state_dir);
        snprintf(k->root, sizeof(k->root), "%.*s/%s", (int)(sizeof(k->root) - sizeof(k->name) - 2),
                 state_dir, k->name);
    }
    atomic_init(&k->serial, 0);
}

bool record_id_valid(const char *id)
{
    size_t n = strlen(id);
    if (n == 0 || n >= RECORD_ID_LEN)
        return false;
    for (size_t i = 0; i < n; i++)
        if (!((id[i] >= '0' && id[i] <= '9') || id[i] == '-'))
            return false;
    return true;
}

bool record_create_dir(struct record_kind *k, const char *dir_override, char id[RECORD_ID_LEN],
                       char *dir, size_t cap, char *err, size_t errlen)
{
    /* Time-ordered ids: they sort by submission and stay unique across restarts. */
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    char stamp[16];
    strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &tm);
    if (!dir_override && !k->root[0]) {
        snprintf(err, errlen, "no state directory to keep %s in", k->name);
        return false;
    }
    if (!dir_override && !fs_mkdir_p(k->root)) {
        snprintf(err, errlen, "cannot create %s: %s", k->root, strerror(errno));
        return false;
    }
    /* The serial is atomic, so no lock is held across the mkdir; an id whose
     * directory exists (a restart in the same second) moves on to the next. */
    for (int attempt = 0; attempt < 10000; attempt++) {
        unsigned serial = atomic_fetch_add(&k->serial, 1) + 1;
        snprintf(id, RECORD_ID_LEN, "%.15s-%04u", stamp, serial % 10000u);
        if (dir_override) {
            snprintf(dir, cap, "%s", dir_override);
            if (fs_mkdir_p(dir))
                return true;
            snprintf(err, errlen, "cannot create %s: %s", dir, strerror(errno));
            return false;
        }
        snprintf(dir, cap, "%s/%s", k->root, id);
        if (mkdir(dir, 0755) == 0)
            return true;
        if (errno != EEXIST) {
            snprintf(err, errlen, "cannot create %s: %s", dir, strerror(errno));
            return false;
        }
    }
    snprintf(err, errlen, "no free id under %s", k->root);
    return false;
}

void record_note_id(struct record_kind *k, const char *id)
{
    const char *dash = strrchr(id, '-');
    unsigned serial = dash ? (unsigned)strtoul(dash + 1, NULL, 10) : 0;
    unsigned cur = atomic_load(&k->serial);
    while (serial > cur && !atomic_compare_exchange_weak(&k->serial, &cur, serial))
        ;
}

json_t *record_read(const char *path, char *why, size_t whylen)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(why, whylen, "cannot open it: %s", strerror(errno));
        return NULL;
    }
    struct stat st;
    json_t *o = NULL;
    if (fstat(fileno(f), &st) != 0) {
        snprintf(why, whylen, "cannot stat it: %s", strerror(errno));
    } else if (st.st_size == 0) {
        snprintf(why, whylen, "empty file");
    } else {
        json_error_t jerr;
        o = json_loadf(f, JSON_REJECT_DUPLICATES, &jerr);
        if (!o)
            snprintf(why, whylen, "not JSON (line %d, column %d: %s)", jerr.line, jerr.column,
                     jerr.text);
        else if (!json_is_object(o)) {
            snprintf(why, whylen, "not a JSON object");
            json_decref(o);
            o = NULL;
        }
    }
    fclose(f);
    return o;
}

bool record_quarantine(const struct record_kind *k, const char *id, const char *path,
                       const char *reason, char *moved_to, size_t cap)
{
    char qdir[PATH_MAX], dest[PATH_MAX + 320];
    if (!k->state_dir[0]) {
        LOG(LOG_ERROR, "cannot quarantine %s (no state directory): %s", path, reason);
        return false;
    }
    snprintf(qdir, sizeof(qdir), "%.*s/quarantine", (int)(sizeof(qdir) - 16), k->state_dir);
    if (!fs_mkdir_p(qdir)) {
        LOG(LOG_ERROR, "cannot quarantine %s: cannot create %s: %s; it stays where it is (%s)",
            path, qdir, strerror(errno), reason);
        return false;
    }
    /* A file keeps its name in the quarantined one; a record's directory
     * (named by its id) is the record. */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    char stamp[32];
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(stamp, sizeof(stamp), "%Y%m%dT%H%M%SZ", &tm);
    bool moved = false;
    for (int n = 0; n < 1000 && !moved; n++) {
        char suffix[16] = "";
        if (n)
            snprintf(suffix, sizeof(suffix), ".%d", n);
        bool named = strcmp(base, id) == 0; /* the id says it all */
        if (snprintf(dest, sizeof(dest), "%s/%s-%.64s%s%.200s-%s%s", qdir, k->name, id,
                     named ? "" : "-", named ? "" : base, stamp, suffix) >= (int)sizeof(dest)) {
            LOG(LOG_ERROR, "cannot quarantine %s: the state directory's path is too long (%s)",
                path, reason);
            return false;
        }
        /* Never replace an earlier quarantined copy. */
        if (access(dest, F_OK) == 0)
            continue;
        if (rename(path, dest) != 0) {
            LOG(LOG_ERROR, "cannot quarantine %s to %s: %s; it stays where it is (%s)", path, dest,
                strerror(errno), reason);
            return false;
        }
        moved = true;
    }
    if (!moved) {
        LOG(LOG_ERROR, "cannot quarantine %s: no free name in %s (%s)", path, qdir, reason);
        return false;
    }
    LOG(LOG_WARN, "quarantined %s to %s: %s", path, dest, reason);
    char reason_path[PATH_MAX + 340], text[1200];
    snprintf(reason_path, sizeof(reason_path), "%s.reason", dest);
    int len = snprintf(text, sizeof(text), "%s\n%s\n", path, reason);
    if (!fs_write_atomic(reason_path, text, len < (int)sizeof(text) ? (size_t)len : sizeof(text) - 1))
        LOG(LOG_WARN, "cannot write %s: %s", reason_path, strerror(errno));
    if (moved_to)
        snprintf(moved_to, cap, "%s", dest);
    return true;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

/* Temporary files are what an interrupted atomic write leaves: never a record. */
void record_remove_tmp_files(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    char path[PATH_MAX + 300];
    while ((e = readdir(d)))
        if (e->d_name[0] != '.' && ends_with(e->d_name, ".tmp")) {
            if (snprintf(path, sizeof(path), "%s/%s", dir, e->d_name) >= (int)sizeof(path))
                continue;
            if (unlink(path) == 0)
                LOG(LOG_INFO, "removed the leftover temporary file %s", path);
            else
                LOG(LOG_WARN, "cannot remove the leftover temporary file %s: %s", path,
                    strerror(errno));
        }
    closedir(d);
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int record_scan(struct record_kind *k, record_known_fn known, record_load_fn load, void *ctx,
                char *err, size_t errlen)
{
    if (!k->root[0])
        return 0;
    DIR *d = opendir(k->root);
    if (!d) {
        if (errno == ENOENT)
            return 0;
        snprintf(err, errlen, "cannot read %s: %s", k->root, strerror(errno));
        return -1;
    }
    /* Names first: quarantining moves entries out of the directory being read. */
    char **names = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    int rc = 0;
    while ((e = readdir(d))) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
            continue;
        if (n == cap) {
            cap = cap ? cap * 2 : 64;
            char **grown = realloc(names, cap * sizeof(*names));
            if (!grown) {
                rc = -1;
                break;
            }
            names = grown;
        }
        if (!(names[n] = strdup(e->d_name))) {
            rc = -1;
            break;
        }
        n++;
    }
    closedir(d);
    if (rc < 0) {
        snprintf(err, errlen, "out of memory reading %s", k->root);
        goto out;
    }
    if (n > 1) /* names is NULL in an empty folder, which qsort may not take */
        qsort(names, n, sizeof(*names), by_name);
    for (size_t i = 0; i < n; i++) {
        char path[PATH_MAX + 300];
        snprintf(path, sizeof(path), "%s/%s", k->root, names[i]);
        struct stat st;
        if (ends_with(names[i], ".tmp")) {
            if (unlink(path) == 0)
                LOG(LOG_INFO, "removed the leftover temporary file %s", path);
            continue;
        }
        if (known && record_id_valid(names[i]) && known(ctx, names[i]))
            continue;
        if (lstat(path, &st) != 0)
            continue; /* gone meanwhile */
        if (!S_ISDIR(st.st_mode) || !record_id_valid(names[i])) {
            record_quarantine(k, names[i], path,
                              S_ISDIR(st.st_mode) ? "a directory whose name is not a record id"
                                                  : "not a record directory",
                              NULL, 0);
            continue;
        }
        record_remove_tmp_files(path);
        load(ctx, names[i], path);
        rc++;
    }
out:
    for (size_t i = 0; i < n; i++)
        free(names[i]);
    free(names);
    return rc;
}

bool record_remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *e;
        char path[PATH_MAX + 300];
        while ((e = readdir(d)))
            if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
                snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
                if (unlink(path) != 0)
                    LOG(LOG_WARN, "retention: cannot remove %s: %s", path, strerror(errno));
            }
        closedir(d);
    }
    if (rmdir(dir) != 0) {
        LOG(LOG_WARN, "retention: cannot remove %s: %s", dir, strerror(errno));
        return false;
    }
    return true;
}
