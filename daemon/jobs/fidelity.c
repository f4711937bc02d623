#define _GNU_SOURCE /* pipe2 */
#include "daemon/jobs/fidelity.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <nettle/sha2.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <utime.h>

#include "common/clock.h"
#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/log.h"
#include "common/png_io.h"
#include "daemon/jobs/deadline.h"
#include "daemon/store/asset_store.h"
#include "daemon/quality/metrics.h"
#include "daemon/spec/fidelity_spec.h"
#include "daemon/reference/reference_files.h"

struct task {
    struct job *job;
    json_t *result, *view;
    struct task *next;
};

struct fidelity {
    struct fidelity_config cfg;
    char state_dir[PATH_MAX];
    struct reference_paths paths;
    struct queue *queue;
    pthread_t thread;
    bool started;
    pthread_mutex_t lock;
    pthread_cond_t wake, idle;
    struct task *head, *tail;
    bool busy, stopping;
};

/* ---- the page's request (GL-free) ---- */

uint8_t fidelity_reencode(uint8_t v, bool to_linear)
{
    double lin = pow(v / 255.0, 2.2);
    double out = to_linear ? lin
                 : lin <= 0.0031308 ? 12.92 * lin : 1.055 * pow(lin, 1.0 / 2.4) - 0.055;
    long r = lround(out * 255.0);
    return (uint8_t)(r < 0 ? 0 : r > 255 ? 255 : r);
}

json_t *fidelity_page_request(const struct job_spec *spec, const json_t *view,
                              const char *const *channels, int nchannels, char *err,
                              size_t errlen)
{
    const struct look_spec *look = &spec->look;
    const char *tonemap;
    double exposure = look->exposure;
    switch (look->tonemap) {
    case LOOK_TONEMAP_PBR_NEUTRAL: tonemap = "pbr_neutral"; break;
    /* shadebench's ACES is Narkowicz's fit after x 0.6 (tone_curves.c). */
    case LOOK_TONEMAP_ACES: tonemap = "aces"; exposure *= 0.6; break;
    case LOOK_TONEMAP_SRGB:
    case LOOK_TONEMAP_NONE: tonemap = "none"; break;
    default:
        snprintf(err, errlen, "look.tonemap: the Khronos viewer has no such curve");
        return NULL;
    }
    /* Without look.ibl shadebench's PBR ambient is a uniform environment of
     * radiance 0.15 (shaders/common/lighting.glsl, AMBIENT). */
    double ibl = 0.15;
    bool file = false;
    if (look->ibl.enabled) {
        ibl = look->ibl.intensity;
        file = look->ibl.environment == IBL_ENV_ASSET;
    }
    /* The viewer maps a panorama as shadebench does (its dirToUV: u = 0.5 +
     * atan2(z, x) / 2 pi, the image's centre at +x; environment.glsl), so
     * it is given no rotation of its own (its UI's default is 90 degrees,
     * which put an environment's +x at +z: a white ball under
     * hdr_gen.sky_and_ground, lit SSIM 0.808 -> 0.980 from the front). */
    json_t *ch = json_array();
    for (int i = 0; i < nchannels; i++)
        json_array_append_new(ch, json_string(channels[i]));
    json_t *r = json_pack("{s:i, s:i, s:O, s:O, s:O, s:O, s:f, s:s, s:f, s:b, s:i, s:b, "
                          "s:[i, i, i, i], s:o}",
                          "width", spec->scene.width, "height", spec->scene.height, "view",
                          json_object_get(view, "view"), "projection",
                          json_object_get(view, "projection"), "eye",
                          json_object_get(view, "eye"), "lights",
                          json_object_get(view, "lights"), "exposure", exposure, "tonemap",
                          tonemap, "ibl_intensity", ibl, "environment_file", file,
                          "environment_rotation_deg", 0, "render_environment", file, "clear", 0,
                          0, 0, 255, "channels", ch);
    if (!r)
        snprintf(err, errlen, "out of memory for the reference's request");
    return r;
}

/* The sampler the viewer runs with for this job. */
static void job_sampler(const struct job_spec *spec, struct reference_sampler *out)
{
    bool uniform = !(spec->look.ibl.enabled && spec->look.ibl.environment == IBL_ENV_ASSET);
    reference_sampler_resolve(&spec->fidelity.sampler, uniform, out);
}

