#ifndef SHADEBENCH_LOOK_DEBUG_H
#define SHADEBENCH_LOOK_DEBUG_H

/* look.debug's pass: after the technique's passes, the output cleared and
 * every opaque and alpha-masked mesh drawn again with shaders/harness/
 * debug.frag, which writes the look's channel (surface.glsl's
 * surface_debug_here) in place of the lit image; the harness's transparent
 * pass then draws the blended meshes' channel over it, back to front. The
 * same for every technique: the channels are the shared surface's, and
 * techniques differ in the lit image alone. Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/gpu_scene.h"

struct look_debug_pass {
    struct scene_program program;
};

/* defines: the look's (LOOK_DEBUG and the channel's among them). */
bool look_debug_init(struct look_debug_pass *d, const struct gpu_scene *gpu, const char *defines,
                     char *err, size_t errlen);
/* Clears the bound framebuffer's colour (to 0) and depth and draws the
 * channel, depth-tested, back faces culled but for double-sided materials. */
void look_debug_draw(const struct look_debug_pass *d, const struct gpu_scene *gpu);
/* Takes a zeroed or initialised pass. */
void look_debug_finish(struct look_debug_pass *d);

#endif
