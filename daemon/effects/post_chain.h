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

#include "daemon/jobs/job_spec.h"
#include "daemon/techniques/technique.h"

struct post_chain;

/* NaN and infinite pixels (any of R, G, B) in one frame's HDR colour. */
struct post_nonfinite {
    uint32_t nan_pixels; /* at least one channel NaN */
    uint32_t inf_pixels; /* no NaN, at least one channel infinite */
    /* 16-bit targets: no NaN or infinity, a channel at +-65504, the largest
     * half float, which drivers that clamp an overflowing write (llvmpipe)
     * leave instead of infinity. */
    uint32_t overflow_pixels;
};

/* Starts the chain of look's effects over tech's output: appends its passes
 * to passes, in frame order (the chain keeps their names, so it must outlive
 * every reader of passes), and prepares the counter. tech, look and passes
 * must outlive the chain. NULL with err filled. */
struct post_chain *post_chain_create(const struct technique_env *tech, const struct look_spec *look,
                                     struct gpu_passes *passes, char *err, size_t errlen);
/* Builds the effects (programs, planes from tech->targets) once the
 * technique was created, since its products (g-buffer normals) choose the
 * programs' variants. Later calls do nothing. */
bool post_chain_build(struct post_chain *c, char *err, size_t errlen);
/* Frees what create made. Accepts NULL. */
void post_chain_destroy(struct post_chain *c);

/* Runs every effect on the technique's output; returns the HDR colour the
 * resolve reads (the output itself when the chain is empty). Timed: no
 * allocation, no uniform lookups. */
GLuint post_chain_run(struct post_chain *c);

/* Counts the non-finite (and, in a 16-bit target, overflowed) pixels of tex (width x height of the output) with
 * a compute pass and reads the two counters back. Stalls: outside every
 * timed region only. */
bool post_chain_count_nonfinite(struct post_chain *c, GLuint tex, struct post_nonfinite *out,
                                char *err, size_t errlen);

#endif
