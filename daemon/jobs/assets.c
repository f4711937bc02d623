/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
#include "daemon/jobs/assets.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <nettle/sha2.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/fsutil.h"
#include "common/log.h"
#include "daemon/scene/environment.h"

/* Free space an upload must leave beside itself, as the store's reserve
 * asks for jobs (store_reserve.h): an asset never takes the room a job's
 * result needs. */
#define ASSETS_HEADROOM (64ull << 20)

enum task_kind { TASK_UPLOAD, TASK_DIR };

/* One conversion to do, on the worker. */
struct task {
    enum task_kind kind;
    char name[STORE_ASSET_NAME_CAP];
    char path[PATH_MAX]; /* TASK_UPLOAD: the temporary file; TASK_DIR: the file in the dir */
    char sha256[65];     /* TASK_UPLOAD: known; TASK_DIR: hashed on the worker */
    char ext[8];
    uint64_t size;
    uint64_t ticket; /* 0: nobody waits (TASK_DIR) */
    struct task *next;
};

struct ticket {
    uint64_t serial;
    bool done, dropped;
    unsigned status;
    json_t *body;
    struct ticket *next;
};

enum dir_state { DIR_PENDING, DIR_READY, DIR_FAILED };
struct dir_entry {
    char name[STORE_ASSET_NAME_CAP];
    enum dir_state state;
    char error[512];
};

struct asset_upload {
    struct assets *a;
    char name[STORE_ASSET_NAME_CAP];
    char tmp[PATH_MAX];
    int fd;
    struct sha256_ctx sha;
    uint64_t bytes;
    unsigned char magic[4];
    bool too_large, disk_full;
    int io_errno;
};

struct assets {
    struct assets_config cfg;
    char state_dir[PATH_MAX], asset_dir[PATH_MAX], asset_dir_real[PATH_MAX];
    char converter[PATH_MAX], dir[PATH_MAX]; /* dir: STATE_DIR/assets */
    struct store *store;
    struct queue *queue;
    /* Guards everything below. Record changes (an upload's row, a delete)
     * hold it across their store write so that a delete and a replace of
     * one name, or the files of one hash, never interleave; never held
     * while converting. */
    pthread_mutex_t lock;
    pthread_cond_t work;
    struct task *tasks, **tasks_tail;
    struct ticket *tickets;
    uint64_t serial;
    unsigned uploads; /* streaming or waiting to convert: at most ASSETS_MAX_UPLOADS */
    char busy_sha[65]; /* the hash the worker is converting: its files stay */
    pid_t child;       /* the converter running, or 0 */
    bool stopping;
    struct dir_entry *dir_entries;
    size_t ndir;
    void (*listener)(void *ctx);
    void *listener_ctx;
    pthread_t workers[ASSETS_WORKERS];
    int nworkers;
};

static void set_error(struct assets_error *e, unsigned status, const char *field, const char *fmt,
                      ...) __attribute__((format(printf, 4, 5)));
static void set_error(struct assets_error *e, unsigned status, const char *field, const char *fmt,
                      ...)
{
    e->status = status;
    snprintf(e->field, sizeof(e->field), "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->message, sizeof(e->message), fmt, ap);
    va_end(ap);
}

static json_t *error_json(const char *field, const char *message)
{
    return json_pack("{s:{s:s, s:s}}", "error", "field", field, "message", message);
}

static void hex(const uint8_t digest[SHA256_DIGEST_SIZE], char out[65])
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++) {
        out[2 * i] = digits[digest[i] >> 4];
        out[2 * i + 1] = digits[digest[i] & 15];
    }
    out[64] = '\0';
}

static void asset_url(const char *name, char *out, size_t cap)
{
    snprintf(out, cap, "/v1/assets/%s", name);
}

static struct dir_entry *dir_find(struct assets *a, const char *name)
{
    for (size_t i = 0; i < a->ndir; i++)
        if (strcmp(a->dir_entries[i].name, name) == 0)
            return &a->dir_entries[i];
    return NULL;
}

static void notify(struct assets *a)
{
    if (a->listener)
        a->listener(a->listener_ctx);
}

/* ---- files ---- */

static void path_of(const struct assets *a, const char *sha, const char *ext, char *out,
                    size_t cap)
{
    snprintf(out, cap, "%s/%s.%s", a->dir, sha, ext);
}

static bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* Under a->lock: the files of a hash no name points at, no conversion is
 * working on and no queued or running job is pinned to. */
