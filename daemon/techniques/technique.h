#ifndef SHADEBENCH_TECHNIQUE_H
#define SHADEBENCH_TECHNIQUE_H

/* The interface every shading technique implements. The job runner owns
 * warm-up, timing, capture and statistics; a technique only draws. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/gpu_timer.h"
#include "daemon/jobs/job_spec.h"
#include "daemon/scene/scene.h"

struct technique_ctx {
    const struct job_spec *spec;
    const struct scene *scene;
    struct gpu_scene *gpu;
    struct gpu_timer *timer; /* switch sections with gpu_timer_section() */
};

struct technique {
    const char *name;
    const char *summary;
    /* GPU timer sections in the order a frame enters them, NULL-terminated. */
    const char *const *sections;
    /* Builds programs and resources; checks GL limits against the job. */
    bool (*create)(const struct technique_ctx *ctx, void **state, char *err, size_t errlen);
    /* Draws frame (timed frames are 1..frames, warm-up frames are <= 0) into
     * the bound framebuffer. */
    bool (*render)(void *state, const struct technique_ctx *ctx, int64_t frame,
                   char *err, size_t errlen);
    /* Technique-specific figures for the result (timed frames only); may be NULL. */
    json_t *(*describe)(void *state);
    void (*destroy)(void *state);
};

extern const struct technique *const technique_registry[];

const struct technique *technique_find(const char *name);
/* NULL-terminated list of registered names, for job validation. */
const char *const *technique_names(void);
int technique_section_count(const struct technique *t);

/* Shared by the single-pass techniques (forward, unlit): scene.vert plus
 * one fragment shader. */
bool single_pass_create(const struct technique_ctx *ctx, const char *label, const char *frag,
                        void **state, char *err, size_t errlen);
bool single_pass_render(void *state, const struct technique_ctx *ctx,
                        int64_t frame, char *err, size_t errlen);
void single_pass_destroy(void *state);

#endif
