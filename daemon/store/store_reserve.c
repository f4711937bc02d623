#define _POSIX_C_SOURCE 200809L
#include "daemon/store/store_reserve.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"

/* A note is one line, "KIND\tID\tSTATUS\tERROR\n"; its error is cut here. */
#define NOTE_ERROR_MAX 400
/* Taking the room back is a system call that fails while the disk is full:
 * asked for by every submission and by the render thread, it runs at most
 * this often. */
#define RETRY_S 1.0

struct store_reserve {
    pthread_mutex_t lock; /* everything below but whole */
    int fd;
    char path[PATH_MAX + 32];
    atomic_bool whole; /* the room is taken */
    atomic_bool full;  /* the last look found no room (store_reserve_ready) */
    double last_try;
    /* The notes block as it is on disk: an earlier run's notes, not yet
     * applied, then this run's. */
    char found[STORE_RESERVE_NOTES_BYTES];
    char notes[STORE_RESERVE_NOTES_BYTES];
};

/* Under the lock: the notes block, rewritten in place and synced. Writing
 * into blocks the file already has needs no free space. */
static bool write_notes_locked(struct store_reserve *r)
{
    char block[STORE_RESERVE_NOTES_BYTES] = {0};
    size_t f = strlen(r->found), n = strlen(r->notes);
    if (f + n >= sizeof(block))
        return false;
    memcpy(block, r->found, f);
    memcpy(block + f, r->notes, n);
    if (pwrite(r->fd, block, sizeof(block), 0) != (ssize_t)sizeof(block) || fdatasync(r->fd) != 0) {
        LOG(LOG_ERROR, "store: cannot write the notes in %s: %s", r->path, strerror(errno));
        return false;
    }
    return true;
}

/* Under the lock: takes the room; false (and nothing held beyond the notes
 * block) when the disk has not got it. */
static bool take_locked(struct store_reserve *r)
{
    int rc = posix_fallocate(r->fd, 0, STORE_RESERVE_BYTES);
    if (rc == 0)
        return true;
    if (ftruncate(r->fd, STORE_RESERVE_NOTES_BYTES) != 0)
        LOG(LOG_WARN, "store: cannot truncate %s: %s", r->path, strerror(errno));
    errno = rc;
    return false;
}