static void release_files_locked(struct assets *a, const char *sha)
{
    if (!asset_store_sha256_valid(sha) || strcmp(a->busy_sha, sha) == 0)
        return;
    for (struct task *t = a->tasks; t; t = t->next)
        if (strcmp(t->sha256, sha) == 0)
            return;
    char job[RECORD_ID_LEN];
    if (store_asset_hash_refs(a->store, sha) != 0 || queue_asset_in_use(a->queue, NULL, sha, job))
        return;
    static const char *const exts[] = {"glb", "gltf", "hdr", ASSET_CACHE_EXT, "json"};
    for (size_t i = 0; i < sizeof(exts) / sizeof(exts[0]); i++) {
        char path[PATH_MAX + 80];
        path_of(a, sha, exts[i], path, sizeof(path));
        if (unlink(path) != 0 && errno != ENOENT)
            LOG(LOG_WARN, "assets: cannot remove %s: %s", path, strerror(errno));
    }
}

/* ---- the converter ---- */

struct conversion {
    enum { CONV_OK, CONV_BAD, CONV_FAILED } outcome;
    json_t *out;       /* stdout's JSON object, when it is one */
    char why[256];     /* CONV_FAILED: how it ended */
};

static void add_arg(char **argv, int *argc, char (*store)[32], const char *flag, uint64_t v)
{
    argv[(*argc)++] = (char *)flag;
    snprintf(store[*argc], sizeof(store[0]), "%llu", (unsigned long long)v);
    argv[*argc] = store[*argc];
    (*argc)++;
}

/* Runs `converter convert IN OUT --limits...` and reads its stdout. The
 * child gets the limits as flags (the converter checks them as it reads)
 * and as rlimits set before exec (a converter that ignores them is still
 * bounded), a process group of its own (so the time-out kills what it
 * started), nice 10 (so the render thread keeps its core) and no file
 * descriptor of the daemon's but stdin (/dev/null), stdout (the pipe) and
 * stderr (the log). */
