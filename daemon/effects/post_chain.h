#ifndef SHADEBENCH_POST_CHAIN_H
#define SHADEBENCH_POST_CHAIN_H

/* The post chain the harness runs after any technique, before its resolve:
 * the effects of a look (look.post), in order, each reading the previous
 * one's colour from one of two ping-pong planes of the look's HDR format,
 * each pass named and timed ("bloom.bright", ...). Also the count of pixels
 * that are NaN or infinite in the colour the resolve reads, taken at
 * captured frames outside the timed region. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/effects/post_spec.h"
#include "daemon/gpu/budget.h"
#include "daemon/gpu/pass.h"
#include "daemon/gpu/targets.h"

struct post_chain;

/* The frame a chain works on: what the harness hands it of the
 * technique's output, nothing of the technique itself. */
struct post_frame {
    int width, height;
    GLenum hdr_format;           /* of color, and of the chain's planes */
    GLuint color, depth;         /* the technique's HDR output and depth texture */
    struct gpu_targets *targets; /* the pool the chain and its effects take planes from */
    struct gpu_budget *budget;   /* bounded submissions (daemon/gpu/budget.h) */
    GLuint motion;               /* the harness's motion vectors, or 0 (effect_env) */
};

/* NaN and infinite pixels (any of R, G, B) in one frame's HDR colour. */
struct post_nonfinite {
    uint32_t nan_pixels; /* at least one channel NaN */
    uint32_t inf_pixels; /* no NaN, at least one channel infinite */
    /* 16-bit targets: no NaN or infinity, a channel at +-65504, the largest
     * half float, which drivers that clamp an overflowing write (llvmpipe)
     * leave instead of infinity. */
    uint32_t overflow_pixels;
};

/* Starts the chain of post's effects over the frame (copied): appends its
 * passes to passes, in frame order (the chain keeps their names, so it must
 * outlive every reader of passes), and prepares the counter. post and
 * passes must outlive the chain. NULL with err filled. */
struct post_chain *post_chain_create(const struct post_frame *frame, const struct post_spec *post,
                                     struct gpu_passes *passes, char *err, size_t errlen);
/* Builds the effects (programs, planes from the frame's pool) once the
 * technique was created, since the normals it publishes choose the
 * programs' variants: normal_tex holds world-space normals (octahedral
 * when normal_octahedral, else rgb), or is 0 and effects rebuild them from
 * depth. Later calls do nothing. */
bool post_chain_build(struct post_chain *c, GLuint normal_tex, bool normal_octahedral, char *err,
                      size_t errlen);
/* Frees what create made. Accepts NULL. */
void post_chain_destroy(struct post_chain *c);

/* Runs every effect on the technique's output at time; *out is the HDR
 * colour the resolve reads (the output itself when the chain is empty).
 * False with err, naming the effect, when one could not run. Timed: no
 * allocation, no uniform lookups. */
bool post_chain_run(struct post_chain *c, const struct gpu_frame_time *time, GLuint *out,
                    char *err, size_t errlen);

/* Counts the non-finite (and, in a 16-bit target, overflowed) pixels of
 * tex (the frame's size) with a compute pass and reads the counters back. Stalls: outside every
 * timed region only. */
bool post_chain_count_nonfinite(struct post_chain *c, GLuint tex, struct post_nonfinite *out,
                                char *err, size_t errlen);

#endif
