#ifndef SHADEBENCH_LOOK_SKY_H
#define SHADEBENCH_LOOK_SKY_H

/* The harness's sky pass: the look's environment (shaders/common/
 * environment.glsl) drawn behind a technique's image in every pixel it left
 * at the far plane, for scenes that have a sky (scene.sky), and behind the
 * scene in each light probe's capture. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/scene/environment.h"

struct look_sky {
    GLuint prog, vao;
    GLuint env_map; /* an uploaded environment (ENV_MAP), or 0 */
    double env_bytes;
};

/* defines: the look's (the environment's #defines among them). env: the
 * uploaded environment image when the look names one (defines then say
 * ENV_MAP), else NULL: uploaded as an RGB32F texture with its mip chain,
 * bound at SB_TEX_ENV_MAP for each draw. */
bool look_sky_init(struct look_sky *s, const char *defines, const struct environment_image *env,
                   char *err, size_t errlen);
/* Draws into the bound framebuffer, whose depth attachment holds the scene's
 * depth, in the frame block's camera; depth test GL_LEQUAL, no writes.
 * Leaves depth writes on, as the pass baseline has them. */
void look_sky_draw(const struct look_sky *s);
/* Takes a zeroed or initialised sky. */
void look_sky_finish(struct look_sky *s);

#endif
