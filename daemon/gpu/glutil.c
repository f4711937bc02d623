#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/glutil.h"

#include <pwd.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"
#include "daemon/gpu/shaders.h"

/* Only the render thread touches GL, so plain statics are enough here. */
static char pending_error[512];
/* The open build log, whether a timed region is running, and the sources
 * this process has built (a hash of each program's stages), to tell a
 * program's first build from a repeat. */
static struct gl_build_log *build_log;
static bool timed_region;
enum { SEEN_MAX = 4096 };
static uint64_t seen[SEEN_MAX];
static int seen_count;

static uint64_t fnv1a(uint64_t h, const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        h = (h ^ (unsigned char)s[i]) * 1099511628211ull;
    return h;
}

/* True when this process built sources hashing to h before; remembers h. */
static bool seen_before(uint64_t h)
{
    for (int i = 0; i < seen_count; i++)
        if (seen[i] == h)
            return true;
    if (seen_count < SEEN_MAX)
        seen[seen_count++] = h;
    return false;
}

static const struct shader_file *shader_entry(const char *name)
{
    for (const struct shader_file *f = shader_files; f->name; f++)
        if (strcmp(f->name, name) == 0)
            return f;
    return NULL;
}

static const char *shader_lookup(const char *name)
{
    const struct shader_file *f = shader_entry(name);
    return f ? f->source : NULL;
}

/* A stage's source with every #include expanded in place, each file once,
 * and "#line N id" markers so that driver messages read "id(line)". */
#define STAGE_MAX_FILES 24
struct expansion {
    char *text;
    size_t len, cap;
    const char *files[STAGE_MAX_FILES];
    int nfiles;
};

static bool append(struct expansion *x, const char *s, size_t n)
{
    if (x->len + n + 1 > x->cap) {
        size_t cap = (x->cap ? x->cap * 2 : 16384) + n;
        char *t = realloc(x->text, cap);
        if (!t)
            return false;
        x->text = t;
        x->cap = cap;
    }
    memcpy(x->text + x->len, s, n);
    x->len += n;
    x->text[x->len] = '\0';
    return true;
}

/* The file named by an '#include "name"' line, or false for other lines. */
static bool include_name(const char *line, size_t len, char *name, size_t cap)
{
    size_t i = 0;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        i++;
    if (len - i < 9 || strncmp(line + i, "#include", 8) != 0)
        return false;
    const char *q = memchr(line + i + 8, '"', len - i - 8);
    const char *e = q ? memchr(q + 1, '"', len - (size_t)(q + 1 - line)) : NULL;
    if (!q || !e || (size_t)(e - q - 1) >= cap)
        return false;
    snprintf(name, cap, "%.*s", (int)(e - q - 1), q + 1);
    return true;
}

static bool expand(struct expansion *x, const char *name, int depth, const char *label,
                   char *err, size_t errlen)
{
    for (int i = 0; i < x->nfiles; i++)
        if (strcmp(x->files[i], name) == 0)
            return true; /* each file once: includes need no guards */
    const struct shader_file *entry = shader_entry(name);
    if (!entry) {
        snprintf(err, errlen, "%s: no embedded shader named %s", label, name);
        return false;
    }
    const char *src = entry->source;
    if (depth > 8 || x->nfiles >= STAGE_MAX_FILES) {
        snprintf(err, errlen, "%s: includes nest too deep at %s", label, name);
        return false;
    }
    int id = x->nfiles;
    x->files[x->nfiles++] = entry->name; /* static: name may be the caller's buffer */
    char mark[48];
    int n = snprintf(mark, sizeof(mark), "#line 1 %d\n", id);
    if (!append(x, mark, (size_t)n))
        goto oom;
    int line = 1;
    for (const char *p = src; *p; line++) {
        const char *nl = strchr(p, '\n');
        size_t len = nl ? (size_t)(nl - p) : strlen(p);
        char inc[64];
        if (include_name(p, len, inc, sizeof(inc))) {
            if (!expand(x, inc, depth + 1, label, err, errlen))
                return false;
            n = snprintf(mark, sizeof(mark), "#line %d %d\n", line + 1, id);
            if (!append(x, mark, (size_t)n))
                goto oom;
        } else if (!append(x, p, len) || !append(x, "\n", 1)) {
            goto oom;
        }
        p += len + (nl ? 1 : 0);
    }
    /* Fault injection for the tests: proves that a shader the driver
     * rejects fails only its job, with the driver's message. */
    const char *fault = getenv("SHADEBENCH_FAULT_SHADER");
    if (fault && strcmp(fault, name) == 0 && !append(x, "\nthis line is not GLSL;\n", 24))
        goto oom;
    return true;
oom:
    snprintf(err, errlen, "%s: out of memory expanding %s", label, name);
    return false;
}