void fidelity_cache_key(const json_t *page_request, const struct job_spec *spec, char out[65])
{
    struct reference_sampler sampler;
    job_sampler(spec, &sampler);
    json_t *k = json_pack("{s:s, s:s, s:o, s:s, s:s, s:o}", "viewer",
                          REFERENCE_VIEWER_PACKAGE "@" REFERENCE_VIEWER_VERSION, "page", "3",
                          "ibl_sampler", reference_sampler_to_json(&sampler),
                          "asset", spec->scene.asset_sha256, "environment",
                          spec->look.ibl.enabled ? spec->look.ibl.env_sha256 : "", "request",
                          json_deep_copy(page_request));
    /* Channels are cached one file each: the key leaves them out. */
    json_object_del(json_object_get(k, "request"), "channels");
    char *text = k ? json_dumps(k, JSON_COMPACT | JSON_SORT_KEYS | JSON_REAL_PRECISION(9)) : NULL;
    json_decref(k);
    uint8_t digest[SHA256_DIGEST_SIZE];
    struct sha256_ctx ctx;
    sha256_init(&ctx);
    sha256_update(&ctx, text ? strlen(text) : 0, (const uint8_t *)(text ? text : ""));
    sha256_digest(&ctx, sizeof(digest), digest);
    free(text);
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++)
        snprintf(out + 2 * i, 3, "%02x", digest[i]);
}

/* ---- the child ---- */

/* Resident bytes of every process in group pgid (/proc; 0 when none). */
static uint64_t group_rss(pid_t pgid)
{
    DIR *d = opendir("/proc");
    if (!d)
        return 0;
    uint64_t total = 0;
    long page = sysconf(_SC_PAGESIZE);
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] < '0' || e->d_name[0] > '9')
            continue;
        char path[300], buf[1024];
        snprintf(path, sizeof(path), "/proc/%.255s/stat", e->d_name);
        int fd = open(path, O_RDONLY | O_CLOEXEC);
        if (fd < 0)
            continue;
        ssize_t n = read(fd, buf, sizeof(buf) - 1);
        close(fd);
        if (n <= 0)
            continue;
        buf[n] = '\0';
        char *p = strrchr(buf, ')'); /* the name may hold spaces */
        if (!p)
            continue;
        /* After ")": state ppid pgrp ... field 24 (rss, pages) is the 22nd after. */
        long long v[24];
        int got = 0;
        char *s = p + 2;
        while (got < 24 && *s) {
            if (got == 0) { /* state, a letter */
                v[got++] = 0;
                s = strchr(s, ' ');
                if (!s) break;
                s++;
                continue;
            }
            char *end;
            v[got++] = strtoll(s, &end, 10);
            if (end == s) break;
            s = end + (*end == ' ');
        }
        if (got >= 22 && v[2] == pgid)
            total += (uint64_t)v[21] * (uint64_t)page;
    }
    closedir(d);
    return total;
}

struct child_run {
    int exit_code; /* -1: killed or not run */
    char *out;     /* its stdout */
    char why[512]; /* killed: why */
    bool cancelled;
};