static void convert(struct assets *a, const char *in, const char *out, struct conversion *c)
{
    memset(c, 0, sizeof(*c));
    c->outcome = CONV_FAILED;
    char *argv[32];
    char nums[32][32];
    int argc = 0;
    argv[argc++] = a->converter;
    argv[argc++] = "convert";
    argv[argc++] = (char *)in;
    argv[argc++] = (char *)out;
    const struct asset_limits *l = &a->cfg.limits;
    add_arg(argv, &argc, nums, "--max-file-bytes", l->max_file_bytes);
    add_arg(argv, &argc, nums, "--max-vertices", l->max_vertices);
    add_arg(argv, &argc, nums, "--max-indices", l->max_indices);
    add_arg(argv, &argc, nums, "--max-texture-pixels", l->max_texture_pixels);
    add_arg(argv, &argc, nums, "--max-texture-edge", l->max_texture_edge);
    if (a->cfg.run.memory_bytes)
        add_arg(argv, &argc, nums, "--max-memory", a->cfg.run.memory_bytes);
    add_arg(argv, &argc, nums, "--max-cpu-seconds", a->cfg.run.cpu_s);
    argv[argc] = NULL;

    int pipefd[2] = {-1, -1}, devnull = -1;
    char *text = NULL;
    size_t len = 0;
    if (pipe2(pipefd, O_CLOEXEC) != 0 || (devnull = open("/dev/null", O_RDONLY | O_CLOEXEC)) < 0) {
        snprintf(c->why, sizeof(c->why), "cannot start it: %s", strerror(errno));
        goto out;
    }
    struct rlimit mem = {a->cfg.run.memory_bytes, a->cfg.run.memory_bytes};
    struct rlimit cpu = {a->cfg.run.cpu_s, a->cfg.run.cpu_s + 5};
    sigset_t none;
    sigemptyset(&none);
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(c->why, sizeof(c->why), "cannot start it: %s", strerror(errno));
        goto out;
    }
    if (pid == 0) {
        /* The child of a threaded process: async-signal-safe calls only. */
        setpgid(0, 0);
        struct sigaction dfl = {.sa_handler = SIG_DFL};
        sigaction(SIGPIPE, &dfl, NULL); /* the daemon ignores it */
        sigprocmask(SIG_SETMASK, &none, NULL); /* and blocks SIGTERM for sigwait */
        if (dup2(devnull, 0) < 0 || dup2(pipefd[1], 1) < 0)
            _exit(127);
        closefrom(3);
        if (mem.rlim_cur)
            setrlimit(RLIMIT_AS, &mem);
        setrlimit(RLIMIT_CPU, &cpu);
        setpriority(PRIO_PROCESS, 0, 10);
        execv(argv[0], argv);
        _exit(127);
    }
    /* Its own process group from the parent's side too: whichever of the
     * two runs first, a kill of -pid after this reaches it. */
    setpgid(pid, pid);
    close(pipefd[1]);
    pipefd[1] = -1;
    pthread_mutex_lock(&a->lock);
    a->child = pid;
    bool stopping = a->stopping;
    pthread_mutex_unlock(&a->lock);

    double deadline = clock_mono_s() + a->cfg.run.wall_s;
    bool timed_out = false, eof = false;
    text = malloc(ASSETS_MAX_STDOUT + 1);
    while (!eof && !stopping) {
        double left = deadline - clock_mono_s();
        if (left <= 0) {
            timed_out = true;
            break;
        }
        /* In slices, so that a daemon stopping (assets_destroy) is not held
         * up by a converter that still has minutes of its time left. */
        struct pollfd p = {.fd = pipefd[0], .events = POLLIN};
        int n = poll(&p, 1, left > 0.25 ? 250 : (int)(left * 1000) + 1);
        pthread_mutex_lock(&a->lock);
        stopping = a->stopping;
        pthread_mutex_unlock(&a->lock);
        if (n < 0 && errno != EINTR)
            break;
        if (n <= 0)
            continue;
        char buf[16384];
        ssize_t got = read(pipefd[0], buf, sizeof(buf));
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0) {
            eof = true;
            break;
        }
        /* Beyond the cap the rest is read and dropped, so the child never
         * blocks on a full pipe. */
        size_t take = text && len < ASSETS_MAX_STDOUT ? (size_t)got : 0;
        if (take > ASSETS_MAX_STDOUT - len)
            take = ASSETS_MAX_STDOUT - len;
        if (take)
            memcpy(text + len, buf, take), len += take;
    }
    /* It closed stdout; it may still be running (or hung). */
    int status = 0;
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR) {
            status = 0;
            break;
        }
        if (stopping || timed_out || clock_mono_s() >= deadline) {
            timed_out = !stopping;
            kill(-pid, SIGKILL);
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            break;
        }
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    pthread_mutex_lock(&a->lock);
    a->child = 0;
    pthread_mutex_unlock(&a->lock);
    if (text)
        text[len] = '\0';
    json_t *j = text && len ? json_loadb(text, len, 0, NULL) : NULL;
    if (j && !json_is_object(j)) {
        json_decref(j);
        j = NULL;
    }
    if (stopping && !timed_out && !WIFEXITED(status)) {
        snprintf(c->why, sizeof(c->why), "the daemon stopped while it ran");
        json_decref(j);
    } else if (timed_out) {
        snprintf(c->why, sizeof(c->why), "it took longer than %g s and was stopped",
                 a->cfg.run.wall_s);
        json_decref(j);
    } else if (WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        snprintf(c->why, sizeof(c->why), "signal %d%s", sig,
                 sig == SIGXCPU || sig == SIGKILL ? ", over its CPU time limit" : "");
        json_decref(j);
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && j) {
        c->outcome = CONV_OK;
        c->out = j;
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 2 && j) {
        c->outcome = CONV_BAD;
        c->out = j;
    } else {
        json_decref(j);
        if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
            snprintf(c->why, sizeof(c->why), "exit 127: %.200s could not be run", a->converter);
        else if (WIFEXITED(status))
            snprintf(c->why, sizeof(c->why), "exit %d%s", WEXITSTATUS(status),
                     WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 2
                         ? ", without a JSON object on stdout"
                         : "");
        else
            snprintf(c->why, sizeof(c->why), "status %d", status);
    }
out:
    free(text);
    if (pipefd[0] >= 0)
        close(pipefd[0]);
    if (pipefd[1] >= 0)
        close(pipefd[1]);
    if (devnull >= 0)
        close(devnull);
}

/* The cache and description of sha, converting in when they are not there
 * yet (an identical file converted before costs nothing). On success
 * *description is a new reference; else *status and e say why. */
