/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets: an upload streamed to a temporary file and hashed, its
 * conversion on the worker, and the ticket its answer waits on (assets.h). */
#include "daemon/jobs/assets_impl.h"

#include <errno.h>
#include <fcntl.h>
#include <nettle/sha2.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "common/log.h"

/* Under a->lock: may name be written over HTTP? */
bool asset_writable_locked(struct assets *a, const char *name, struct assets_error *e)
{
    if (asset_dir_find(a, name)) {
        asset_refuse(e, ASSETS_READ_ONLY, "name",
                     "%s comes from the asset directory (--asset-dir): it cannot "
                     "be replaced or deleted over HTTP", name);
        return false;
    }
    return true;
}

struct asset_upload *assets_upload_begin(struct assets *a, const char *name,
                                         uint64_t content_length, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        asset_refuse(e, ASSETS_INVALID, "name",
                     "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                     "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    if (content_length > a->cfg.max_asset_bytes) {
        asset_refuse(e, ASSETS_TOO_LARGE, "body",
                     "an asset must be at most %llu bytes (--max-asset-bytes); "
                     "this one is %llu", (unsigned long long)a->cfg.max_asset_bytes,
                     (unsigned long long)content_length);
        return NULL;
    }
    if (!store_has_room(a->store)) {
        asset_refuse(e, ASSETS_NO_SPACE, "state_dir",
                     "the disk of %s is full (%s): no asset is accepted until "
                     "there is room", a->state_dir, strerror(ENOSPC));
        return NULL;
    }
    struct statvfs vfs;
    if (statvfs(a->dir, &vfs) == 0) {
        uint64_t avail = (uint64_t)vfs.f_bavail * vfs.f_frsize;
        uint64_t need = (content_length ? content_length : 0) + ASSETS_HEADROOM;
        if (avail < need) {
            asset_refuse(e, ASSETS_NO_SPACE, "state_dir",
                         "%s has %llu bytes free; this upload needs %llu "
                         "(its size and %llu MiB kept for jobs)", a->state_dir,
                         (unsigned long long)avail, (unsigned long long)need,
                         (unsigned long long)(ASSETS_HEADROOM >> 20));
            return NULL;
        }
    }
    struct asset_upload *u = calloc(1, sizeof(*u));
    if (!u) {
        asset_refuse(e, ASSETS_INTERNAL, "body", "out of memory");
        return NULL;
    }
    pthread_mutex_lock(&a->lock);
    bool ok = asset_writable_locked(a, name, e);
    if (ok && a->stopping) {
        asset_refuse(e, ASSETS_STOPPING, "body", "the daemon is stopping");
        ok = false;
    }
    if (ok && a->uploads >= ASSETS_MAX_UPLOADS) {
        asset_refuse(e, ASSETS_BUSY, "body",
                     "%d uploads are streaming or converting already; retry later",
                     ASSETS_MAX_UPLOADS);
        ok = false;
    }
    uint64_t serial = ++a->serial;
    if (ok)
        a->uploads++;
    pthread_mutex_unlock(&a->lock);
    if (!ok) {
        free(u);
        return NULL;
    }
    u->a = a;
    snprintf(u->name, sizeof(u->name), "%s", name);
    snprintf(u->tmp, sizeof(u->tmp), "%.*s/upload-%llu.part", (int)(sizeof(u->tmp) - 40), a->dir,
             (unsigned long long)serial);
    u->fd = open(u->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (u->fd < 0) {
        int saved = errno;
        asset_refuse(e, saved == ENOSPC || saved == EDQUOT ? ASSETS_NO_SPACE : ASSETS_INTERNAL,
                     "state_dir", "cannot create %s: %s", u->tmp, strerror(saved));
        pthread_mutex_lock(&a->lock);
        a->uploads--;
        pthread_mutex_unlock(&a->lock);
        free(u);
        return NULL;
    }
    sha256_init(&u->sha);
    return u;
}

void assets_upload_write(struct asset_upload *u, const void *data, size_t len)
{
    if (u->too_large || u->disk_full || u->io_errno)
        return; /* read and dropped */
    if (u->bytes + len > u->a->cfg.max_asset_bytes) {
        u->too_large = true;
        return;
    }
    for (size_t i = 0; i < len && u->bytes + i < 4; i++)
        u->magic[u->bytes + i] = ((const unsigned char *)data)[i];
    sha256_update(&u->sha, len, data);
    u->bytes += len;
    const char *p = data;
    while (len) {
        ssize_t n = write(u->fd, p, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            if (errno == ENOSPC || errno == EDQUOT)
                u->disk_full = true;
            else
                u->io_errno = errno;
            return;
        }
        p += n;
        len -= (size_t)n;
    }
}

static void upload_free(struct asset_upload *u, bool count_done)
{
    if (u->fd >= 0)
        close(u->fd);
    unlink(u->tmp);
    if (count_done) {
        pthread_mutex_lock(&u->a->lock);
        u->a->uploads--;
        pthread_mutex_unlock(&u->a->lock);
    }
    free(u);
}

void assets_upload_abort(struct asset_upload *u)
{
    if (u)
        upload_free(u, true);
}

uint64_t assets_upload_finish(struct asset_upload *u, struct assets_error *e)
{
    struct assets *a = u->a;
    if (u->too_large) {
        asset_refuse(e, ASSETS_TOO_LARGE, "body",
                     "an asset must be at most %llu bytes (--max-asset-bytes)",
                     (unsigned long long)a->cfg.max_asset_bytes);
        goto refuse;
    }
    if (u->disk_full) {
        asset_refuse(e, ASSETS_NO_SPACE, "state_dir", "cannot store the upload in %s: %s", a->dir,
                     strerror(ENOSPC));
        goto refuse;
    }
    if (u->io_errno) {
        asset_refuse(e, ASSETS_INTERNAL, "state_dir", "cannot store the upload in %s: %s", a->dir,
                     strerror(u->io_errno));
        goto refuse;
    }
    if (u->bytes == 0) {
        asset_refuse(e, ASSETS_INVALID, "body",
                     "the body must be the asset's .glb, .gltf, .hdr or .exr file; it is "
                     "empty");
        goto refuse;
    }
    close(u->fd);
    u->fd = -1;
    struct task *t = calloc(1, sizeof(*t));
    struct ticket *k = calloc(1, sizeof(*k));
    if (!t || !k) {
        free(t);
        free(k);
        asset_refuse(e, ASSETS_INTERNAL, "body", "out of memory");
        goto refuse;
    }
    uint8_t digest[SHA256_DIGEST_SIZE];
    sha256_digest(&u->sha, SHA256_DIGEST_SIZE, digest);
    t->kind = TASK_UPLOAD;
    sha256_hex(digest, t->sha256);
    snprintf(t->name, sizeof(t->name), "%s", u->name);
    snprintf(t->path, sizeof(t->path), "%s", u->tmp);
    /* A binary glTF starts with its magic, a Radiance image with "#?"
     * and an OpenEXR one with 76 2f 31 01 (environment maps); anything
     * else is given to the converter as JSON glTF. */
    snprintf(t->ext, sizeof(t->ext), "%s",
             memcmp(u->magic, "glTF", 4) == 0 ? "glb"
             : memcmp(u->magic, "#?", 2) == 0 ? "hdr"
             : memcmp(u->magic, "\x76\x2f\x31\x01", 4) == 0 ? "exr"
                                                          : "gltf");
    t->size = u->bytes;
    pthread_mutex_lock(&a->lock);
    if (a->stopping) {
        pthread_mutex_unlock(&a->lock);
        free(t);
        free(k);
        asset_refuse(e, ASSETS_STOPPING, "body", "the daemon is stopping");
        goto refuse;
    }
    k->serial = t->ticket = ++a->serial;
    k->next = a->tickets;
    a->tickets = k;
    *a->tasks_tail = t;
    a->tasks_tail = &t->next;
    pthread_cond_signal(&a->work);
    pthread_mutex_unlock(&a->lock);
    free(u); /* the temporary is the task's now; the upload counts until it is converted */
    return k->serial;
refuse:
    upload_free(u, true);
    return 0;
}

/* Takes the answer's record. */
static void finish_ticket(struct assets *a, uint64_t serial, struct assets_answer *answer)
{
    pthread_mutex_lock(&a->lock);
    struct ticket **p = &a->tickets;
    while (*p && (*p)->serial != serial)
        p = &(*p)->next;
    if (*p && !(*p)->dropped) {
        (*p)->done = true;
        (*p)->answer = *answer;
        answer->record = NULL;
    } else if (*p) {
        struct ticket *t = *p;
        *p = t->next;
        free(t);
    }
    pthread_mutex_unlock(&a->lock);
    json_decref(answer->record);
    assets_notify(a);
}

void asset_upload_run(struct assets *a, struct task *t)
{
    struct assets_error e = {0};
    json_t *description = NULL;
    char original[PATH_MAX + 80];
    asset_path(a, t->sha256, t->ext, original, sizeof(original));
    /* The same bytes stored before: the temporary goes, the original stays.
     * Else it is made durable here, on the worker, not on the HTTP thread
     * that received it (an fsync of 256 MiB can take seconds). */
    int fd = -1;
    if (file_exists(original))
        unlink(t->path);
    else if ((fd = open(t->path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW)) < 0 || fsync(fd) != 0 ||
             rename(t->path, original) != 0) {
        int err = errno;
        if (fd >= 0)
            close(fd);
        asset_refuse(&e, err == ENOSPC || err == EDQUOT ? ASSETS_NO_SPACE : ASSETS_INTERNAL,
                     "state_dir", "cannot store the upload as %s: %s", original, strerror(err));
        unlink(t->path);
        goto fail;
    }
    if (fd >= 0)
        close(fd);
    if (!asset_ensure_cache(a, t->sha256, original, &description, &e))
        goto fail;
    bool replaced = false;
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    bool ok = asset_put_record_locked(a, t, description, &replaced, &e);
    if (!ok)
        asset_release_files_locked(a, t->sha256);
    pthread_mutex_unlock(&a->lock);
    if (!ok)
        goto fail_unlocked;
    LOG(LOG_INFO, "assets: %s %s (%s, %llu bytes)", replaced ? "replaced" : "stored", t->name,
        t->sha256, (unsigned long long)t->size);
    struct assets_answer stored = {
        .record = json_pack("{s:s, s:s, s:I, s:s, s:O}", "name", t->name, "sha256", t->sha256,
                            "size", (json_int_t)t->size, "format", t->ext, "description",
                            description),
        .replaced = replaced};
    if (!stored.record)
        asset_refuse(&stored.refusal, ASSETS_INTERNAL, "body", "out of memory");
    finish_ticket(a, t->ticket, &stored);
    json_decref(description);
    return;
fail:
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    asset_release_files_locked(a, t->sha256);
    pthread_mutex_unlock(&a->lock);
fail_unlocked:
    json_decref(description);
    LOG(LOG_INFO, "assets: upload of %s refused: %s: %s", t->name, e.field, e.message);
    finish_ticket(a, t->ticket, &(struct assets_answer){.refusal = e});
}

bool assets_ticket_done(struct assets *a, uint64_t serial)
{
    pthread_mutex_lock(&a->lock);
    bool done = true; /* no such ticket: nothing to wait for */
    for (struct ticket *t = a->tickets; t; t = t->next)
        if (t->serial == serial)
            done = t->done;
    if (a->stopping)
        done = true;
    pthread_mutex_unlock(&a->lock);
    return done;
}

bool assets_ticket_take(struct assets *a, uint64_t serial, struct assets_answer *out)
{
    pthread_mutex_lock(&a->lock);
    struct ticket **p = &a->tickets;
    while (*p && (*p)->serial != serial)
        p = &(*p)->next;
    struct ticket *t = *p && (*p)->done ? *p : NULL;
    if (t)
        *p = t->next;
    pthread_mutex_unlock(&a->lock);
    if (!t)
        return false;
    *out = t->answer;
    free(t);
    return true;
}

void assets_ticket_drop(struct assets *a, uint64_t serial)
{
    pthread_mutex_lock(&a->lock);
    struct ticket **p = &a->tickets;
    while (*p && (*p)->serial != serial)
        p = &(*p)->next;
    if (*p && (*p)->done) {
        struct ticket *t = *p;
        *p = t->next;
        json_decref(t->answer.record);
        free(t);
    } else if (*p) {
        (*p)->dropped = true; /* finish_ticket frees it */
    }
    pthread_mutex_unlock(&a->lock);
}
