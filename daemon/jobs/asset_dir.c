/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets of --asset-dir: the folder scanned at start, each file hashed
 * and converted on the worker, its state while it is not ready (assets.h). */
#include "daemon/jobs/assets_impl.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <nettle/sha2.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/log.h"

struct dir_entry *asset_dir_find(struct assets *a, const char *name)
{
    for (size_t i = 0; i < a->ndir; i++)
        if (strcmp(a->dir_entries[i].name, name) == 0)
            return &a->dir_entries[i];
    return NULL;
}

static bool hash_file(const char *path, char sha[65], uint64_t *size, char *why, size_t cap)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        snprintf(why, cap, "cannot read %s: %s", path, strerror(errno));
        return false;
    }
    struct sha256_ctx ctx;
    sha256_init(&ctx);
    static _Thread_local char buf[1 << 16];
    ssize_t n;
    *size = 0;
    while ((n = read(fd, buf, sizeof(buf))) > 0 || (n < 0 && errno == EINTR))
        if (n > 0) {
            sha256_update(&ctx, (size_t)n, (const uint8_t *)buf);
            *size += (uint64_t)n;
        }
    int saved = errno;
    close(fd);
    if (n < 0) {
        snprintf(why, cap, "cannot read %s: %s", path, strerror(saved));
        return false;
    }
    uint8_t digest[SHA256_DIGEST_SIZE];
    sha256_digest(&ctx, SHA256_DIGEST_SIZE, digest);
    sha256_hex(digest, sha);
    return true;
}

static void set_dir_state(struct assets *a, const char *name, enum dir_state st, const char *why)
{
    pthread_mutex_lock(&a->lock);
    struct dir_entry *d = asset_dir_find(a, name);
    if (d) {
        d->state = st;
        snprintf(d->error, sizeof(d->error), "%s", why ? why : "");
    }
    pthread_mutex_unlock(&a->lock);
}

void asset_dir_run(struct assets *a, struct task *t)
{
    char why[PATH_MAX + 100];
    struct assets_error e = {0};
    if (!hash_file(t->path, t->sha256, &t->size, why, sizeof(why))) {
        LOG(LOG_WARN, "assets: --asset-dir: %s", why);
        set_dir_state(a, t->name, DIR_FAILED, "the file cannot be read (see the log)");
        return;
    }
    pthread_mutex_lock(&a->lock);
    snprintf(a->busy_sha, sizeof(a->busy_sha), "%s", t->sha256);
    pthread_mutex_unlock(&a->lock);
    json_t *description = NULL;
    bool ok = asset_ensure_cache(a, t->sha256, t->path, &description, &e);
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    bool replaced;
    if (ok)
        ok = asset_put_record_locked(a, t, description, &replaced, &e);
    if (!ok) {
        /* The file changed and no longer converts: its old record would
         * name bytes the folder no longer has. */
        struct store_asset old;
        if (store_asset_get(a->store, t->name, &old) == STORE_FOUND && old.from_dir) {
            char err[PATH_MAX + 300];
            if (store_asset_delete(a->store, t->name, err, sizeof(err)))
                asset_release_files_locked(a, old.sha256);
        }
        store_asset_finish(&old);
        asset_release_files_locked(a, t->sha256);
    }
    pthread_mutex_unlock(&a->lock);
    json_decref(description);
    if (ok) {
        set_dir_state(a, t->name, DIR_READY, NULL);
        return;
    }
    char msg[512]; /* dir_entry.error's size */
    snprintf(msg, sizeof(msg), "%.40s: %.440s", e.field, e.message);
    LOG(LOG_WARN, "assets: --asset-dir %s: %s", t->path, msg);
    set_dir_state(a, t->name, DIR_FAILED, msg);
}

static bool has_asset_ext(const char *name, char ext[8])
{
    const char *dot = strrchr(name, '.');
    if (dot && strcasecmp(dot, ".glb") == 0)
        return snprintf(ext, 8, "glb"), true;
    if (dot && strcasecmp(dot, ".gltf") == 0)
        return snprintf(ext, 8, "gltf"), true;
    if (dot && strcasecmp(dot, ".hdr") == 0)
        return snprintf(ext, 8, "hdr"), true;
    if (dot && strcasecmp(dot, ".exr") == 0)
        return snprintf(ext, 8, "exr"), true;
    return false;
}

