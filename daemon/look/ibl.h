#ifndef SHADEBENCH_LOOK_IBL_H
#define SHADEBENCH_LOOK_IBL_H

/* Image-based lighting (look.ibl), run by the harness for every technique:
 * before the timed frames it captures the environment and each light probe
 * (the scene seen from the probe, lit by the first frame's lights, the sky
 * behind) into a cube map, and filters each into an irradiance map and a
 * prefiltered specular map whose levels step through roughness, beside the
 * split-sum BRDF table (daemon/lighting/pbr_math.c). The time it takes is
 * the job's setup time, reported in the result. Each frame it picks the
 * probes that light it (daemon/lighting/ibl_plan.h) and binds everything
 * where shaders/common/ibl.glsl reads it. Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/budget.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/look/sky.h"
#include "daemon/lighting/look_lighting.h"
#include "daemon/scene/scene.h"

struct look_ibl;

struct look_ibl_env {
    const struct ibl_spec *spec;
    const struct scene *scene;
    struct gpu_scene *gpu;
    struct gpu_frame_block *frame_block; /* overwritten by the captures */
    const struct look_sky *sky;
    /* Whose stop predicate the captures and filters ask (NULL: none); they
     * measure their pieces in a budget of their own. */
    const struct gpu_budget *budget;
};

/* Captures and filters everything (outside the timed frames; leaves the
 * framebuffer binding at 0). NULL with err filled on failure. */
struct look_ibl *look_ibl_create(const struct look_ibl_env *env, char *err, size_t errlen);
/* Chooses frame's probes for its camera and binds the maps, the table and
 * the probe block. Timed: no allocation, no lookups; uploads only when the
 * choice changes. */
void look_ibl_frame(struct look_ibl *ibl, int64_t frame);
/* Setup times, probes, maps and their bytes, the choice at frame 1. New
 * reference. */
json_t *look_ibl_describe(const struct look_ibl *ibl);
/* Accepts NULL. */
void look_ibl_destroy(struct look_ibl *ibl);

#endif
