#ifndef SHADEBENCH_HEAT_H
#define SHADEBENCH_HEAT_H

/* The light-count heat map a many-lights technique publishes as
 * env->products->heat_tex (GL_R32UI, light evaluations per pixel). It is
 * written only on the frames the harness captures, which read it back
 * outside the timed region; other frames pay nothing for it. Programs that
 * write it include shaders/culling/heat.glsl. Render thread only. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/techniques/technique.h"

struct heat {
    GLuint tex, fbo;
};

/* Takes the "heat" target from the pool and publishes it in env->products. */
bool heat_init(struct heat *h, const struct technique_env *env, char *err, size_t errlen);

/* True when frame is captured, so that the technique writes the map. */
bool heat_wanted(const struct technique_env *env, int64_t frame);

/* The location of u_heat_on in prog, looked up once at create. */
GLint heat_location(GLuint prog);
/* Switches prog's heat writes on or off for this frame. */
void heat_enable(GLuint prog, GLint location, bool on);

/* Zeroes the map (for programs that add to it) and binds it; restore_fbo is
 * bound for drawing again afterwards (the pass's framebuffer). */
void heat_clear(const struct heat *h, GLuint restore_fbo);
/* Binds the map's image unit. */
void heat_bind(const struct heat *h);
/* Makes the frame's image writes visible to the harness's readback. */
void heat_done(void);

#endif
