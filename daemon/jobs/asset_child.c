/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets: the converter, shadebenchd-asset, run as a child process
 * under its limits and time-out, and the cache it writes (assets.h). */
#include "daemon/jobs/assets_impl.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

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
 * *description is a new reference; else e says why. */
bool asset_ensure_cache(struct assets *a, const char *sha, const char *in, json_t **description,
                        struct assets_error *e)
{
    char cache[PATH_MAX + 80], desc[PATH_MAX + 80], tmp[PATH_MAX + 120];
    asset_path(a, sha, ASSET_CACHE_EXT, cache, sizeof(cache));
    asset_path(a, sha, "json", desc, sizeof(desc));
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
        asset_refuse(e, st == 400 ? ASSETS_INVALID : ASSETS_UNCONVERTIBLE, field ? field : "body",
                     "%s", message ? message : "the converter refused the asset");
        json_decref(c.out);
        unlink(tmp);
        return false;
    }
    if (c.outcome == CONV_FAILED) {
        asset_refuse(e, ASSETS_UNCONVERTIBLE, "body",
                     "the asset loader failed on this file (%s)", c.why);
        unlink(tmp);
        return false;
    }
    if (!file_exists(tmp) || rename(tmp, cache) != 0) {
        asset_refuse(e, ASSETS_UNCONVERTIBLE, "body",
                     "the asset loader said it succeeded but wrote no cache file");
        json_decref(c.out);
        unlink(tmp);
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
