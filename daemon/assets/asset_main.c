#define _POSIX_C_SOURCE 200809L /* mkdtemp, setrlimit */
/* shadebench-asset: the glTF converter the daemon runs as a child process
 * (docs/assets.md), and the environment maps' (a Radiance .hdr, told apart
 * by its first bytes: env_convert.h). One thread; it reads IN_FILE and
 * writes OUT_CACHE and nothing else.
 *
 *   shadebench-asset convert IN_FILE OUT_CACHE [--max-file-bytes N]
 *       [--max-vertices N] [--max-indices N] [--max-texture-pixels N]
 *       [--max-texture-edge N] [--max-nodes N] [--max-cache-bytes N]
 *       [--disk-room-bytes N] [--max-memory BYTES] [--max-cpu-seconds S]
 *
 * Exit 0: OUT_CACHE written, stdout one JSON object (asset_describe). Exit
 * 2: the asset is refused, stdout {"status": 400|422|507, "field",
 * "message"} (507: the cache does not fit the room --disk-room-bytes says
 * the disk has, or the disk filled while it was written).
 * Anything else (1 for usage or the converter's own failures, a signal from
 * the limits): the loader failed. */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "daemon/assets/asset_convert.h"
#include "daemon/assets/env_convert.h"

static int usage(void)
{
    fprintf(stderr, "usage: shadebench-asset convert IN_FILE OUT_CACHE [--max-file-bytes N] "
                    "[--max-vertices N] [--max-indices N] [--max-texture-pixels N] "
                    "[--max-texture-edge N] [--max-nodes N] [--max-cache-bytes N] "
                    "[--disk-room-bytes N] [--max-memory BYTES] [--max-cpu-seconds S] "
                    "[--radiance-copy PATH]\n");
    return 1;
}

static bool parse_u64(const char *s, uint64_t *out)
{
    if (!s || !*s || *s == '-')
        return false;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || *end)
        return false;
    *out = v;
    return true;
}

static int refuse(int status, const char *field, const char *message)
{
    json_t *o = json_pack("{si ss ss}", "status", status, "field", field, "message", message);
    if (!o)
        return 1;
    char *s = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    if (!s)
        return 1;
    printf("%s\n", s);
    free(s);
    return fflush(stdout) == 0 ? 2 : 1;
}

static void limit(int resource, uint64_t value, const char *what)
{
    struct rlimit rl = {(rlim_t)value, (rlim_t)value};
    if (setrlimit(resource, &rl) != 0)
        fprintf(stderr, "shadebench-asset: cannot set %s to %" PRIu64 " (%s); continuing without\n",
                what, value, strerror(errno));
}

/* The whole file, at most max bytes (one more is read to tell "over"). */
static uint8_t *read_input(const char *path, uint64_t max, size_t *len, bool *over)
{
    *over = false;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return NULL;
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        errno = EINVAL;
        return NULL;
    }
    if ((uint64_t)st.st_size > max) {
        close(fd);
        *over = true;
        *len = (size_t)st.st_size;
        return NULL;
    }
    size_t cap = (size_t)st.st_size + 1, n = 0;
    uint8_t *buf = malloc(cap);
    if (!buf) {
        close(fd);
        return NULL;
    }
    for (;;) {
        ssize_t r = read(fd, buf + n, cap - n);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0) {
            free(buf);
            close(fd);
            return NULL;
        }
        if (r == 0)
            break;
        n += (size_t)r;
        if (n == cap) { /* the file grew: over what fstat said */
            free(buf);
            close(fd);
            *over = n > max;
            errno = EFBIG;
            return NULL;
        }
    }
    close(fd);
    *len = n;
    return buf;
}

/* path made absolute against the working directory; malloc'ed, NULL when
 * it cannot be. */
static char *absolute(const char *path)
{
    if (path[0] == '/')
        return strdup(path);
    char cwd[4096];
    if (!getcwd(cwd, sizeof(cwd)))
        return NULL;
    char *p = malloc(strlen(cwd) + strlen(path) + 2);
    if (p)
        sprintf(p, "%s/%s", cwd, path);
    return p;
}