static void run_child(struct fidelity *f, struct job *job, const char *request_path,
                      const char *log_path, struct child_run *cr)
{
    memset(cr, 0, sizeof(*cr));
    cr->exit_code = -1;
    int out[2];
    if (pipe2(out, O_CLOEXEC) != 0) {
        snprintf(cr->why, sizeof(cr->why), "pipe: %s", strerror(errno));
        return;
    }
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(cr->why, sizeof(cr->why), "fork: %s", strerror(errno));
        close(out[0]);
        close(out[1]);
        return;
    }
    if (pid == 0) {
        setpgid(0, 0);
        if (nice(10) < 0) { /* lower priority than the render thread; best effort */ }
        int devnull = open("/dev/null", O_RDONLY);
        int log = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (devnull < 0 || dup2(devnull, 0) < 0 || dup2(out[1], 1) < 0 ||
            dup2(log >= 0 ? log : devnull, 2) < 0)
            _exit(127);
        execl(f->paths.program, f->paths.program, "render", request_path, (char *)NULL);
        _exit(127);
    }
    setpgid(pid, pid); /* from this side too, so that the group exists before we kill it */
    close(out[1]);
    double t0 = clock_mono_s(), timeout = f->cfg.timeout_s > 0 ? f->cfg.timeout_s
                                                               : FIDELITY_TIMEOUT_S;
    uint64_t limit = f->cfg.memory_bytes ? f->cfg.memory_bytes : FIDELITY_MEMORY;
    size_t len = 0, cap = 0;
    char *buf = NULL;
    bool eof = false, killed = false;
    double next_rss = 0;
    while (!eof) {
        struct pollfd p = {.fd = out[0], .events = POLLIN};
        int r = poll(&p, 1, 200);
        if (r > 0) {
            if (cap - len < 4096) {
                size_t ncap = cap ? cap * 2 : 65536;
                char *b = ncap <= (64u << 20) ? realloc(buf, ncap) : NULL;
                if (!b) {
                    snprintf(cr->why, sizeof(cr->why), "its answer is over 64 MiB");
                    killed = true;
                    break;
                }
                buf = b;
                cap = ncap;
            }
            ssize_t n = read(out[0], buf + len, cap - len - 1);
            if (n > 0)
                len += (size_t)n;
            else if (n == 0 || (errno != EINTR && errno != EAGAIN))
                eof = true;
        }
        double now = clock_mono_s();
        if (atomic_load(&job->cancel)) {
            cr->cancelled = killed = true;
            snprintf(cr->why, sizeof(cr->why), "the job was cancelled");
        } else if (job_timed_out(job)) {
            killed = true;
            snprintf(cr->why, sizeof(cr->why), "the job ran past its timeout_s of %g s",
                     job->spec.timeout_s);
        } else if (now - t0 > timeout) {
            killed = true;
            snprintf(cr->why, sizeof(cr->why), "it ran past its %.0f s (--reference-timeout)",
                     timeout);
        } else if (now >= next_rss) {
            next_rss = now + 0.25;
            uint64_t rss = group_rss(pid);
            if (rss > limit) {
                killed = true;
                snprintf(cr->why, sizeof(cr->why), "Chromium and it held %.0f MiB, over the "
                         "%.0f MiB limit (--reference-memory)", rss / 1048576.0,
                         limit / 1048576.0);
            }
        }
        if (killed)
            break;
    }
    close(out[0]);
    if (killed)
        kill(-pid, SIGKILL);
    int st = 0;
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR)
        ;
    /* Whatever of the group outlived its leader (Chromium's helpers). */
    kill(-pid, SIGKILL);
    if (buf)
        buf[len] = '\0';
    cr->out = buf;
    if (!killed && WIFEXITED(st))
        cr->exit_code = WEXITSTATUS(st);
    else if (!killed)
        snprintf(cr->why, sizeof(cr->why), "it died of signal %d", WTERMSIG(st));
}

/* ---- the cache's bound ---- */

struct cache_entry {
    char name[80];
    double mtime;
};

static int by_mtime(const void *a, const void *b)
{
    double x = ((const struct cache_entry *)a)->mtime, y = ((const struct cache_entry *)b)->mtime;
    return x < y ? -1 : x > y;
}

static void remove_entry(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char p[PATH_MAX + 300];
        snprintf(p, sizeof(p), "%s/%.255s", dir, e->d_name);
        unlink(p);
    }
    if (d)
        closedir(d);
    rmdir(dir);
}

/* At most FIDELITY_CACHE_MAX_KEYS keys: the least recently used go (a hit
 * touches its folder). Temporary folders of runs cut short go too. */
static void prune_cache(const struct fidelity *f)
{
    char root[PATH_MAX + 40];
    snprintf(root, sizeof(root), "%s/" FIDELITY_CACHE_DIR, f->state_dir);
    DIR *d = opendir(root);
    if (!d)
        return;
    size_t n = 0, cap = 0;
    struct cache_entry *list = NULL;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t len = strlen(e->d_name);
        if (e->d_name[0] == '.' || len >= sizeof(list->name))
            continue;
        char p[PATH_MAX + 120];
        if (snprintf(p, sizeof(p), "%s/%s", root, e->d_name) >= (int)sizeof(p))
            continue;
        struct stat st;
        if (stat(p, &st) != 0 || !S_ISDIR(st.st_mode))
            continue;
        if (strstr(e->d_name, ".tmp-") && time(NULL) - st.st_mtime > 3600) {
            remove_entry(p);
            continue;
        }
        if (n == cap) {
            struct cache_entry *l = realloc(list, (cap = cap ? cap * 2 : 64) * sizeof(*l));
            if (!l)
                break;
            list = l;
        }
        memcpy(list[n].name, e->d_name, len + 1); /* len < sizeof(name), checked above */
        list[n++].mtime = (double)st.st_mtime;
    }
    closedir(d);
    if (n > FIDELITY_CACHE_MAX_KEYS) {
        qsort(list, n, sizeof(*list), by_mtime);
        for (size_t i = 0; i < n - FIDELITY_CACHE_MAX_KEYS; i++) {
            char p[PATH_MAX + 120];
            snprintf(p, sizeof(p), "%s/%s", root, list[i].name);
            remove_entry(p);
        }
    }
    free(list);
}

/* ---- comparing ---- */

static bool read_png(const char *path, struct image *img, char *err, size_t errlen)
{
    return png_read_rgb(path, img, err, errlen);
}