static bool ensure_cache(struct assets *a, const char *sha, const char *in, json_t **description,
                         struct assets_error *e)
{
    char cache[PATH_MAX + 80], desc[PATH_MAX + 80], tmp[PATH_MAX + 120];
    path_of(a, sha, ASSET_CACHE_EXT, cache, sizeof(cache));
    path_of(a, sha, "json", desc, sizeof(desc));
    /* A cache an older shadebench wrote (another layout) is converted anew. */
    if (asset_file_is_current(cache) && (*description = json_load_file(desc, 0, NULL)))
        return true;
    snprintf(tmp, sizeof(tmp), "%s/convert-%s.%s", a->dir, sha, ASSET_CACHE_EXT);
    unlink(tmp);
    struct conversion c;
    double t0 = clock_mono_s();
    convert(a, in, tmp, &c);
    LOG(LOG_INFO, "assets: converted %s in %.2f s: %s", in, clock_mono_s() - t0,
        c.outcome == CONV_OK ? "ok" : c.outcome == CONV_BAD ? "refused" : c.why);
    if (c.outcome == CONV_BAD) {
        json_int_t st = json_integer_value(json_object_get(c.out, "status"));
        const char *field = json_string_value(json_object_get(c.out, "field"));
        const char *message = json_string_value(json_object_get(c.out, "message"));
        set_error(e, st == 400 ? 400 : 422, field ? field : "body", "%s",
                  message ? message : "the converter refused the asset");
        json_decref(c.out);
        unlink(tmp);
        return false;
    }
    if (c.outcome == CONV_FAILED) {
        set_error(e, 422, "body", "the asset loader failed on this file (%s)", c.why);
        unlink(tmp);
        return false;
    }
    if (!exists(tmp) || rename(tmp, cache) != 0) {
        set_error(e, 422, "body", "the asset loader said it succeeded but wrote no cache file");
        json_decref(c.out);
        unlink(tmp);
        return false;
    }
    if (!fs_write_json_atomic(desc, c.out)) {
        set_error(e, 507, "state_dir", "cannot write %s: %s", desc, strerror(errno));
        json_decref(c.out);
        unlink(cache);
        return false;
    }
    *description = c.out;
    return true;
}

static json_t *record_json(const struct store_asset *r, bool full)
{
    char url[STORE_ASSET_NAME_CAP + 16];
    asset_url(r->name, url, sizeof(url));
    json_t *o = json_pack("{s:s, s:s, s:I, s:s, s:f, s:f, s:s, s:b, s:s}", "name", r->name,
                          "sha256", r->sha256, "size", (json_int_t)r->size, "format", r->ext,
                          "created", r->created, "updated", r->updated, "source",
                          r->from_dir ? "asset-dir" : "upload", "read_only", r->from_dir, "url",
                          url);
    if (!o)
        return NULL;
    if (full) {
        json_object_set(o, "description", r->description ? r->description : json_null());
        return o;
    }
    /* A list shows counts only: the description's arrays as their sizes,
     * its numbers as they are. */
    json_t *summary = json_object();
    static const char *const keys[] = {"meshes", "triangles", "vertices", "materials",
                                       "textures", "images", "lights", "cameras",
                                       "kind", "width", "height"};
    for (size_t i = 0; summary && i < sizeof(keys) / sizeof(keys[0]); i++) {
        json_t *v = json_object_get(r->description, keys[i]);
        if (json_is_array(v))
            json_object_set_new(summary, keys[i], json_integer((json_int_t)json_array_size(v)));
        else if (json_is_object(v) && json_is_integer(json_object_get(v, "count")))
            json_object_set(summary, keys[i], json_object_get(v, "count"));
        else if (json_is_number(v) || json_is_string(v))
            json_object_set(summary, keys[i], v);
    }
    json_object_set_new(o, "summary", summary ? summary : json_null());
    return o;
}

/* Under a->lock: the record of name now points at sha. The files of the
 * hash it pointed at before go when nothing else needs them. *replaced:
 * the name had a record. */
static bool put_record_locked(struct assets *a, const struct task *t, const json_t *description,
                              bool *replaced, struct assets_error *e)
{
    struct store_asset old;
    enum store_found f = store_asset_get(a->store, t->name, &old);
    if (f == STORE_ERROR) {
        set_error(e, 500, "store", "cannot read the asset records (see the log)");
        return false;
    }
    *replaced = f == STORE_FOUND;
    if (f == STORE_FOUND && old.from_dir && t->kind == TASK_UPLOAD) {
        store_asset_finish(&old);
        set_error(e, 403, "name", "%s comes from the asset directory (--asset-dir): it cannot "
                  "be replaced over HTTP", t->name);
        return false;
    }
    struct store_asset r = {.size = t->size, .from_dir = t->kind == TASK_DIR,
                            .description = (json_t *)description};
    snprintf(r.name, sizeof(r.name), "%s", t->name);
    snprintf(r.sha256, sizeof(r.sha256), "%s", t->sha256);
    snprintf(r.ext, sizeof(r.ext), "%s", t->ext);
    r.created = r.updated = clock_unix_s();
    char err[PATH_MAX + 300];
    bool ok = store_asset_put(a->store, &r, err, sizeof(err));
    if (!ok) {
        LOG(LOG_ERROR, "assets: %s", err);
        set_error(e, strstr(err, "full") || strstr(err, "No space") ? 507 : 500, "state_dir",
                  "%.480s", err);
    } else if (f == STORE_FOUND && strcmp(old.sha256, t->sha256) != 0) {
        release_files_locked(a, old.sha256);
    }
    store_asset_finish(&old);
    return ok;
}

/* ---- the worker ---- */

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
    hex(digest, sha);
    return true;
}

