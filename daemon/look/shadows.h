#ifndef SHADEBENCH_LOOK_SHADOWS_H
#define SHADEBENCH_LOOK_SHADOWS_H

/* Omni shadow maps (look.shadows), run by the harness for every technique
 * (and an orthographic map for each of the first SHADOW_MAX_SUNS
 * directional lights, fitted to the scene):
 * each frame, in its own timed pass before the technique's, it plans which
 * lights get maps and where (daemon/lighting/shadow_plan.h), renders the
 * casters reaching each face into the depth atlas (or the cube map array),
 * writes where each light's faces lie and binds both for
 * shaders/common/shadows.glsl. It reports the atlas use, the lights
 * mapped, culled and dropped, and fails the frame naming the lights that
 * lost their shadows when overflow is "fail". Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/budget.h"
#include "daemon/gpu/caps.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/lighting/look_lighting.h"
#include "daemon/scene/scene.h"

struct look_shadows;

/* NULL with err filled (out of memory, or an atlas past the device's
 * texture size limit, naming look.shadows.atlas). */
struct look_shadows *look_shadows_create(const struct shadow_spec *spec,
                                               const struct scene *s, struct gpu_scene *gpu,
                                               const struct gpu_caps *caps, char *err,
                                               size_t errlen);
/* Frame's maps, in pass `pass` of passes; then binds them. Timed: no
 * allocation, no lookups. False (err set) only when overflow is "fail"
 * and a light lost its shadow. `timed` counts the frame in the figures. */
bool look_shadows_render(struct look_shadows *sh, const struct gpu_passes *passes, int pass,
                            int64_t frame, bool timed, struct gpu_budget *budget, char *err,
                            size_t errlen);
/* Atlas use and lights per timed frame, the lights that lost shadows. New
 * reference. */
json_t *look_shadows_describe(const struct look_shadows *sh);
/* Accepts NULL. */
void look_shadows_destroy(struct look_shadows *sh);

#endif