struct store_reserve *store_reserve_open(const char *state_dir)
{
    struct store_reserve *r = calloc(1, sizeof(*r));
    if (!r)
        return NULL;
    snprintf(r->path, sizeof(r->path), "%s/%s", state_dir, STORE_RESERVE_FILE);
    r->fd = open(r->path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (r->fd < 0) {
        LOG(LOG_ERROR, "store: cannot open %s: %s; a full disk may then leave a job's end "
            "unrecorded", r->path, strerror(errno));
        free(r);
        return NULL;
    }
    pthread_mutex_init(&r->lock, NULL);
    ssize_t got = pread(r->fd, r->found, sizeof(r->found) - 1, 0);
    r->found[got > 0 ? got : 0] = '\0'; /* the notes end at the block's zero padding */
    if (r->found[0])
        LOG(LOG_WARN, "store: %s holds states the last run could not store (the disk was full)",
            r->path);
    bool whole = take_locked(r);
    if (!whole)
        LOG(LOG_ERROR, "store: cannot keep %d bytes in reserve in %s: %s; no job starts and "
            "none is accepted until there is room", STORE_RESERVE_BYTES, r->path, strerror(errno));
    atomic_init(&r->whole, whole);
    atomic_init(&r->full, false);
    r->last_try = clock_mono_s();
    return r;
}

void store_reserve_close(struct store_reserve *r)
{
    if (!r)
        return;
    close(r->fd);
    pthread_mutex_destroy(&r->lock);
    free(r);
}

/* Under the lock: removes the lines of kind/id from text. */
static void remove_note(char *text, int kind, const char *id)
{
    char prefix[64];
    int n = snprintf(prefix, sizeof(prefix), "%d\t%s\t", kind, id);
    char *line = text;
    while (*line) {
        char *end = strchr(line, '\n');
        end = end ? end + 1 : line + strlen(line);
        if (strncmp(line, prefix, (size_t)n) == 0)
            memmove(line, end, strlen(end) + 1);
        else
            line = end;
    }
}

bool store_reserve_note(struct store_reserve *r, int kind, const char *id, const char *status,
                        const char *error)
{
    if (!r)
        return false;
    /* One line of four fields: the error's own tabs and newlines go. */
    char clean[NOTE_ERROR_MAX + 1], line[NOTE_ERROR_MAX + 128];
    snprintf(clean, sizeof(clean), "%s", error ? error : "");
    for (char *p = clean; *p; p++)
        if (*p == '\n' || *p == '\r' || *p == '\t')
            *p = ' ';
    int n = snprintf(line, sizeof(line), "%d\t%.40s\t%.24s\t%s\n", kind, id, status, clean);
    pthread_mutex_lock(&r->lock);
    remove_note(r->notes, kind, id);
    size_t used = strlen(r->notes);
    bool ok = used + strlen(r->found) + (size_t)n + 1 < STORE_RESERVE_NOTES_BYTES;
    if (ok) {
        memcpy(r->notes + used, line, (size_t)n + 1);
        ok = write_notes_locked(r);
    } else {
        LOG(LOG_ERROR, "store: no room left in %s's notes for %s", r->path, id);
    }
    pthread_mutex_unlock(&r->lock);
    return ok;
}

void store_reserve_unnote(struct store_reserve *r, int kind, const char *id)
{
    if (!r)
        return;
    pthread_mutex_lock(&r->lock);
    size_t before = strlen(r->notes);
    remove_note(r->notes, kind, id);
    if (strlen(r->notes) != before)
        write_notes_locked(r);
    pthread_mutex_unlock(&r->lock);
}

bool store_reserve_release(struct store_reserve *r)
{
    if (!r || !atomic_load(&r->whole))
        return false;
    pthread_mutex_lock(&r->lock);
    bool released = atomic_load(&r->whole) && ftruncate(r->fd, STORE_RESERVE_NOTES_BYTES) == 0;
    if (released) {
        atomic_store(&r->whole, false);
        r->last_try = clock_mono_s();
    }
    pthread_mutex_unlock(&r->lock);
    return released;
}

/* Free space beside the reserve, as an unprivileged writer sees it. */
static bool disk_has_room(int fd)
{
    struct statvfs v;
    return fstatvfs(fd, &v) != 0 ||
           (unsigned long long)v.f_bavail * v.f_frsize >= (unsigned long long)STORE_RESERVE_HEADROOM;
}

bool store_reserve_ready(struct store_reserve *r)
{
    if (!r)
        return true; /* no reserve to wait for */
    /* The room alone is not enough: taken back from a disk that had just
     * that much free (a restart after the reserve was released), it would
     * start a job into a disk with nothing left. */
    bool room = atomic_load(&r->whole) && disk_has_room(r->fd);
    if (!room && !atomic_load(&r->whole)) {
        pthread_mutex_lock(&r->lock);
        double now = clock_mono_s();
        if (!atomic_load(&r->whole) && now - r->last_try >= RETRY_S) {
            r->last_try = now;
            if (take_locked(r))
                atomic_store(&r->whole, true);
        }
        pthread_mutex_unlock(&r->lock);
        room = atomic_load(&r->whole) && disk_has_room(r->fd);
    }
    if (atomic_exchange(&r->full, !room) != !room)
        LOG(room ? LOG_INFO : LOG_ERROR, "store: %s", room ? "there is room again on the disk of "
            "the state directory: jobs start and are accepted again" : "the disk of the state "
            "directory is full: no job starts and none is accepted until there is room");
    return room;
}

bool store_reserve_released(struct store_reserve *r)
{
    return r && (!atomic_load(&r->whole) || atomic_load(&r->full));
}

bool store_reserve_found(const struct store_reserve *r, int kind, const char *id, char *status,
                         size_t status_cap, char *error, size_t error_cap)
{
    if (!r)
        return false;
    char prefix[64];
    int n = snprintf(prefix, sizeof(prefix), "%d\t%s\t", kind, id);
    const char *hit = NULL;
    for (const char *line = r->found; *line;) {
        if (strncmp(line, prefix, (size_t)n) == 0)
            hit = line + n; /* the newest wins */
        const char *end = strchr(line, '\n');
        line = end ? end + 1 : line + strlen(line);
    }
    if (!hit)
        return false;
    const char *tab = strchr(hit, '\t');
    const char *end = strchr(hit, '\n');
    if (!end)
        end = hit + strlen(hit);
    if (!tab || tab > end)
        tab = end;
    snprintf(status, status_cap, "%.*s", (int)(tab - hit), hit);
    snprintf(error, error_cap, "%.*s", tab < end ? (int)(end - tab - 1) : 0, tab < end ? tab + 1 : "");
    return true;
}

void store_reserve_found_done(struct store_reserve *r)
{
    if (!r)
        return;
    pthread_mutex_lock(&r->lock);
    if (r->found[0]) {
        r->found[0] = '\0';
        write_notes_locked(r);
    }
    pthread_mutex_unlock(&r->lock);
}