/* An environment map: decoded, written, described; frees data and out.
 * An OpenEXR one is also written as a Radiance file at radiance_copy
 * (when given), the copy the Khronos viewer reads (it reads only .hdr). */
static int convert_environment(uint8_t *data, size_t len, char *out, const char *radiance_copy)
{
    const char *format = env_convert_format(data, len);
    struct environment_limits lim;
    environment_limits_defaults(&lim);
    struct environment_image env;
    struct asset_convert_error cerr;
    bool ok = env_convert_buffer(data, len, &lim, &env, &cerr);
    free(data);
    if (!ok) {
        free(out);
        if (cerr.status == 400 || cerr.status == 422)
            return refuse(cerr.status, cerr.field, cerr.message);
        fprintf(stderr, "shadebench-asset: %s: %s\n", cerr.field, cerr.message);
        return 1;
    }
    char err[512];
    ok = environment_file_write(&env, out, err, sizeof(err));
    free(out);
    bool copied = false;
    if (ok && radiance_copy && strcmp(format, "openexr") == 0)
        ok = copied = env_convert_write_radiance(&env, radiance_copy, err, sizeof(err));
    json_t *d = ok ? environment_describe(&env, format) : NULL;
    if (d && copied)
        json_object_set_new(d, "viewer_copy", json_string("radiance_hdr"));
    environment_image_finish(&env);
    if (!ok) {
        fprintf(stderr, "shadebench-asset: %s\n", err);
        return 1;
    }
    char *s = d ? json_dumps(d, JSON_COMPACT) : NULL;
    json_decref(d);
    if (!s) {
        fprintf(stderr, "shadebench-asset: out of memory\n");
        return 1;
    }
    printf("%s\n", s);
    free(s);
    return fflush(stdout) == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc < 4 || strcmp(argv[1], "convert") != 0)
        return usage();
    const char *in = argv[2], *out = argv[3];
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    uint64_t max_memory = 0, max_cpu = 0, disk_room = 0;
    bool have_room = false;
    const char *radiance_copy = NULL;
    for (int i = 4; i < argc; i += 2) {
        uint64_t v;
        if (!strcmp(argv[i], "--radiance-copy") && i + 1 < argc) {
            radiance_copy = argv[i + 1];
            continue;
        }
        if (i + 1 >= argc || !parse_u64(argv[i + 1], &v)) {
            fprintf(stderr, "shadebench-asset: %s needs a non-negative integer\n", argv[i]);
            return usage();
        }
        if (!strcmp(argv[i], "--max-file-bytes"))
            lim.max_file_bytes = v;
        else if (!strcmp(argv[i], "--max-vertices"))
            lim.max_vertices = v;
        else if (!strcmp(argv[i], "--max-indices"))
            lim.max_indices = v;
        else if (!strcmp(argv[i], "--max-texture-pixels"))
            lim.max_texture_pixels = v;
        else if (!strcmp(argv[i], "--max-texture-edge") && v <= UINT32_MAX)
            lim.max_texture_edge = (uint32_t)v;
        else if (!strcmp(argv[i], "--max-nodes") && v <= UINT32_MAX)
            lim.max_nodes = (uint32_t)v;
        else if (!strcmp(argv[i], "--max-cache-bytes"))
            lim.max_cache_bytes = v;
        else if (!strcmp(argv[i], "--disk-room-bytes"))
            disk_room = v, have_room = true;
        else if (!strcmp(argv[i], "--max-memory"))
            max_memory = v;
        else if (!strcmp(argv[i], "--max-cpu-seconds"))
            max_cpu = v;
        else
            return usage();
    }
    /* The limits first, before the file is read: a hostile file meets them
     * from its first byte. */
    if (max_memory)
        limit(RLIMIT_AS, max_memory, "RLIMIT_AS");
    if (max_cpu)
        limit(RLIMIT_CPU, max_cpu, "RLIMIT_CPU");

    /* jansson would read /dev/urandom for its hash seed at the first
     * object; seeding it here keeps the converter's reads to IN_FILE, and
     * the seed still unknown to the file's author. */
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    json_object_seed((size_t)now.tv_nsec ^ ((size_t)getpid() << 16) ^ (size_t)now.tv_sec);

    /* The outputs' full paths, taken before leaving the working directory. */
    char *out_abs = absolute(out), *copy_abs = radiance_copy ? absolute(radiance_copy) : NULL;
    if (!out_abs || (radiance_copy && !copy_abs)) {
        fprintf(stderr, "shadebench-asset: cannot resolve %s\n", out_abs ? radiance_copy : out);
        free(out_abs);
        free(copy_abs);
        return 1;
    }
    size_t len = 0;
    bool over = false;
    uint8_t *data = read_input(in, lim.max_file_bytes, &len, &over);
    if (!data) {
        free(out_abs);
        free(copy_abs);
        if (over) {
            char msg[160];
            snprintf(msg, sizeof(msg), "%zu bytes, the limit is %" PRIu64, len, lim.max_file_bytes);
            return refuse(422, "limits.max_file_bytes", msg);
        }
        fprintf(stderr, "shadebench-asset: cannot read %s: %s\n", in, strerror(errno));
        return 1;
    }
    /* Nothing relative resolves against the caller's folder from here on:
     * the converter reads no file but IN_FILE (already in memory). */
    if (chdir("/") != 0)
        fprintf(stderr, "shadebench-asset: cannot chdir to /: %s\n", strerror(errno));

    if (env_convert_format(data, len)) {
        int rc = convert_environment(data, len, out_abs, copy_abs);
        free(copy_abs);
        return rc;
    }
    free(copy_abs);
    struct asset a;
    struct asset_convert_error cerr;
    bool ok = asset_convert_buffer(data, len, &lim, &a, &cerr);
    free(data);
    if (!ok) {
        free(out_abs);
        if (cerr.status == 400 || cerr.status == 422)
            return refuse(cerr.status, cerr.field, cerr.message);
        fprintf(stderr, "shadebench-asset: %s: %s\n", cerr.field, cerr.message);
        return 1;
    }
    /* The cache's size, known before a byte of it is written: over the
     * limit, or over the room the daemon says the disk has for it (its free
     * space less what it keeps for jobs), it is refused, not written until
     * the disk fills. */
    uint64_t size = asset_file_size(&a);
    char msg[320];
    if (size > lim.max_cache_bytes || (have_room && size > disk_room)) {
        bool limit = size > lim.max_cache_bytes;
        if (limit)
            snprintf(msg, sizeof(msg), "the cache would take %" PRIu64 " bytes (its images "
                     "decoded, its vertices expanded), the limit is %" PRIu64, size,
                     lim.max_cache_bytes);
        else
            snprintf(msg, sizeof(msg), "the cache would take %" PRIu64 " bytes; the state "
                     "directory's disk has room for %" PRIu64 " (its free space less what is "
                     "kept for jobs)", size, disk_room);
        asset_finish(&a);
        free(out_abs);
        return refuse(limit ? 422 : 507, limit ? "limits.max_cache_bytes" : "state_dir", msg);
    }
    char err[512];
    if (!asset_file_write(&a, out_abs, err, sizeof(err))) {
        int saved = errno;
        fprintf(stderr, "shadebench-asset: %s\n", err);
        asset_finish(&a);
        free(out_abs);
        if (saved == ENOSPC || saved == EDQUOT)
            return refuse(507, "state_dir", err);
        return 1;
    }
    free(out_abs);
    json_t *d = asset_describe(&a);
    asset_finish(&a);
    char *s = d ? json_dumps(d, JSON_COMPACT) : NULL;
    json_decref(d);
    if (!s) {
        fprintf(stderr, "shadebench-asset: out of memory\n");
        return 1;
    }
    printf("%s\n", s);
    free(s);
    return fflush(stdout) == 0 ? 0 : 1;
}
