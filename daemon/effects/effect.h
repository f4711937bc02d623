#ifndef SHADEBENCH_EFFECT_H
#define SHADEBENCH_EFFECT_H

/* The GL half of a post effect: what the post chain (post_chain.h) calls to
 * build an effect for a run and to run it on a frame. An effect reads the
 * colour it is handed (HDR, full size, the look's format) plus the
 * technique's depth and normals, and writes its result into the framebuffer
 * it is handed; it times each of its passes with gpu_pass_begin/end, in the
 * order its info's active_passes lists them, starting at env->first_pass.
 * Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/effects/effect_info.h"
#include "daemon/gpu/budget.h"
#include "daemon/gpu/pass.h"
#include "daemon/gpu/targets.h"

/* What the chain hands an effect: the frame it works on, and nothing of the
 * technique that drew it or of the job. Valid from create to destroy. */
struct effect_env {
    int width, height;     /* of the frame and of dst */
    GLuint depth_tex;      /* the technique's depth texture */
    /* World-space normals the technique published, or 0: effects then
     * rebuild them from depth (normal_defines says which). */
    GLuint normal_tex;
    struct gpu_targets *targets; /* the pool effect_plane takes planes from */
    const struct gpu_passes *passes;
    int first_pass;      /* index of its first active pass */
    const char *label;   /* "bloom", "bloom2": prefixes its target names */
    GLenum hdr_format;   /* the look's HDR format, for the effect's colour planes */
    GLuint empty_vao;    /* for full-screen triangles (fullscreen.vert) */
    GLuint linear_sampler; /* bilinear, clamped: for reading a plane of another size */
    /* "#define HAVE_NORMAL_TEX 1" and its encoding when the technique
     * publishes normals, for programs that include post_common.glsl. */
    const char *normal_defines;
    /* Bounded submissions: effect_draw_fullscreen draws in tiles. */
    struct gpu_budget *budget;
    /* The harness's motion vectors (RG16F, pixels this frame minus the
     * frame before: daemon/harness/motion.h), drawn before the chain every
     * frame when an effect's needs ask for them; else 0. */
    GLuint motion_tex;
};

struct effect {
    const struct effect_info *info;
    /* Builds programs and asks the pool for planes. Outside the timed
     * region; may take any GL state. opts is the effect's options struct. */
    bool (*create)(const struct effect_env *env, const void *opts, void **state, char *err,
                   size_t errlen);
    /* One frame: reads src, writes dst_fbo (full size). time says which
     * frame, whether the history an effect keeps restarts at it (it then
     * reads none: frame k is a pure function of k) and the projection's
     * jitter. Timed: no allocation, no readback, no uniform lookups by
     * name. Leaves every sampler unit it bound to a sampler object unbound
     * again. False with err when the frame cannot be made (the job fails
     * with it). */
    bool (*run)(void *state, const struct effect_env *env, const struct gpu_frame_time *time,
                GLuint src, GLuint dst_fbo, char *err, size_t errlen);
    /* Frees what create made (pool planes stay in the pool). Accepts NULL. */
    void (*destroy)(void *state);
};

/* The GL half of the registry: every registered effect, in the order of
 * effect_infos (each folder's effect_NAME), NULL-terminated. */
extern const struct effect *const effect_registry[];

/* Draws the full-screen triangle with prog into the bound framebuffer;
 * shared by the effects. */
void effect_draw_fullscreen(const struct effect_env *env, GLuint prog);

/* A named plane of the pool at a size and the framebuffer over it; the
 * name is "<label>.<suffix>". False with err filled. */
bool effect_plane(const struct effect_env *env, const char *suffix, GLenum format, int w, int h,
                  GLuint *tex, GLuint *fbo, char *err, size_t errlen);

#endif