static void finish_ticket(struct assets *a, uint64_t serial, unsigned status, json_t *body)
{
    pthread_mutex_lock(&a->lock);
    struct ticket **p = &a->tickets;
    while (*p && (*p)->serial != serial)
        p = &(*p)->next;
    if (*p && !(*p)->dropped) {
        (*p)->done = true;
        (*p)->status = status;
        (*p)->body = body;
        body = NULL;
    } else if (*p) {
        struct ticket *t = *p;
        *p = t->next;
        free(t);
    }
    pthread_mutex_unlock(&a->lock);
    json_decref(body);
    notify(a);
}

static void run_upload(struct assets *a, struct task *t)
{
    struct assets_error e = {0};
    json_t *description = NULL;
    char original[PATH_MAX + 80];
    path_of(a, t->sha256, t->ext, original, sizeof(original));
    /* The same bytes stored before: the temporary goes, the original stays.
     * Else it is made durable here, on the worker, not on the HTTP thread
     * that received it (an fsync of 256 MiB can take seconds). */
    int fd = -1;
    if (exists(original))
        unlink(t->path);
    else if ((fd = open(t->path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW)) < 0 || fsync(fd) != 0 ||
             rename(t->path, original) != 0) {
        int err = errno;
        if (fd >= 0)
            close(fd);
        set_error(&e, err == ENOSPC || err == EDQUOT ? 507 : 500, "state_dir",
                  "cannot store the upload as %s: %s", original, strerror(err));
        unlink(t->path);
        goto fail;
    }
    if (fd >= 0)
        close(fd);
    if (!ensure_cache(a, t->sha256, original, &description, &e))
        goto fail;
    bool replaced = false;
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    bool ok = put_record_locked(a, t, description, &replaced, &e);
    if (!ok)
        release_files_locked(a, t->sha256);
    pthread_mutex_unlock(&a->lock);
    if (!ok)
        goto fail_unlocked;
    char url[STORE_ASSET_NAME_CAP + 16];
    asset_url(t->name, url, sizeof(url));
    LOG(LOG_INFO, "assets: %s %s (%s, %llu bytes)", replaced ? "replaced" : "stored", t->name,
        t->sha256, (unsigned long long)t->size);
    finish_ticket(a, t->ticket, replaced ? 200 : 201,
                  json_pack("{s:s, s:s, s:I, s:s, s:O, s:s}", "name", t->name, "sha256",
                            t->sha256, "size", (json_int_t)t->size, "format", t->ext,
                            "description", description, "url", url));
    json_decref(description);
    return;
fail:
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    release_files_locked(a, t->sha256);
    pthread_mutex_unlock(&a->lock);
fail_unlocked:
    json_decref(description);
    LOG(LOG_INFO, "assets: upload of %s refused: %d %s: %s", t->name, e.status, e.field,
        e.message);
    finish_ticket(a, t->ticket, e.status, error_json(e.field, e.message));
}

static void set_dir_state(struct assets *a, const char *name, enum dir_state st, const char *why)
{
    pthread_mutex_lock(&a->lock);
    struct dir_entry *d = dir_find(a, name);
    if (d) {
        d->state = st;
        snprintf(d->error, sizeof(d->error), "%s", why ? why : "");
    }
    pthread_mutex_unlock(&a->lock);
}

static void run_dir(struct assets *a, struct task *t)
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
    bool ok = ensure_cache(a, t->sha256, t->path, &description, &e);
    pthread_mutex_lock(&a->lock);
    a->busy_sha[0] = '\0';
    bool replaced;
    if (ok)
        ok = put_record_locked(a, t, description, &replaced, &e);
    if (!ok) {
        /* The file changed and no longer converts: its old record would
         * name bytes the folder no longer has. */
        struct store_asset old;
        if (store_asset_get(a->store, t->name, &old) == STORE_FOUND && old.from_dir) {
            char err[PATH_MAX + 300];
            if (store_asset_delete(a->store, t->name, err, sizeof(err)))
                release_files_locked(a, old.sha256);
        }
        store_asset_finish(&old);
        release_files_locked(a, t->sha256);
    }
    pthread_mutex_unlock(&a->lock);
    json_decref(description);
    if (ok) {
        set_dir_state(a, t->name, DIR_READY, NULL);
        return;
    }
    char msg[512]; /* dir_entry.error's size */
    snprintf(msg, sizeof(msg), "%u %.40s: %.440s", e.status, e.field, e.message);
    LOG(LOG_WARN, "assets: --asset-dir %s: %s", t->path, msg);
    set_dir_state(a, t->name, DIR_FAILED, msg);
}

static void *worker(void *arg)
{
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
            run_upload(a, t);
        else
            run_dir(a, t);
        pthread_mutex_lock(&a->lock);
        if (t->kind == TASK_UPLOAD)
            a->uploads--;
        free(t);
    }
    pthread_mutex_unlock(&a->lock);
    return NULL;
}