static void collect_dir_row(void *ctx, const struct store_asset *r)
{
    json_array_append_new(ctx, json_string(r->name));
}

/* The folder's .glb and .gltf files: each a task for the worker. A link
 * is followed only when it stays inside the folder. */
bool scan_asset_dir(struct assets *a, char *err, size_t errlen)
{
    if (!realpath(a->asset_dir, a->asset_dir_real)) {
        snprintf(err, errlen, "--asset-dir %s: %s", a->asset_dir, strerror(errno));
        return false;
    }
    DIR *d = opendir(a->asset_dir_real);
    if (!d) {
        snprintf(err, errlen, "--asset-dir %s: %s", a->asset_dir, strerror(errno));
        return false;
    }
    size_t base = strlen(a->asset_dir_real);
    struct dirent *de;
    while ((de = readdir(d))) {
        char ext[8], path[PATH_MAX + 300], real[PATH_MAX];
        if (de->d_name[0] == '.' || !has_asset_ext(de->d_name, ext))
            continue;
        if (!scene_asset_name_valid(de->d_name)) {
            LOG(LOG_WARN, "assets: --asset-dir: %s skipped: an asset name is 1 to %d letters, "
                "digits, '.', '_' or '-'", de->d_name, SCENE_ASSET_NAME_MAX);
            continue;
        }
        snprintf(path, sizeof(path), "%s/%s", a->asset_dir_real, de->d_name);
        struct stat st;
        if (!realpath(path, real) || strncmp(real, a->asset_dir_real, base) != 0 ||
            real[base] != '/' || stat(real, &st) != 0 || !S_ISREG(st.st_mode)) {
            LOG(LOG_WARN, "assets: --asset-dir: %s skipped: not a regular file inside %s (a "
                "link that leaves the folder is refused)", de->d_name, a->asset_dir_real);
            continue;
        }
        struct dir_entry *grown = realloc(a->dir_entries, (a->ndir + 1) * sizeof(*grown));
        struct task *t = calloc(1, sizeof(*t));
        if (!grown || !t) {
            free(t);
            if (grown)
                a->dir_entries = grown;
            closedir(d);
            snprintf(err, errlen, "out of memory");
            return false;
        }
        a->dir_entries = grown;
        struct dir_entry *e = &a->dir_entries[a->ndir++];
        memset(e, 0, sizeof(*e));
        snprintf(e->name, sizeof(e->name), "%.128s", de->d_name); /* checked: at most 128 */
        t->kind = TASK_DIR;
        snprintf(t->name, sizeof(t->name), "%.128s", de->d_name);
        snprintf(t->path, sizeof(t->path), "%s", real);
        snprintf(t->ext, sizeof(t->ext), "%s", ext);
        *a->tasks_tail = t;
        a->tasks_tail = &t->next;
    }
    closedir(d);
    LOG(LOG_INFO, "assets: %zu file(s) in --asset-dir %s, converted in the background",
        a->ndir, a->asset_dir_real);
    return true;
}

/* Rows of --asset-dir files that are no longer there (or no folder now). */
void drop_gone_dir_rows(struct assets *a)
{
    json_t *names = json_array();
    char next[STORE_ASSET_NAME_CAP] = "", err[PATH_MAX + 300];
    do {
        char after[STORE_ASSET_NAME_CAP];
        snprintf(after, sizeof(after), "%s", next);
        if (!store_asset_list(a->store, after, 1000, true, collect_dir_row, names, next, err,
                              sizeof(err)))
            break;
    } while (next[0]);
    size_t i;
    json_t *v;
    json_array_foreach(names, i, v) {
        const char *name = json_string_value(v);
        if (asset_dir_find(a, name))
            continue;
        struct store_asset old;
        if (store_asset_get(a->store, name, &old) == STORE_FOUND &&
            store_asset_delete(a->store, name, err, sizeof(err))) {
            LOG(LOG_INFO, "assets: %s left --asset-dir: its record goes", name);
            asset_release_files_locked(a, old.sha256);
        }
        store_asset_finish(&old);
    }
    json_decref(names);
}
