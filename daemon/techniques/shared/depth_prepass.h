#ifndef SHADEBENCH_DEPTH_PREPASS_H
#define SHADEBENCH_DEPTH_PREPASS_H

/* The depth pre-pass of the forward light-culling techniques: every
 * object's depth into the output's depth texture (depth and stencil), no
 * colour, with the same vertex shader as the shading pass so that its depths
 * equal the shading pass's, and a GL_LEQUAL test and a stencil mark there
 * shade each pixel once, with the fragment forward would keep. Tiled binning
 * reads the depths for its tile bounds. Render thread only. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/techniques/technique.h"

struct depth_prepass {
    struct scene_program program;
};

bool depth_prepass_init(struct depth_prepass *d, const struct technique_env *env, char *err,
                        size_t errlen);
/* Accepts a zeroed d. */
void depth_prepass_finish(struct depth_prepass *d);

/* Pass `pass`: clears the output (colour black, depth far, stencil 0) and
 * draws depth. */
void depth_prepass_draw(const struct depth_prepass *d, const struct technique_env *env, int pass);

/* For the shading pass that follows, inside its gpu_pass_begin: depth test
 * GL_LEQUAL against the pre-pass, no depth writes, and a stencil test that
 * lets only the first fragment at a pixel's depth through, so that ties go
 * the way forward's GL_LESS sends them (gpu_pass_begin turns it off again). */
void depth_prepass_shading_state(void);

#endif