static json_t *compare_channel(const char *dir, const char *name, const char *ours,
                               const char *theirs, char *err, size_t errlen)
{
    struct image a = {0}, b = {0};
    json_t *m = NULL;
    if (!read_png(theirs, &a, err, errlen) || !read_png(ours, &b, err, errlen))
        goto out;
    if (a.width != b.width || a.height != b.height) {
        snprintf(err, errlen, "%s: the images differ in size (%dx%d, %dx%d)", name, a.width,
                 a.height, b.width, b.height);
        goto out;
    }
    struct metrics_options o;
    metrics_options_defaults(&o);
    o.which = METRIC_ALL;
    char ssim_path[PATH_MAX + 64], flip_path[PATH_MAX + 64];
    snprintf(ssim_path, sizeof(ssim_path), "%s/ssim-%s.png", dir, name);
    snprintf(flip_path, sizeof(flip_path), "%s/flip-%s.png", dir, name);
    m = metrics_compare(&a, &b, &o, ssim_path, flip_path, NULL, err, errlen);
    if (m) {
        /* How many pixels differ, and by how much at most (8-bit levels). */
        long over8 = 0, over32 = 0;
        int maxd = 0;
        for (size_t i = 0; i < (size_t)a.width * a.height * 3; i += 3) {
            int d = 0;
            for (int c = 0; c < 3; c++)
                d = abs((int)a.rgb[i + c] - (int)b.rgb[i + c]) > d
                        ? abs((int)a.rgb[i + c] - (int)b.rgb[i + c]) : d;
            over8 += d > 8;
            over32 += d > 32;
            maxd = d > maxd ? d : maxd;
        }
        json_object_set_new(m, "pixels_over_8", json_integer(over8));
        json_object_set_new(m, "pixels_over_32", json_integer(over32));
        json_object_set_new(m, "max_difference", json_integer(maxd));
    }
out:
    image_finish(&a);
    image_finish(&b);
    return m;
}

/* Rewrites a viewer image in shadebench's encoding (fidelity_reencode). */
static bool reencode_png(const char *from, const char *to, bool to_linear, char *err,
                         size_t errlen)
{
    struct image img = {0};
    if (!png_read_rgb(from, &img, err, errlen))
        return false;
    uint8_t lut[256];
    for (int v = 0; v < 256; v++)
        lut[v] = fidelity_reencode((uint8_t)v, to_linear);
    size_t n = (size_t)img.width * img.height;
    uint8_t *rgba = malloc(n * 4);
    bool ok = rgba != NULL;
    /* png_write_gl_rgba takes rows bottom first. */
    for (int y = 0; ok && y < img.height; y++)
        for (int x = 0; x < img.width; x++) {
            const uint8_t *s = img.rgb + ((size_t)y * img.width + x) * 3;
            uint8_t *d = rgba + ((size_t)(img.height - 1 - y) * img.width + x) * 4;
            d[0] = lut[s[0]], d[1] = lut[s[1]], d[2] = lut[s[2]], d[3] = 255;
        }
    ok = ok && png_write_gl_rgba(to, rgba, img.width, img.height, err, errlen);
    if (!rgba)
        snprintf(err, errlen, "out of memory");
    free(rgba);
    image_finish(&img);
    return ok;
}

static bool copy_file(const char *from, const char *to)
{
    size_t len;
    char *data = fs_read_file(from, 1u << 30, &len);
    bool ok = data && fs_write_atomic(to, data, len);
    free(data);
    return ok;
}

/* The uploaded file of the asset: STATE/assets/SHA256.glb or .gltf. */
static bool original_asset(const struct fidelity *f, const char *sha, char *out, size_t cap)
{
    static const char *const exts[] = {"glb", "gltf"};
    for (int i = 0; i < 2; i++)
        if (asset_store_original_path(f->state_dir, sha, exts[i], out, cap) &&
            access(out, R_OK) == 0)
            return true;
    return false;
}

/* One job: the reference (from the cache, or the child), the comparisons,
 * result.fidelity. false with err (and *status). */