/* Logs each file of the stage numbered as the driver counts it. */
static void log_numbered(const char *label, const struct expansion *x)
{
    for (int i = 0; i < x->nfiles; i++) {
        LOG(LOG_ERROR, "%s: file %d is %s", label, i, x->files[i]);
        const char *p = shader_lookup(x->files[i]);
        for (int line = 1; p && *p; line++) {
            const char *nl = strchr(p, '\n');
            int len = nl ? (int)(nl - p) : (int)strlen(p);
            LOG(LOG_ERROR, "%s %d:%-4d| %.*s", label, i, line, len, p);
            p += len + (nl ? 1 : 0);
        }
    }
}

static GLuint compile_stage(const char *label, const struct gl_stage *st,
                            const char *defines, uint64_t *hash, char *err, size_t errlen)
{
    struct expansion x = {0};
    GLuint sh = 0;
    const char *head = "#version 430 core\n";
    if (!append(&x, head, strlen(head)) ||
        (defines && !append(&x, defines, strlen(defines)))) {
        snprintf(err, errlen, "%s: out of memory", label);
        goto out;
    }
    /* Binding numbers come from the header the C code includes. */
    if (!expand(&x, "bindings.h", 0, label, err, errlen))
        goto out;
    for (int i = 0; i < 4 && st->files[i]; i++)
        if (!expand(&x, st->files[i], 0, label, err, errlen))
            goto out;
    *hash = fnv1a(fnv1a(*hash, (const char *)&st->type, sizeof(st->type)), x.text, x.len);
    sh = glCreateShader(st->type);
    const char *text = x.text;
    glShaderSource(sh, 1, &text, NULL);
    glCompileShader(sh);
    GLint ok = GL_FALSE;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (ok)
        goto out;
    char log[1024] = "";
    glGetShaderInfoLog(sh, sizeof(log), NULL, log);
    const char *main_file = st->files[0];
    for (int i = 1; i < 4 && st->files[i]; i++)
        main_file = st->files[i];
    LOG(LOG_ERROR, "%s: compiling %s failed: %s", label, main_file, log);
    log_numbered(label, &x);
    char numbering[384] = "";
    for (int i = 0, used = 0; i < x.nfiles && used < (int)sizeof(numbering); i++)
        used += snprintf(numbering + used, sizeof(numbering) - (size_t)used, "%s%d = %s",
                         i ? ", " : "", i, x.files[i]);
    snprintf(err, errlen, "%s: %s failed to compile (files: %s): %s", label, main_file,
             numbering, log);
    glDeleteShader(sh);
    sh = 0;
out:
    free(x.text);
    return sh;
}

static void record_build(const char *label, int stages, double compile_ms, double link_ms,
                         uint64_t hash)
{
    bool repeat = seen_before(hash);
    if (timed_region)
        LOG(LOG_WARN, "%s: a program built inside the timed region (%.1f ms): the frame times "
            "include it", label, compile_ms + link_ms);
    struct gl_build_log *log = build_log;
    if (!log)
        return;
    log->compile_ms += compile_ms;
    log->link_ms += link_ms;
    log->seen_before += repeat;
    log->in_timed_region += timed_region;
    if (log->count == log->cap) {
        int cap = log->cap ? log->cap * 2 : 32;
        struct gl_build_record *r = cap <= 1024 ? realloc(log->records, (size_t)cap * sizeof(*r))
                                                : NULL;
        if (!r) {
            log->dropped++;
            return;
        }
        log->records = r;
        log->cap = cap;
    }
    struct gl_build_record *r = &log->records[log->count++];
    snprintf(r->label, sizeof(r->label), "%s", label);
    r->stages = stages;
    r->compile_ms = compile_ms;
    r->link_ms = link_ms;
    r->seen_before = repeat;
    r->in_timed_region = timed_region;
}