/* ---- start-up ---- */

/* Temporaries of a run that stopped (uploads, conversions), and files of
 * hashes no name points at (a crash between a delete's row and its
 * files). */
static void sweep_state_dir(struct assets *a)
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
            unlink(path);
            continue;
        }
        char sha[65];
        if (strlen(n) > 65 && n[64] == '.') {
            memcpy(sha, n, 64);
            sha[64] = '\0';
            release_files_locked(a, sha); /* no other thread yet */
        }
    }
    closedir(d);
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
    return false;
}

static void collect_dir_row(void *ctx, const struct store_asset *r)
{
    json_array_append_new(ctx, json_string(r->name));
}

/* The folder's .glb and .gltf files: each a task for the worker. A link
 * is followed only when it stays inside the folder. */
static bool scan_asset_dir(struct assets *a, char *err, size_t errlen)
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
static void drop_gone_dir_rows(struct assets *a)
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
        if (dir_find(a, name))
            continue;
        struct store_asset old;
        if (store_asset_get(a->store, name, &old) == STORE_FOUND &&
            store_asset_delete(a->store, name, err, sizeof(err))) {
            LOG(LOG_INFO, "assets: %s left --asset-dir: its record goes", name);
            release_files_locked(a, old.sha256);
        }
        store_asset_finish(&old);
    }
    json_decref(names);
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
    sweep_state_dir(a);
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
    if (a->child > 0) {
        kill(-a->child, SIGKILL);
        kill(a->child, SIGKILL);
    }
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
        json_decref(t->body);
        free(t);
    }
    free(a->dir_entries);
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

/* ---- uploads ---- */

/* Under a->lock: may name be written over HTTP? */
static bool writable_locked(struct assets *a, const char *name, struct assets_error *e)
{
    if (dir_find(a, name)) {
        set_error(e, 403, "name", "%s comes from the asset directory (--asset-dir): it cannot "
                  "be replaced or deleted over HTTP", name);
        return false;
    }
    return true;
}