static bool finish_fidelity(struct fidelity *f, struct task *t, enum job_status *status,
                            char *err, size_t errlen)
{
    struct job *job = t->job;
    const struct job_spec *spec = &job->spec;
    char dir[PATH_MAX + 16];
    snprintf(dir, sizeof(dir), "%s/" FIDELITY_DIR, job->dir);
    char why[512];
    if (!fidelity_available(f, why, sizeof(why))) {
        snprintf(err, errlen, "the Khronos reference is not available: %s", why);
        return false;
    }
    /* The channels shadebench drew, in enum order. */
    json_t *ours = json_object_get(t->view, "channels");
    const char *names[FIDELITY_CHANNELS];
    int n = 0;
    for (int c = 0; c < FIDELITY_CHANNELS; c++)
        if (json_object_get(json_object_get(ours, fidelity_channel_names[c]), "source"))
            names[n++] = fidelity_channel_names[c];
    json_t *page = fidelity_page_request(spec, t->view, names, n, err, errlen);
    if (!page)
        return false;
    char key[65];
    fidelity_cache_key(page, spec, key);
    struct reference_sampler sampler;
    job_sampler(spec, &sampler);
    char cache[PATH_MAX + 100];
    snprintf(cache, sizeof(cache), "%s/" FIDELITY_CACHE_DIR "/%s", f->state_dir, key);
    /* The channels the cache lacks. */
    json_t *todo = json_array();
    for (int i = 0; i < n; i++) {
        char p[PATH_MAX + 160];
        snprintf(p, sizeof(p), "%s/%s.png", cache, names[i]);
        if (access(p, R_OK) != 0)
            json_array_append_new(todo, json_string(names[i]));
    }
    json_t *cost = NULL;
    char cost_path[PATH_MAX + 120];
    snprintf(cost_path, sizeof(cost_path), "%s/cost.json", cache);
    bool hit = json_array_size(todo) == 0;
    bool ok = false;
    if (!hit) {
        char tmp[PATH_MAX + 140], req_path[PATH_MAX + 160], log_path[PATH_MAX + 40];
        snprintf(tmp, sizeof(tmp), "%s.tmp-%s", cache, job->id);
        snprintf(req_path, sizeof(req_path), "%s/request.json", tmp);
        snprintf(log_path, sizeof(log_path), "%s/reference.log", dir);
        char asset[PATH_MAX], env[PATH_MAX] = "";
        if (!original_asset(f, spec->scene.asset_sha256, asset, sizeof(asset))) {
            snprintf(err, errlen, "the uploaded file of asset %s (%s) is not in the state "
                     "directory", spec->scene.asset, spec->scene.asset_sha256);
            goto out;
        }
        /* The Radiance file: the upload, or an OpenEXR upload's copy. */
        if (spec->look.ibl.enabled && spec->look.ibl.environment == IBL_ENV_ASSET &&
            (!asset_store_original_path(f->state_dir, spec->look.ibl.env_sha256, "hdr", env,
                                        sizeof(env)) ||
             access(env, R_OK) != 0)) {
            snprintf(err, errlen, "look.ibl.environment: no Radiance file of %s for the viewer "
                     "(%s)", spec->look.ibl.env_sha256, env);
            goto out;
        }
        json_object_set(page, "channels", todo);
        json_t *req = json_pack("{s:s, s:s, s:s, s:s, s:s?, s:s, s:f, s:o, s:O}", "chromium",
                                f->paths.chromium, "page_dir", f->paths.page_dir, "viewer_dir",
                                f->paths.viewer_dir, "asset", asset, "environment",
                                env[0] ? env : NULL, "out_dir", tmp, "timeout_s",
                                f->cfg.timeout_s > 0 ? f->cfg.timeout_s : FIDELITY_TIMEOUT_S,
                                "ibl_sampler", reference_sampler_to_json(&sampler),
                                "render", page);
        if (!fs_mkdir_p(tmp) || !req || !fs_write_json_atomic(req_path, req)) {
            snprintf(err, errlen, "cannot write %.600s: %s", req_path, strerror(errno));
            json_decref(req);
            goto out;
        }
        json_decref(req);
        struct child_run cr;
        LOG(LOG_INFO, "job %s: the Khronos reference (%zu channels)", job->id,
            json_array_size(todo));
        run_child(f, job, req_path, log_path, &cr);
        json_error_t je;
        json_t *answer = cr.out ? json_loads(cr.out, 0, &je) : NULL;
        free(cr.out);
        if (cr.cancelled) {
            *status = JOB_CANCELLED;
            snprintf(err, errlen, "cancelled while the Khronos reference rendered");
        } else if (cr.exit_code != 0) {
            const char *e = json_string_value(json_object_get(answer, "error"));
            snprintf(err, errlen, "the Khronos reference failed: %.500s (its log: %.300s)",
                     e ? e : cr.why[0] ? cr.why : "no answer", log_path);
        }
        if (cr.exit_code != 0 || !answer) {
            if (cr.exit_code == 0)
                snprintf(err, errlen, "the Khronos reference answered no JSON");
            json_decref(answer);
            char rm[PATH_MAX + 160];
            snprintf(rm, sizeof(rm), "%s/request.json", tmp);
            unlink(rm);
            for (size_t i = 0; i < json_array_size(todo); i++) {
                snprintf(rm, sizeof(rm), "%s/%s.png", tmp,
                         json_string_value(json_array_get(todo, i)));
                unlink(rm);
            }
            rmdir(tmp);
            goto out;
        }
        /* Into the cache: each channel's image, and what they cost. */
        fs_mkdir_p(cache);
        for (size_t i = 0; i < json_array_size(todo); i++) {
            char from[PATH_MAX + 160], to[PATH_MAX + 160];
            const char *nm = json_string_value(json_array_get(todo, i));
            snprintf(from, sizeof(from), "%s/%s.png", tmp, nm);
            snprintf(to, sizeof(to), "%s/%s.png", cache, nm);
            rename(from, to);
        }
        unlink(req_path);
        rmdir(tmp);
        cost = answer;
        fs_write_json_atomic(cost_path, cost);
        prune_cache(f);
    } else {
        json_error_t je;
        cost = json_load_file(cost_path, 0, &je);
        utime(cache, NULL); /* recently used */
    }
    /* Compare each channel. */
    json_t *channels = json_object();
    json_t *lit = NULL;
    for (int i = 0; i < n; i++) {
        char theirs[PATH_MAX + 160], mine[PATH_MAX + 160];
        snprintf(theirs, sizeof(theirs), "%s/khronos-%s.png", dir, names[i]);
        char cached[PATH_MAX + 160];
        snprintf(cached, sizeof(cached), "%s/%s.png", cache, names[i]);
        bool lit_channel = strcmp(names[i], "lit") == 0;
        int tm = spec->look.tonemap;
        /* The viewer writes gamma 2.2: as it is where shadebench does too. */
        bool encoded = lit_channel && (tm == LOOK_TONEMAP_NONE ||
                                       spec->look.transfer != LOOK_TRANSFER_GAMMA_2_2);
        if (!(encoded ? reencode_png(cached, theirs, tm == LOOK_TONEMAP_NONE, err, errlen)
                      : copy_file(cached, theirs))) {
            if (!encoded)
                snprintf(err, errlen, "cannot copy %.400s to %.400s", cached, theirs);
            json_decref(channels);
            goto out;
        }
        snprintf(mine, sizeof(mine), "%s",
                 json_string_value(json_object_get(json_object_get(ours, names[i]), "source")));
        if (lit_channel) {
            char copy[PATH_MAX + 160];
            snprintf(copy, sizeof(copy), "%s/shadebench-lit.png", dir);
            copy_file(mine, copy);
        }
        json_t *m = compare_channel(dir, names[i], mine, theirs, err, errlen);
        if (!m) {
            json_decref(channels);
            goto out;
        }
        char a[PATH_MAX], b[PATH_MAX], c[PATH_MAX], d[PATH_MAX];
        snprintf(a, sizeof(a), FIDELITY_DIR "/shadebench-%s.png", names[i]);
        snprintf(b, sizeof(b), FIDELITY_DIR "/khronos-%s.png", names[i]);
        snprintf(c, sizeof(c), FIDELITY_DIR "/ssim-%s.png", names[i]);
        snprintf(d, sizeof(d), FIDELITY_DIR "/flip-%s.png", names[i]);
        json_object_set_new(m, "files", json_pack("{s:s, s:s, s:s, s:s}", "shadebench", a,
                                                  "khronos", b, "ssim_map", c, "flip_map", d));
        json_object_set_new(channels, names[i], m);
        if (lit_channel)
            lit = m;
    }
    /* Channels shadebench could not draw (look.debug refused them). */
    const char *key2;
    json_t *v;
    json_object_foreach(ours, key2, v)
        if (json_object_get(v, "error"))
            json_object_set_new(channels, key2, json_pack("{s:O}", "error",
                                                          json_object_get(v, "error")));
    json_t *per = json_object_get(cost, "channels");
    json_t *costs = json_object();
    size_t i;
    json_t *c;
    json_array_foreach(per, i, c)
        json_object_set(costs, json_string_value(json_object_get(c, "name")),
                        json_object_get(c, "render_ms"));
    json_t *fid = json_pack(
        "{s:s, s:s, s:s, s:b, s:s, s:o, s:{s:O, s:O, s:O, s:O, s:O, s:o, s:b}, s:O, s:O, s:o, s:O, s:o}",
        "renderer", "khronos", "viewer", REFERENCE_VIEWER_PACKAGE "@" REFERENCE_VIEWER_VERSION,
        "browser", json_string_value(json_object_get(cost, "browser")) ?
                       json_string_value(json_object_get(cost, "browser")) : "",
        "cache_hit", hit, "cache_key", key, "channels", channels, "cost",
        "chromium_start_ms", json_object_get(cost, "chromium_start_ms") ?
                                 json_object_get(cost, "chromium_start_ms") : json_null(),
        "page_ms", json_object_get(cost, "page_ms") ? json_object_get(cost, "page_ms") : json_null(),
        "load_ms", json_object_get(cost, "load_ms") ? json_object_get(cost, "load_ms") : json_null(),
        "environment_ms", json_object_get(cost, "environment_ms") ?
                              json_object_get(cost, "environment_ms") : json_null(),
        "total_ms", json_object_get(cost, "total_ms") ? json_object_get(cost, "total_ms") : json_null(),
        "render_ms", costs, "this_job_rendered", !hit,
        "webgl_renderer", json_object_get(cost, "webgl_renderer") ?
                              json_object_get(cost, "webgl_renderer") : json_null(),
        "frame", json_object_get(t->view, "frame"), "camera",
        json_pack("{s:O, s:O, s:O}", "view_matrix", json_object_get(t->view, "view"),
                  "projection_matrix", json_object_get(t->view, "projection"), "eye",
                  json_object_get(t->view, "eye")),
        "lights", json_object_get(t->view, "lights"),
        "viewer_settings", json_pack("{s:O, s:O, s:O, s:O, s:o}", "tonemap",
                                      json_object_get(page, "tonemap"), "exposure",
                                      json_object_get(page, "exposure"), "ibl_intensity",
                                      json_object_get(page, "ibl_intensity"), "environment_file",
                                      json_object_get(page, "environment_file"), "ibl_sampler",
                                      reference_sampler_to_json(&sampler)));
    /* The nodes whose mirrored matrix the page restated for the viewer
     * (page.js: restateMirroredMatrices), what it changed in the viewer
     * (page.js: viewer_patches), and each rasteriser's sub-pixel
     * precision. */
    json_t *restated = json_object_get(cost, "mirrored_matrices_restated");
    json_object_set_new(fid, "mirrored_matrices_restated",
                        json_is_array(restated) ? json_incref(restated) : json_array());
    json_t *patches = json_object_get(cost, "viewer_patches");
    json_object_set_new(fid, "viewer_patches",
                        json_is_array(patches) ? json_incref(patches) : json_array());
    json_object_set_new(fid, "subpixel_bits",
                        json_pack("{s:O, s:O}", "shadebench",
                                  json_object_get(t->view, "subpixel_bits") ?
                                      json_object_get(t->view, "subpixel_bits") : json_null(),
                                  "khronos", json_object_get(cost, "subpixel_bits") ?
                                      json_object_get(cost, "subpixel_bits") : json_null()));
    if (lit)
        json_object_set_new(fid, "lit_transfer",
                            json_string(spec->look.tonemap == LOOK_TONEMAP_NONE
                                            ? "the viewer's gamma 2.2 decoded to linear, as "
                                              "tonemap none writes"
                                        : spec->look.transfer == LOOK_TRANSFER_GAMMA_2_2
                                            ? "gamma 2.2, both (look.transfer)"
                                            : "the viewer's gamma 2.2 re-encoded as sRGB"));
    json_object_set_new(t->result, "fidelity", fid);
    ok = true;
out:
    json_decref(todo);
    json_decref(page);
    json_decref(cost);
    return ok;
}