GLuint gl_program_build(const char *label, const struct gl_stage *stages,
                        int stage_count, const char *defines, char *err,
                        size_t errlen)
{
    GLuint prog = glCreateProgram(), shaders[4] = {0};
    uint64_t hash = 1469598103934665603ull;
    /* Wall time of each step up to its status query, which waits for a
     * driver that compiles in the background. */
    double t0 = clock_mono_s();
    for (int i = 0; i < stage_count; i++) {
        shaders[i] = compile_stage(label, &stages[i], defines, &hash, err, errlen);
        if (!shaders[i])
            goto fail;
        glAttachShader(prog, shaders[i]);
    }
    double t1 = clock_mono_s();
    glLinkProgram(prog);
    GLint ok = GL_FALSE;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    double t2 = clock_mono_s();
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(prog, sizeof(log), NULL, log);
        LOG(LOG_ERROR, "%s: link failed: %s", label, log);
        snprintf(err, errlen, "%s: program link failed: %s", label, log);
        goto fail;
    }
    for (int i = 0; i < stage_count; i++)
        glDeleteShader(shaders[i]);
    record_build(label, stage_count, (t1 - t0) * 1e3, (t2 - t1) * 1e3, hash);
    return prog;
fail:
    for (int i = 0; i < stage_count; i++)
        if (shaders[i])
            glDeleteShader(shaders[i]);
    glDeleteProgram(prog);
    return 0;
}

void gl_build_log_begin(struct gl_build_log *log)
{
    memset(log, 0, sizeof(*log));
    build_log = log;
}

void gl_build_log_end(void) { build_log = NULL; }

void gl_build_log_free(struct gl_build_log *log)
{
    if (build_log == log)
        build_log = NULL;
    free(log->records);
    memset(log, 0, sizeof(*log));
}

void gl_build_timed_region(bool inside) { timed_region = inside; }

static bool env_true(const char *name)
{
    const char *v = getenv(name);
    return v && (!strcmp(v, "1") || !strcasecmp(v, "true") || !strcasecmp(v, "yes"));
}

/* $XDG_CACHE_HOME, else the home folder's .cache (getpwuid where HOME is unset). */
static void cache_home(char *out, size_t cap)
{
    const char *xdg = getenv("XDG_CACHE_HOME");
    if (xdg && xdg[0] == '/') {
        snprintf(out, cap, "%s", xdg);
        return;
    }
    const char *home = getenv("HOME");
    struct passwd *pw = home && home[0] ? NULL : getpwuid(getuid());
    snprintf(out, cap, "%s/.cache", home && home[0] ? home : pw && pw->pw_dir ? pw->pw_dir : "");
}

json_t *gl_shader_cache_json(void)
{
    const char *vendor = (const char *)glGetString(GL_VENDOR);
    const char *version = (const char *)glGetString(GL_VERSION);
    bool nvidia = vendor && strstr(vendor, "NVIDIA");
    bool mesa = version && strstr(version, "Mesa");
    char dir[1100] = "", home[1024], set_by[256];
    bool on;
    const char *driver;
    if (nvidia) {
        driver = "nvidia";
        const char *v = getenv("__GL_SHADER_DISK_CACHE");
        on = !(v && !strcmp(v, "0"));
        snprintf(set_by, sizeof(set_by), "%s", v ? "__GL_SHADER_DISK_CACHE" :
                 "__GL_SHADER_DISK_CACHE unset: NVIDIA's default (on)");
        const char *path = getenv("__GL_SHADER_DISK_CACHE_PATH");
        cache_home(home, sizeof(home));
        if (path && path[0])
            snprintf(dir, sizeof(dir), "%s", path);
        else
            snprintf(dir, sizeof(dir), "%s/nvidia/GLCache", home);
    } else if (mesa) {
        driver = "mesa";
        bool off = env_true("MESA_SHADER_CACHE_DISABLE") || env_true("MESA_GLSL_CACHE_DISABLE");
        on = !off;
        snprintf(set_by, sizeof(set_by), "%s",
                 getenv("MESA_SHADER_CACHE_DISABLE") ? "MESA_SHADER_CACHE_DISABLE"
                 : getenv("MESA_GLSL_CACHE_DISABLE") ? "MESA_GLSL_CACHE_DISABLE"
                 : "MESA_SHADER_CACHE_DISABLE unset: Mesa's default (on)");
        const char *path = getenv("MESA_SHADER_CACHE_DIR");
        if (!path || !path[0])
            path = getenv("MESA_GLSL_CACHE_DIR");
        cache_home(home, sizeof(home));
        /* Mesa keeps its files in mesa_shader_cache under the folder named. */
        snprintf(dir, sizeof(dir), "%s/mesa_shader_cache", path && path[0] ? path : home);
    } else {
        driver = "other";
        on = false;
        snprintf(set_by, sizeof(set_by), "not known for this driver (GL_VENDOR %s)",
                 vendor ? vendor : "?");
    }
    GLint formats = 0;
    glGetIntegerv(GL_NUM_PROGRAM_BINARY_FORMATS, &formats);
    json_t *j = json_pack("{s:s, s:s, s:i}", "driver", driver, "set_by", set_by,
                          "program_binary_formats", formats);
    if (strcmp(driver, "other") == 0) {
        json_object_set_new(j, "disk_cache", json_null());
        return j;
    }
    struct stat st;
    bool exists = stat(dir, &st) == 0 && S_ISDIR(st.st_mode);
    json_object_set_new(j, "disk_cache", json_string(on ? "on" : "off"));
    json_object_set_new(j, "dir", json_string(dir));
    json_object_set_new(j, "dir_exists", json_boolean(exists));
    json_object_set_new(j, "dir_writable", json_boolean(exists && access(dir, W_OK) == 0));
    return j;
}

