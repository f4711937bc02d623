#ifndef SHADEBENCH_GLUTIL_H
#define SHADEBENCH_GLUTIL_H

#include <epoxy/gl.h>
#include <jansson.h>
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

/* What building programs cost: each program's compile and link wall time,
 * kept by the log open on the render thread (a run's set-up opens one:
 * run.c). Programs built with no log open are timed but not kept. */
struct gl_build_record {
    char label[48];
    int stages;
    double compile_ms; /* glCompileShader of every stage, to its COMPILE_STATUS */
    double link_ms;    /* glLinkProgram to its LINK_STATUS */
    bool seen_before;  /* this process built the same sources before (a cache hit where the
                        * driver's disk cache is on) */
    bool in_timed_region;
};

struct gl_build_log {
    struct gl_build_record *records;
    int count, cap;
    int dropped; /* records past the cap (counted in the sums, not listed) */
    double compile_ms, link_ms;
    int seen_before, in_timed_region;
};

/* Opens log (zeroed by the call) for the programs built from now on; end
 * closes it; free releases its records (accepts a zeroed log). */
void gl_build_log_begin(struct gl_build_log *log);
void gl_build_log_end(void);
void gl_build_log_free(struct gl_build_log *log);
/* Marks the timed region (measure.c): a program built inside it is counted
 * in in_timed_region and logged as a warning, since its cost would be in
 * the frame times. */
void gl_build_timed_region(bool inside);
/* The result's "compile" object: programs (label, stages, compile_ms,
 * link_ms, seen_before), their sums, in_timed_region, the driver's shader
 * disk cache (gl_shader_cache_json) and how it is measured. Context current. */
json_t *gl_build_log_json(const struct gl_build_log *log);
/* The driver's shader disk cache as its environment sets it: Mesa's
 * (MESA_SHADER_CACHE_DISABLE, MESA_SHADER_CACHE_DIR) or NVIDIA's
 * (__GL_SHADER_DISK_CACHE, __GL_SHADER_DISK_CACHE_PATH), its folder and
 * whether it exists and is writable, and GL_NUM_PROGRAM_BINARY_FORMATS.
 * Context current. */
json_t *gl_shader_cache_json(void);

/* Routes KHR_debug messages into LOG and remembers the first error. */
void gl_debug_install(void);

/* Takes any GL error raised since the last call (debug callback message or
 * glGetError code). Returns false when there was none. */
bool gl_error_take(const char *where, char *err, size_t errlen);

#endif
