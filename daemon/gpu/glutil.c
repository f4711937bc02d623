#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/glutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "daemon/gpu/shaders.h"

/* Only the render thread touches GL, so plain statics are enough here. */
static char pending_error[512];

static const char *shader_lookup(const char *name)
{
    for (const struct shader_file *f = shader_files; f->name; f++)
        if (strcmp(f->name, name) == 0)
            return f->source;
    return NULL;
}

/* Logs each embedded file numbered as the driver counts it ("file:line",
 * thanks to the "#line 1 file" directive before each file). */
static void log_numbered(const char *label, const struct gl_stage *st)
{
    for (int i = 0; i < 4 && st->files[i]; i++) {
        const char *p = shader_lookup(st->files[i]);
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
    const char *parts[16];
    char lines[4][48];
    int n = 0;
    parts[n++] = "#version 430 core\n";
    parts[n++] = defines ? defines : "";
    for (int i = 0; i < 4 && st->files[i]; i++) {
        const char *src = shader_lookup(st->files[i]);
        if (!src) {
            snprintf(err, errlen, "%s: no embedded shader named %s", label, st->files[i]);
            return 0;
        }
        /* "#line 1 i" makes driver messages read "i(line)" per file. */
        snprintf(lines[i], sizeof(lines[i]), "#line 1 %d\n", i);
        parts[n++] = lines[i];
        parts[n++] = src;
        /* Fault injection for the tests: proves that a shader the driver
         * rejects fails only its job, with the driver's message. */
        const char *fault = getenv("SHADEBENCH_FAULT_SHADER");
        if (fault && strcmp(fault, st->files[i]) == 0)
            parts[n++] = "\nthis line is not GLSL;\n";
    }
    GLuint sh = glCreateShader(st->type);
    glShaderSource(sh, n, parts, NULL);
    glCompileShader(sh);
    GLint ok = GL_FALSE;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (ok)
        return sh;
    char log[1024] = "";
    glGetShaderInfoLog(sh, sizeof(log), NULL, log);
    const char *main_file = st->files[0];
    for (int i = 1; i < 4 && st->files[i]; i++)
        main_file = st->files[i];
    LOG(LOG_ERROR, "%s: compiling %s failed: %s", label, main_file, log);
    for (int i = 0; i < 4 && st->files[i]; i++)
        LOG(LOG_ERROR, "%s: file %d is %s", label, i, st->files[i]);
    log_numbered(label, st);
    char numbering[256] = "";
    for (int i = 0, used = 0; i < 4 && st->files[i] && used < (int)sizeof(numbering); i++)
        used += snprintf(numbering + used, sizeof(numbering) - (size_t)used, "%s%d = %s",
                         i ? ", " : "", i, st->files[i]);
    snprintf(err, errlen, "%s: %s failed to compile (files: %s): %s", label, main_file,
             numbering, log);
    glDeleteShader(sh);
    return 0;
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