struct asset_upload *assets_upload_begin(struct assets *a, const char *name,
                                         uint64_t content_length, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        set_error(e, 400, "name", "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                  "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    if (content_length > a->cfg.max_asset_bytes) {
        set_error(e, 413, "body", "an asset must be at most %llu bytes (--max-asset-bytes); "
                  "this one is %llu", (unsigned long long)a->cfg.max_asset_bytes,
                  (unsigned long long)content_length);
        return NULL;
    }
    if (!store_has_room(a->store)) {
        set_error(e, 507, "state_dir", "the disk of %s is full (%s): no asset is accepted until "
                  "there is room", a->state_dir, strerror(ENOSPC));
        return NULL;
    }
    struct statvfs vfs;
    if (statvfs(a->dir, &vfs) == 0) {
        uint64_t avail = (uint64_t)vfs.f_bavail * vfs.f_frsize;
        uint64_t need = (content_length ? content_length : 0) + ASSETS_HEADROOM;
        if (avail < need) {
            set_error(e, 507, "state_dir", "%s has %llu bytes free; this upload needs %llu "
                      "(its size and %llu MiB kept for jobs)", a->state_dir,
                      (unsigned long long)avail, (unsigned long long)need,
                      (unsigned long long)(ASSETS_HEADROOM >> 20));
            return NULL;
        }
    }
    struct asset_upload *u = calloc(1, sizeof(*u));
    if (!u) {
        set_error(e, 500, "body", "out of memory");
        return NULL;
    }
    pthread_mutex_lock(&a->lock);
    bool ok = writable_locked(a, name, e);
    if (ok && a->stopping) {
        set_error(e, 503, "body", "the daemon is stopping");
        ok = false;
    }
    if (ok && a->uploads >= ASSETS_MAX_UPLOADS) {
        set_error(e, 429, "body", "%d uploads are streaming or converting already; retry later",
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
        set_error(e, saved == ENOSPC || saved == EDQUOT ? 507 : 500, "state_dir",
                  "cannot create %s: %s", u->tmp, strerror(saved));
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
        set_error(e, 413, "body", "an asset must be at most %llu bytes (--max-asset-bytes)",
                  (unsigned long long)a->cfg.max_asset_bytes);
        goto refuse;
    }
    if (u->disk_full) {
        set_error(e, 507, "state_dir", "cannot store the upload in %s: %s", a->dir,
                  strerror(ENOSPC));
        goto refuse;
    }
    if (u->io_errno) {
        set_error(e, 500, "state_dir", "cannot store the upload in %s: %s", a->dir,
                  strerror(u->io_errno));
        goto refuse;
    }
    if (u->bytes == 0) {
        set_error(e, 400, "body", "the body must be the asset's .glb, .gltf or .hdr file; it is empty");
        goto refuse;
    }
    close(u->fd);
    u->fd = -1;
    struct task *t = calloc(1, sizeof(*t));
    struct ticket *k = calloc(1, sizeof(*k));
    if (!t || !k) {
        free(t);
        free(k);
        set_error(e, 500, "body", "out of memory");
        goto refuse;
    }
    uint8_t digest[SHA256_DIGEST_SIZE];
    sha256_digest(&u->sha, SHA256_DIGEST_SIZE, digest);
    t->kind = TASK_UPLOAD;
    hex(digest, t->sha256);
    snprintf(t->name, sizeof(t->name), "%s", u->name);
    snprintf(t->path, sizeof(t->path), "%s", u->tmp);
    /* A binary glTF starts with its magic, a Radiance image with "#?"
     * (an environment map); anything else is given to the converter as
     * JSON glTF. */
    snprintf(t->ext, sizeof(t->ext), "%s", memcmp(u->magic, "glTF", 4) == 0 ? "glb"
                                           : memcmp(u->magic, "#?", 2) == 0 ? "hdr"
                                                                             : "gltf");
    t->size = u->bytes;
    pthread_mutex_lock(&a->lock);
    if (a->stopping) {
        pthread_mutex_unlock(&a->lock);
        free(t);
        free(k);
        set_error(e, 503, "body", "the daemon is stopping");
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

bool assets_ticket_take(struct assets *a, uint64_t serial, unsigned *status, json_t **body)
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
    *status = t->status;
    *body = t->body;
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
        json_decref(t->body);
        free(t);
    } else if (*p) {
        (*p)->dropped = true; /* finish_ticket frees it */
    }
    pthread_mutex_unlock(&a->lock);
}

/* ---- reads, deletes, jobs ---- */

/* Under a->lock: a name of --asset-dir that is not ready answers here. */
static bool dir_not_ready_locked(struct assets *a, const char *name, const char *field,
                                 struct assets_error *e)
{
    struct dir_entry *d = dir_find(a, name);
    if (d && d->state == DIR_PENDING) {
        set_error(e, 409, field, "%s (from --asset-dir) is being converted; retry shortly", name);
        return true;
    }
    if (d && d->state == DIR_FAILED) {
        set_error(e, 422, field, "%s (from --asset-dir) could not be converted: %.400s", name,
                  d->error);
        return true;
    }
    return false;
}

json_t *assets_describe(struct assets *a, const char *name, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        set_error(e, 400, "name", "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                  "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    pthread_mutex_lock(&a->lock);
    bool not_ready = dir_not_ready_locked(a, name, "name", e);
    pthread_mutex_unlock(&a->lock);
    if (not_ready)
        return NULL;
    struct store_asset r;
    enum store_found f = store_asset_get(a->store, name, &r);
    json_t *o = f == STORE_FOUND ? record_json(&r, true) : NULL;
    store_asset_finish(&r);
    if (f == STORE_MISSING)
        set_error(e, 404, "name", "no asset of that name (GET /v1/assets lists them)");
    else if (!o)
        set_error(e, 500, "store", "cannot read the asset records (see the log)");
    return o;
}

static void list_row(void *ctx, const struct store_asset *r)
{
    json_array_append_new(ctx, record_json(r, false));
}

json_t *assets_list(struct assets *a, const char *cursor, int limit, struct assets_error *e)
{
    json_t *items = json_array();
    char next[STORE_ASSET_NAME_CAP], err[PATH_MAX + 300];
    if (!items || !store_asset_list(a->store, cursor, limit, false, list_row, items, next, err,
                                    sizeof(err))) {
        json_decref(items);
        set_error(e, 500, "store", "%.480s", items ? err : "out of memory");
        return NULL;
    }
    json_t *o = json_pack("{s:o}", "assets", items);
    if (o && next[0]) {
        char url[STORE_ASSET_NAME_CAP + 64];
        snprintf(url, sizeof(url), "/v1/assets?limit=%d&cursor=%s", limit, next);
        json_object_set_new(o, "next", json_string(url));
    }
    pthread_mutex_lock(&a->lock);
    size_t pending = 0, failed = 0;
    for (size_t i = 0; i < a->ndir; i++) {
        pending += a->dir_entries[i].state == DIR_PENDING;
        failed += a->dir_entries[i].state == DIR_FAILED;
    }
    pthread_mutex_unlock(&a->lock);
    if (o && (pending || failed))
        json_object_set_new(o, "asset_dir", json_pack("{s:I, s:I}", "converting",
                                                      (json_int_t)pending, "failed",
                                                      (json_int_t)failed));
    return o;
}

json_t *assets_delete(struct assets *a, const char *name, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        set_error(e, 400, "name", "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                  "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    json_t *out = NULL;
    struct store_asset r;
    memset(&r, 0, sizeof(r));
    pthread_mutex_lock(&a->lock);
    if (!writable_locked(a, name, e))
        goto out;
    enum store_found f = store_asset_get(a->store, name, &r);
    if (f != STORE_FOUND) {
        set_error(e, f == STORE_MISSING ? 404 : 500, "name",
                  f == STORE_MISSING ? "no asset of that name (GET /v1/assets lists them)"
                                     : "cannot read the asset records (see the log)");
        goto out;
    }
    char job[RECORD_ID_LEN];
    if (queue_asset_in_use(a->queue, name, NULL, job)) {
        set_error(e, 409, "name", "job %s (queued or running) uses %s: cancel it or wait for it "
                  "to end (DELETE /v1/jobs/%s)", job, name, job);
        goto out;
    }
    char err[PATH_MAX + 300];
    if (!store_asset_delete(a->store, name, err, sizeof(err))) {
        set_error(e, 500, "store", "%.480s", err);
        goto out;
    }
    release_files_locked(a, r.sha256);
    LOG(LOG_INFO, "assets: deleted %s (%s)", name, r.sha256);
    out = json_pack("{s:s, s:s, s:s}", "name", name, "sha256", r.sha256, "status", "deleted");
out:
    pthread_mutex_unlock(&a->lock);
    store_asset_finish(&r);
    return out;
}

/* name's stored hash into sha (pinned: must equal it), when the asset is
 * of the kind asked for (an environment map or a glTF scene). field and
 * sha_field name what the job called it. */
static bool resolve_name(struct assets *a, const char *name, char sha[65], bool environment,
                         const char *field, const char *sha_field, struct assets_error *e)
{
    pthread_mutex_lock(&a->lock);
    bool not_ready = dir_not_ready_locked(a, name, field, e);
    pthread_mutex_unlock(&a->lock);
    if (not_ready)
        return false;
    struct store_asset r;
    enum store_found f = store_asset_get(a->store, name, &r);
    bool ok = false;
    const char *kind = f == STORE_FOUND
                           ? json_string_value(json_object_get(r.description, "kind"))
                           : NULL;
    bool is_environment = kind && strcmp(kind, "environment") == 0;
    if (f == STORE_MISSING)
        set_error(e, 400, field, "no asset of that name; PUT /v1/assets/%s first", name);
    else if (f == STORE_ERROR)
        set_error(e, 500, field, "cannot read the asset records (see the log)");
    else if (is_environment != environment)
        set_error(e, 400, field, environment
                                     ? "%s is a glTF scene, not an environment map (an "
                                       "equirectangular .hdr)"
                                     : "%s is an environment map: name it in "
                                       "look.ibl.environment {\"asset\": ...}, not scene.asset",
                  name);
    else if (sha[0] && strcmp(sha, r.sha256) != 0)
        set_error(e, 409, sha_field, "the asset %s is now %s, not the pinned %s", name,
                  r.sha256, sha);
    else {
        memcpy(sha, r.sha256, 65);
        ok = true;
    }
    store_asset_finish(&r);
    return ok;
}

bool assets_resolve(struct assets *a, struct scene_spec *scene, struct assets_error *e)
{
    if (!scene->asset[0])
        return true;
    return resolve_name(a, scene->asset, scene->asset_sha256, false, "scene.asset",
                        "scene.asset_sha256", e);
}

bool assets_resolve_job(struct assets *a, struct job_spec *spec, struct assets_error *e)
{
    if (!assets_resolve(a, &spec->scene, e))
        return false;
    struct ibl_spec *looks[2] = {&spec->look.ibl, &spec->reference_look.ibl};
    for (int i = 0; i < 2; i++)
        if (looks[i]->enabled && looks[i]->environment == IBL_ENV_ASSET &&
            !resolve_name(a, looks[i]->env_asset, looks[i]->env_sha256, true,
                          i ? "reference_look.ibl.environment.asset"
                            : "look.ibl.environment.asset",
                          i ? "reference_look.ibl.environment.asset_sha256"
                            : "look.ibl.environment.asset_sha256",
                          e))
            return false;
    return true;
}

bool assets_queue_resolver(void *ctx, struct job_spec *spec, char *field, size_t field_cap,
                           char *message, size_t message_cap)
{
    struct assets_error e;
    if (assets_resolve_job(ctx, spec, &e))
        return true;
    snprintf(field, field_cap, "%s", e.field);
    snprintf(message, message_cap, "%s", e.message);
    return false;
}