static void finish_task(struct fidelity *f, struct task *t)
{
    struct job *job = t->job;
    enum job_status status = JOB_FAILED;
    char err[1024] = "";
    double t0 = clock_mono_s();
    bool ok = finish_fidelity(f, t, &status, err, sizeof(err));
    if (ok) {
        json_object_set_new(json_object_get(t->result, "fidelity"), "fidelity_s",
                            json_real(clock_mono_s() - t0));
        char path[PATH_MAX + 16];
        job_file_path(job->dir, JOB_FILE_RESULT, path, sizeof(path));
        if (!fs_write_json_atomic(path, t->result)) {
            ok = false;
            snprintf(err, sizeof(err), "cannot write %.400s: %s", path, strerror(errno));
        }
    }
    if (ok) {
        LOG(LOG_INFO, "job %s done: fidelity against the Khronos viewer", job->id);
        queue_finish(f->queue, job, JOB_DONE, NULL, t->result);
    } else {
        if (status != JOB_CANCELLED && job_timed_out(job))
            job_timeout_message(job, "fidelity", "", err, sizeof(err));
        LOG(LOG_WARN, "job %s %s: %s", job->id, job_status_name(status), err);
        queue_finish(f->queue, job, status, err, NULL);
        json_decref(t->result);
    }
    json_decref(t->view);
    free(t);
}

