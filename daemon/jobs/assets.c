/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets (assets.h): the lifetime, the worker thread that converts one
 * task at a time, the start-up sweep of leftover files, /v1/info's limits. */
#include "daemon/jobs/assets_impl.h"
#include "daemon/scene/environment.h"

#include <dirent.h>
#include <errno.h>
#include <nettle/sha2.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/child.h"
#include "common/fsutil.h"
#include "common/log.h"

void asset_refuse(struct assets_error *e, enum assets_cause cause, const char *field,
                  const char *fmt, ...)
{
    e->cause = cause;
    snprintf(e->field, sizeof(e->field), "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->message, sizeof(e->message), fmt, ap);
    va_end(ap);
}

void sha256_hex(const uint8_t digest[SHA256_DIGEST_SIZE], char out[65])
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++) {
        out[2 * i] = digits[digest[i] >> 4];
        out[2 * i + 1] = digits[digest[i] & 15];
    }
    out[64] = '\0';
}

void assets_notify(struct assets *a)
{
    if (a->listener)
        a->listener(a->listener_ctx);
}

static void *worker(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-assets"); /* named in crash reports, top, gdb */
    struct assets *a = arg;
    pthread_mutex_lock(&a->lock);
    for (;;) {
        while (!a->stopping && !a->tasks)
            pthread_cond_wait(&a->work, &a->lock);
        if (a->stopping)
            break;
        struct task *t = a->tasks;
        a->tasks = t->next;
        if (!a->tasks)
            a->tasks_tail = &a->tasks;
        if (t->kind == TASK_UPLOAD)
            snprintf(a->busy_sha, sizeof(a->busy_sha), "%s", t->sha256);
        pthread_mutex_unlock(&a->lock);
        if (t->kind == TASK_UPLOAD)
            asset_upload_run(a, t);
        else
            asset_dir_run(a, t);
        pthread_mutex_lock(&a->lock);
        if (t->kind == TASK_UPLOAD)
            a->uploads--;
        free(t);
    }
    pthread_mutex_unlock(&a->lock);
    return NULL;
}

/* Without hashes: the temporaries of a run that stopped (uploads,
 * conversions and the cache the converter was writing), at start-up before
 * anything new is made. With hashes: the files of hashes no name points at
 * and nothing holds (a crash between a delete's row and its files). */
static void sweep_state_dir(struct assets *a, bool hashes)
{
    DIR *d = opendir(a->dir);
    if (!d)
        return;
    struct dirent *de;
    while ((de = readdir(d))) {
        const char *n = de->d_name;
        char path[PATH_MAX + 300];
        snprintf(path, sizeof(path), "%s/%s", a->dir, n);
        if (strncmp(n, "upload-", 7) == 0 || strncmp(n, "convert-", 8) == 0 || strstr(n, ".tmp")) {
            if (!hashes && unlink(path) == 0)
                LOG(LOG_INFO, "assets: removed %s, left by an earlier run", path);
            continue;
        }
        char sha[65];
        if (hashes && strlen(n) > 65 && n[64] == '.') {
            memcpy(sha, n, 64);
            sha[64] = '\0';
            asset_release_files_locked(a, sha);
        }
    }
    closedir(d);
}

void assets_release_unused(struct assets *a)
{
    pthread_mutex_lock(&a->lock);
    sweep_state_dir(a, true);
    pthread_mutex_unlock(&a->lock);
}

