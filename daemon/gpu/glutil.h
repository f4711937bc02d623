#ifndef SHADEBENCH_GLUTIL_H
#define SHADEBENCH_GLUTIL_H

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

/* One stage of a program: the embedded files to concatenate, in order
 * (shared code first), after "#version 430 core" and the defines. */
struct gl_stage {
    GLenum type;
    const char *files[4];
};

/* Compiles and links; on failure logs the numbered source and puts the
 * driver's message into err. Returns 0 on failure. */
GLuint gl_program_build(const char *label, const struct gl_stage *stages,
                        int stage_count, const char *defines, char *err,
                        size_t errlen);

/* Routes KHR_debug messages into LOG and remembers the first error. */
void gl_debug_install(void);

/* Takes any GL error raised since the last call (debug callback message or
 * glGetError code). Returns false when there was none. */
bool gl_error_take(const char *where, char *err, size_t errlen);

#endif