static void *worker_main(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-fidelity"); /* named in crash reports, top, gdb */
    struct fidelity *f = arg;
    pthread_mutex_lock(&f->lock);
    for (;;) {
        while (!f->head && !f->stopping)
            pthread_cond_wait(&f->wake, &f->lock);
        if (!f->head)
            break;
        struct task *t = f->head;
        f->head = t->next;
        if (!f->head)
            f->tail = NULL;
        f->busy = true;
        pthread_mutex_unlock(&f->lock);
        finish_task(f, t);
        pthread_mutex_lock(&f->lock);
        f->busy = false;
        pthread_cond_broadcast(&f->idle);
    }
    pthread_mutex_unlock(&f->lock);
    return NULL;
}

struct fidelity *fidelity_create(const struct fidelity_config *cfg, struct queue *q)
{
    struct fidelity *f = calloc(1, sizeof(*f));
    if (!f)
        return NULL;
    f->cfg = *cfg;
    snprintf(f->state_dir, sizeof(f->state_dir), "%s", cfg->state_dir && cfg->state_dir[0]
                                                           ? cfg->state_dir : ".");
    f->queue = q;
    reference_paths_find(&f->paths, cfg->chromium, cfg->viewer_dir, cfg->page_dir, cfg->program,
                         cfg->pkgdatadir);
    pthread_mutex_init(&f->lock, NULL);
    pthread_cond_init(&f->wake, NULL);
    pthread_cond_init(&f->idle, NULL);
    if (pthread_create(&f->thread, NULL, worker_main, f) != 0) {
        fidelity_destroy(f);
        return NULL;
    }
    f->started = true;
    if (f->paths.missing[0])
        LOG(LOG_INFO, "the Khronos reference (fidelity jobs) is not available: %s",
            f->paths.missing);
    return f;
}