static bool find_converter(const struct assets_config *cfg, char *out, size_t cap, char *err,
                           size_t errlen)
{
    if (cfg->converter && *cfg->converter) {
        snprintf(out, cap, "%s", cfg->converter);
        return true;
    }
    char self[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    if (n <= 0) {
        snprintf(err, errlen, "cannot find the daemon's own executable (/proc/self/exe: %s); "
                 "name the converter with --asset-converter", strerror(errno));
        return false;
    }
    self[n] = '\0';
    char *slash = strrchr(self, '/');
    *slash = '\0';
    if (snprintf(out, cap, "%.*s/shadebench-asset", (int)(cap - 20), self) >= (int)cap) {
        snprintf(err, errlen, "the daemon's path is too long; name the converter with "
                 "--asset-converter");
        return false;
    }
    return true;
}

struct assets *assets_create(const struct assets_config *cfg, struct store *store,
                             struct queue *queue, char *err, size_t errlen)
{
    struct assets *a = calloc(1, sizeof(*a));
    if (!a) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    a->cfg = *cfg;
    a->store = store;
    a->queue = queue;
    a->tasks_tail = &a->tasks;
    pthread_mutex_init(&a->lock, NULL);
    pthread_cond_init(&a->work, NULL);
    snprintf(a->state_dir, sizeof(a->state_dir), "%s", cfg->state_dir ? cfg->state_dir : "");
    snprintf(a->asset_dir, sizeof(a->asset_dir), "%s", cfg->asset_dir ? cfg->asset_dir : "");
    if (!find_converter(cfg, a->converter, sizeof(a->converter), err, errlen))
        goto fail;
    if (!asset_store_dir(a->state_dir, a->dir, sizeof(a->dir)) || !fs_mkdir_p(a->dir)) {
        snprintf(err, errlen, "cannot create %s: %s", a->dir, strerror(errno));
        goto fail;
    }
    if (access(a->converter, X_OK) != 0)
        LOG(LOG_WARN, "assets: the converter %s cannot be run (%s): uploads will be refused "
            "with 422 until it is installed", a->converter, strerror(errno));
    if (a->asset_dir[0] && !scan_asset_dir(a, err, errlen))
        goto fail;
    drop_gone_dir_rows(a);
    sweep_state_dir(a, false); /* no other thread yet */
    for (int i = 0; i < ASSETS_WORKERS; i++) {
        if (pthread_create(&a->workers[i], NULL, worker, a) != 0) {
            snprintf(err, errlen, "cannot start the asset thread");
            goto fail;
        }
        a->nworkers++;
    }
    return a;
fail:
    assets_destroy(a);
    return NULL;
}

void assets_destroy(struct assets *a)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->stopping = true;
    if (a->child > 0)
        child_kill(a->child);
    pthread_cond_broadcast(&a->work);
    pthread_mutex_unlock(&a->lock);
    for (int i = 0; i < a->nworkers; i++)
        pthread_join(a->workers[i], NULL);
    while (a->tasks) {
        struct task *t = a->tasks;
        a->tasks = t->next;
        if (t->kind == TASK_UPLOAD)
            unlink(t->path);
        free(t);
    }
    while (a->tickets) {
        struct ticket *t = a->tickets;
        a->tickets = t->next;
        json_decref(t->answer.record);
        free(t);
    }
    free(a->dir_entries);
    free(a->pins);
    pthread_cond_destroy(&a->work);
    pthread_mutex_destroy(&a->lock);
    free(a);
}

void assets_set_listener(struct assets *a, void (*fn)(void *ctx), void *ctx)
{
    pthread_mutex_lock(&a->lock);
    a->listener = fn;
    a->listener_ctx = ctx;
    pthread_mutex_unlock(&a->lock);
}

uint64_t assets_max_bytes(const struct assets *a) { return a->cfg.max_asset_bytes; }

double assets_answer_wait_s(const struct assets *a)
{
    /* Every conversion queued before it may take its whole time-out. */
    return a->cfg.run.wall_s * (ASSETS_MAX_UPLOADS + 1) + 30;
}

json_t *assets_info_json(const struct assets *a)
{
    struct environment_limits env;
    environment_limits_defaults(&env);
    return json_pack("{s:I, s:o, s:o, s:I, s:I, s:f, s:i, s:i}", "max_asset_bytes",
                     (json_int_t)a->cfg.max_asset_bytes, "limits",
                     asset_limits_to_json(&a->cfg.limits), "environment_limits",
                     environment_limits_to_json(&env), "max_memory_bytes",
                     (json_int_t)a->cfg.run.memory_bytes, "max_cpu_seconds",
                     (json_int_t)a->cfg.run.cpu_s, "timeout_s", a->cfg.run.wall_s,
                     "conversions_at_once", ASSETS_WORKERS, "max_uploads_at_once",
                     ASSETS_MAX_UPLOADS);
}
