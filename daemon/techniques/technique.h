#ifndef SHADEBENCH_TECHNIQUE_H
#define SHADEBENCH_TECHNIQUE_H

/* The contract between the harness and a shading technique (GL side). The
 * harness owns warm-up, timing, capture, the resolve to 8 bits and the
 * statistics; a technique draws each frame into the HDR output it is handed,
 * in the passes its info declares. Every hook runs on the render thread. */

#include <epoxy/gl.h>
#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "daemon/gpu/budget.h"
#include "daemon/gpu/caps.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/gpu/targets.h"
#include "daemon/lighting/look_spec.h"
#include "daemon/scene/scene.h"
#include "daemon/techniques/technique_info.h"

/* What a technique may publish for the harness after create (0 = none):
 * post effects read normals from a g-buffer when there is one (SSAO), else
 * rebuild them from the depth texture; a light-culling technique publishes
 * how many lights it evaluated per pixel, which the harness captures as a
 * heat map beside the colour captures. */
enum technique_normal_encoding {
    TECHNIQUE_NORMAL_FLOAT3,     /* rgb = world-space unit normal */
    TECHNIQUE_NORMAL_OCTAHEDRAL, /* rg = octahedral world-space normal in [-1, 1] */
};

struct technique_products {
    GLuint normal_tex;
    int normal_encoding; /* enum technique_normal_encoding */
    GLuint heat_tex;     /* GL_R32UI, width x height: light evaluations this frame */
};

/* What the harness hands a technique: what it needs to render a frame, and
 * nothing of the job it serves. Valid from create to destroy. */
struct technique_env {
    /* The run's frames: warmup_frames warm-up frames (numbered from
     * 1 - warmup_frames to 0), then the timed frames 1..frames. Timed frame
     * k is captured when capture_interval > 0 and k is a multiple of it
     * (technique_env_captures); 0 captures none. */
    int frames, warmup_frames, capture_interval;
    /* The look this run renders with: the job's, or the reference's
     * reference_look (lighting model, materials a g-buffer must carry). */
    const struct look_spec *look;
    const void *options; /* the technique's own options struct (its info's layout) */
    const struct scene *scene;
    struct gpu_scene *gpu;
    const struct gpu_caps *caps;
    struct gpu_targets *targets;    /* ask for extra planes by name */
    const struct gpu_passes *passes; /* index i is info->passes[i] */
    /* The output: HDR colour (look->hdr format) and a depth texture that
     * later passes may sample, both width x height, attached to output_fbo. */
    GLuint output_fbo, output_color, output_depth;
    int width, height;
    /* MSAA samples a pixel of the output (the job's "msaa"): 1, or 2 to 8,
     * when output_color and output_depth are GL_TEXTURE_2D_MULTISAMPLE
     * (bind and attach them as such; gpu_targets_kind says which) that the
     * harness resolves after the technique's passes. A technique that
     * samples the depth (tile depth bounds, a g-buffer) reads every sample;
     * planes it draws beside the output take the same count. */
    int samples;
    /* #define lines for the look (lighting model), to pass to
     * gl_program_build for every program that lights. */
    const char *defines;
    /* Zeroed by the harness before create; the technique fills what it has. */
    struct technique_products *products;
    /* Bounded submissions (daemon/gpu/budget.h): a pass whose work may be
     * large draws it in tiles (gpu_tiles_*) or takes checkpoints in its
     * loops (gpu_loop_*), and render returns false, err "stopped", once
     * gpu_budget_stopped. */
    struct gpu_budget *budget;
    /* The frame contract's time during render (gpu/pass.h): the frame,
     * whether a history the technique keeps (its info's needs) restarts at
     * it, and the projection's jitter (already in the frame block). */
    const struct gpu_frame_time *time;
};

/* After a pass drew in tiles or took checkpoints: false, err "stopped",
 * once the budget was told to stop (the harness then says why). */
static inline bool technique_keep_going(const struct technique_env *env, char *err,
                                        size_t errlen)
{
    if (!gpu_budget_stopped(env->budget))
        return true;
    snprintf(err, errlen, "stopped");
    return false;
}

struct technique {
    const struct technique_info *info;
    /* Builds programs and resources and checks the job against env->caps.
     * Called once per run, outside the timed region; may take any GL state. */
    bool (*create)(const struct technique_env *env, void **state, char *err, size_t errlen);
    /* Draws frame (timed frames are 1..frames, warm-up frames <= 0) into
     * env->output_fbo, one gpu_pass_begin/end per declared pass, in order.
     * Timed (CPU and GPU): no allocation, no readback, no uniform lookups.
     * May assume the baseline state of gpu_pass_begin and the frame block
     * bound; must leave the output framebuffer's attachments as they are. */
    bool (*render)(void *state, const struct technique_env *env, int64_t frame, char *err,
                   size_t errlen);
    /* Optional. After the last timed frame has finished on the GPU, outside
     * the timed region: fails the job (false, err naming the option) when
     * the frames recorded a failure only the GPU saw, such as a light list
     * that overflowed under overflow "fail". */
    bool (*verify)(void *state, char *err, size_t errlen);
    /* Technique-specific figures for the result (timed frames only); NULL
     * when it has none. Called after the last timed frame. */
    json_t *(*describe)(void *state);
    /* Frees everything create made. Accepts NULL. */
    void (*destroy)(void *state);
};

/* True when timed frame `frame` is captured: the harness reads the output
 * back after it, and a technique that publishes a heat map writes it. */
static inline bool technique_env_captures(const struct technique_env *env, int64_t frame)
{
    return env->capture_interval > 0 && frame >= 1 && frame <= env->frames &&
           frame % env->capture_interval == 0;
}

/* The GL half of the registry: every registered technique, in the order of
 * technique_infos (each folder's technique_NAME), NULL-terminated. */
extern const struct technique *const technique_registry[];

const struct technique *technique_find(const char *name);
int technique_pass_count(const struct technique *t);

/* Checks a technique's GL half: its info and its mandatory hooks. */
bool technique_check(const struct technique *t, char *err, size_t errlen);
/* Checks every registered technique (technique_check) and that the GL
 * registry follows technique_infos; at start-up, before any job. */
bool technique_registry_check(char *err, size_t errlen);

#endif
