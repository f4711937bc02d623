/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets: the converter, shadebenchd-asset, run as a child process
 * under its limits and time-out, and the cache it writes (assets.h). */
#include "daemon/jobs/assets_impl.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "common/child.h"
#include "common/clock.h"
#include "common/fsutil.h"
#include "common/log.h"

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
 * started), death with the daemon (PR_SET_PDEATHSIG: a daemon killed with
 * SIGKILL leaves no converter running), nice 10 (so the render thread
 * keeps its core) and no file descriptor of the daemon's but stdin
 * (/dev/null), stdout (the pipe) and stderr (the log): common/child.h. */
static void convert(struct assets *a, const char *in, const char *out, const char *radiance_copy,
                    struct conversion *c)
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
    add_arg(argv, &argc, nums, "--max-nodes", l->max_nodes);
    add_arg(argv, &argc, nums, "--max-cache-bytes", l->max_cache_bytes);
    /* The room the cache may take: the disk's free space less what is kept
     * for jobs (ASSETS_HEADROOM), as an upload's own bytes are checked. */
    struct statvfs vfs;
    if (statvfs(a->dir, &vfs) == 0) {
        uint64_t avail = (uint64_t)vfs.f_bavail * vfs.f_frsize;
        add_arg(argv, &argc, nums, "--disk-room-bytes",
                avail > ASSETS_HEADROOM ? avail - ASSETS_HEADROOM : 0);
    }
    if (a->cfg.run.memory_bytes)
        add_arg(argv, &argc, nums, "--max-memory", a->cfg.run.memory_bytes);
    add_arg(argv, &argc, nums, "--max-cpu-seconds", a->cfg.run.cpu_s);
    argv[argc++] = "--radiance-copy";
    argv[argc++] = (char *)radiance_copy;
    argv[argc] = NULL;

    int pipefd[2] = {-1, -1};
    char *text = NULL;
    size_t len = 0;
    if (pipe2(pipefd, O_CLOEXEC) != 0) {
        snprintf(c->why, sizeof(c->why), "cannot start it: %s", strerror(errno));
        goto out;
    }
    /* Run from the worker thread, which lives as long as the daemon: the
     * converter's PR_SET_PDEATHSIG follows it (common/child.h). */
    struct child_spec spec = {.argv = argv, .stdout_fd = pipefd[1], .stderr_fd = -1,
                              .address_space = a->cfg.run.memory_bytes,
                              .cpu_s = a->cfg.run.cpu_s, .nice = 10};
    char why[200];
    pid_t pid = child_spawn(&spec, why, sizeof(why));
    if (pid < 0) {
        snprintf(c->why, sizeof(c->why), "%s", why);
        goto out;
    }
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
            child_kill(pid);
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
}

/* What a converter killed while it wrote left: its cache's temporary
 * (asset_file_write's OUT.XXXXXX beside convert-SHA.sbasset). */
static void remove_partial_cache(struct assets *a, const char *sha)
{
    char prefix[128];
    int n = snprintf(prefix, sizeof(prefix), "convert-%s.%s.", sha, ASSET_CACHE_EXT);
    DIR *d = opendir(a->dir);
    if (!d)
        return;
    struct dirent *de;
    while ((de = readdir(d)))
        if (strncmp(de->d_name, prefix, (size_t)n) == 0 && unlinkat(dirfd(d), de->d_name, 0) == 0)
            LOG(LOG_INFO, "assets: removed %s/%s, left by the converter", a->dir, de->d_name);
    closedir(d);
}

/* The cache and description of sha, converting in when they are not there
 * yet (an identical file converted before costs nothing). On success
 * *description is a new reference; else e says why. */
bool asset_ensure_cache(struct assets *a, const char *sha, const char *in, json_t **description,
                        struct assets_error *e)
{
    char cache[PATH_MAX + 80], desc[PATH_MAX + 80], tmp[PATH_MAX + 120];
    char copy[PATH_MAX + 80], tmp_copy[PATH_MAX + 120];
    asset_path(a, sha, ASSET_CACHE_EXT, cache, sizeof(cache));
    asset_path(a, sha, "json", desc, sizeof(desc));
    /* A cache an older shadebench wrote (another layout) is converted anew. */
    if (asset_file_is_current(cache) && (*description = json_load_file(desc, 0, NULL)))
        return true;
    snprintf(tmp, sizeof(tmp), "%s/convert-%s.%s", a->dir, sha, ASSET_CACHE_EXT);
    unlink(tmp);
    /* The converter writes an OpenEXR environment's Radiance copy (the
     * Khronos viewer reads only .hdr) here; it becomes SHA256.hdr. */
    snprintf(tmp_copy, sizeof(tmp_copy), "%s/convert-%s.hdr", a->dir, sha);
    unlink(tmp_copy);
    struct conversion c;
    double t0 = clock_mono_s();
    convert(a, in, tmp, tmp_copy, &c);
    LOG(LOG_INFO, "assets: converted %s in %.2f s: %s", in, clock_mono_s() - t0,
        c.outcome == CONV_OK ? "ok" : c.outcome == CONV_BAD ? "refused" : c.why);
    if (c.outcome == CONV_BAD) {
        json_int_t st = json_integer_value(json_object_get(c.out, "status"));
        const char *field = json_string_value(json_object_get(c.out, "field"));
        const char *message = json_string_value(json_object_get(c.out, "message"));
        enum assets_cause cause = st == 400   ? ASSETS_INVALID
                                  : st == 507 ? ASSETS_NO_SPACE
                                              : ASSETS_UNCONVERTIBLE;
        asset_refuse(e, cause, field ? field : "body", "%s",
                     message ? message : "the converter refused the asset");
        json_decref(c.out);
        unlink(tmp);
        unlink(tmp_copy);
        return false;
    }
    if (c.outcome == CONV_FAILED) {
        asset_refuse(e, ASSETS_UNCONVERTIBLE, "body",
                     "the asset loader failed on this file (%s)", c.why);
        unlink(tmp);
        remove_partial_cache(a, sha);
        unlink(tmp_copy);
        return false;
    }
    /* The copy first: the cache file is what says the work is done. */
    asset_path(a, sha, "hdr", copy, sizeof(copy));
    if (!file_exists(tmp) || (file_exists(tmp_copy) && rename(tmp_copy, copy) != 0) ||
        rename(tmp, cache) != 0) {
        asset_refuse(e, ASSETS_UNCONVERTIBLE, "body",
                     "the asset loader said it succeeded but wrote no cache file");
        json_decref(c.out);
        unlink(tmp);
        unlink(tmp_copy);
        return false;
    }
    if (!fs_write_json_atomic(desc, c.out)) {
        asset_refuse(e, ASSETS_NO_SPACE, "state_dir", "cannot write %s: %s", desc, strerror(errno));
        json_decref(c.out);
        unlink(cache);
        return false;
    }
    *description = c.out;
    return true;
}
