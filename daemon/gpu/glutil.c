#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/glutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "daemon/gpu/shaders.h"

/* Only the render thread touches GL, so plain statics are enough here. */
static char pending_error[512];

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
                            const char *defines, char *err, size_t errlen)
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

GLuint gl_program_build(const char *label, const struct gl_stage *stages,
                        int stage_count, const char *defines, char *err,
                        size_t errlen)
{
    GLuint prog = glCreateProgram(), shaders[4] = {0};
    for (int i = 0; i < stage_count; i++) {
        shaders[i] = compile_stage(label, &stages[i], defines, err, errlen);
        if (!shaders[i])
            goto fail;
        glAttachShader(prog, shaders[i]);
    }
    glLinkProgram(prog);
    GLint ok = GL_FALSE;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(prog, sizeof(log), NULL, log);
        LOG(LOG_ERROR, "%s: link failed: %s", label, log);
        snprintf(err, errlen, "%s: program link failed: %s", label, log);
        goto fail;
    }
    for (int i = 0; i < stage_count; i++)
        glDeleteShader(shaders[i]);
    return prog;
fail:
    for (int i = 0; i < stage_count; i++)
        if (shaders[i])
            glDeleteShader(shaders[i]);
    glDeleteProgram(prog);
    return 0;
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