void fidelity_destroy(struct fidelity *f)
{
    if (!f)
        return;
    if (f->started) {
        pthread_mutex_lock(&f->lock);
        f->stopping = true;
        pthread_cond_broadcast(&f->wake);
        pthread_mutex_unlock(&f->lock);
        pthread_join(f->thread, NULL);
    }
    pthread_mutex_destroy(&f->lock);
    pthread_cond_destroy(&f->wake);
    pthread_cond_destroy(&f->idle);
    free(f);
}

bool fidelity_available(const struct fidelity *f, char *why, size_t whylen)
{
    if (!f) {
        snprintf(why, whylen, "this daemon runs no fidelity worker");
        return false;
    }
    snprintf(why, whylen, "%s", f->paths.missing);
    return !f->paths.missing[0];
}

json_t *fidelity_info_json(const struct fidelity *f)
{
    char why[600];
    bool ok = fidelity_available(f, why, sizeof(why));
    json_t *o = json_pack("{s:b, s:s, s:s, s:f, s:f}", "available", ok, "renderer",
                          "khronos", "viewer", REFERENCE_VIEWER_PACKAGE "@" REFERENCE_VIEWER_VERSION,
                          "timeout_s", f && f->cfg.timeout_s > 0 ? f->cfg.timeout_s
                                                                 : FIDELITY_TIMEOUT_S,
                          "memory_bytes", (double)(f && f->cfg.memory_bytes ? f->cfg.memory_bytes
                                                                            : FIDELITY_MEMORY));
    if (!ok)
        json_object_set_new(o, "missing", json_string(why));
    if (f) {
        json_object_set_new(o, "chromium", json_string(f->paths.chromium));
        json_object_set_new(o, "viewer_dir", json_string(f->paths.viewer_dir));
    }
    return o;
}

void fidelity_submit(struct fidelity *f, struct job *job, json_t *result, json_t *view)
{
    struct task *t = calloc(1, sizeof(*t));
    if (!t) {
        queue_finish(f->queue, job, JOB_FAILED, "fidelity: out of memory", NULL);
        json_decref(result);
        json_decref(view);
        return;
    }
    *t = (struct task){.job = job, .result = result, .view = view};
    pthread_mutex_lock(&f->lock);
    if (f->tail)
        f->tail->next = t;
    else
        f->head = t;
    f->tail = t;
    pthread_cond_signal(&f->wake);
    pthread_mutex_unlock(&f->lock);
}

void fidelity_wait_idle(struct fidelity *f)
{
    if (!f)
        return;
    pthread_mutex_lock(&f->lock);
    while (f->head || f->busy)
        pthread_cond_wait(&f->idle, &f->lock);
    pthread_mutex_unlock(&f->lock);
}