json_t *gl_build_log_json(const struct gl_build_log *log)
{
    json_t *programs = json_array();
    for (int i = 0; i < log->count; i++) {
        const struct gl_build_record *r = &log->records[i];
        json_array_append_new(programs,
                              json_pack("{s:s, s:i, s:f, s:f, s:f, s:b}", "label", r->label,
                                        "stages", r->stages, "compile_ms", r->compile_ms,
                                        "link_ms", r->link_ms, "total_ms",
                                        r->compile_ms + r->link_ms, "seen_before",
                                        r->seen_before));
    }
    int n = log->count + log->dropped;
    return json_pack(
        "{s:i, s:f, s:f, s:f, s:i, s:i, s:o, s:o, s:s}", "count", n, "compile_ms", log->compile_ms,
        "link_ms", log->link_ms, "total_ms", log->compile_ms + log->link_ms, "seen_before",
        log->seen_before, "in_timed_region", log->in_timed_region, "programs", programs, "cache",
        gl_shader_cache_json(), "method",
        "every program the run's set-up built (the technique, the look's stages, the post "
        "chain; the resolve programs are built once when the context comes up): wall time "
        "(CLOCK_MONOTONIC) of glShaderSource and glCompileShader of its stages up to "
        "GL_COMPILE_STATUS, and of glLinkProgram up to GL_LINK_STATUS, before the warm-up "
        "frames, outside the timed region. seen_before: this daemon process built the same "
        "sources before, so where the driver's disk cache is on the build was a cache hit; "
        "a program not seen before may still hit a cache an earlier process filled. A "
        "driver that defers work to the first draw moves it into the first warm-up frame, "
        "which is not timed");
}

static void GLAPIENTRY debug_callback(GLenum source, GLenum type, GLuint id,
                                      GLenum severity, GLsizei length,
                                      const GLchar *message, const void *user)
{
    (void)source, (void)length, (void)user;
    enum log_level level = LOG_DEBUG;
    if (type == GL_DEBUG_TYPE_ERROR)
        level = LOG_ERROR;
    else if (severity == GL_DEBUG_SEVERITY_HIGH || severity == GL_DEBUG_SEVERITY_MEDIUM)
        level = LOG_WARN;
    LOG(level, "GL debug (id %u): %s", id, message);
    if (type == GL_DEBUG_TYPE_ERROR && !pending_error[0])
        snprintf(pending_error, sizeof(pending_error), "%s", message);
}

void gl_debug_install(void)
{
    if (!epoxy_has_gl_extension("GL_KHR_debug") && epoxy_gl_version() < 43)
        return;
    glEnable(GL_DEBUG_OUTPUT);
    glDebugMessageCallback(debug_callback, NULL);
    /* Notifications are chatty (buffer placement hints) and say nothing about
     * correctness; keep them out unless debug logging is on. */
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DEBUG_SEVERITY_NOTIFICATION,
                          0, NULL, log_get_level() <= LOG_DEBUG);
}

bool gl_error_take(const char *where, char *err, size_t errlen)
{
    GLenum code = glGetError();
    bool any = pending_error[0] || code != GL_NO_ERROR;
    if (any) {
        if (pending_error[0])
            snprintf(err, errlen, "GL error during %s: %s", where, pending_error);
        else
            snprintf(err, errlen, "GL error during %s: glGetError 0x%04x", where, code);
        while (glGetError() != GL_NO_ERROR)
            ;
    }
    pending_error[0] = '\0';
    return any;
}
