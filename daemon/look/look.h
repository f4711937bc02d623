#ifndef SHADEBENCH_LOOK_STAGES_H
#define SHADEBENCH_LOOK_STAGES_H

/* The look's work that the harness does for every technique, so that each
 * technique only calls the lighting library: the #defines of the look, the
 * image-based lighting's setup and per-frame binding (ibl.h), the shadow
 * pass before the technique's passes (shadows.h), the sky pass after them
 * (sky.h, for scenes with a sky), or look.debug's pass in its place
 * (debug.h). Render thread only. */

#include <epoxy/gl.h>
#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/caps.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/look/debug.h"
#include "daemon/look/ibl.h"
#include "daemon/look/shadows.h"
#include "daemon/look/sky.h"
#include "daemon/lighting/look_spec.h"
#include "daemon/scene/scene.h"

/* The #define lines of a look, for every program that lights: the model,
 * the environment, image-based lighting and shadows, with the constants C
 * owns (pbr_math.h, look_lighting.h) so that GLSL cannot disagree. */
void look_defines(const struct look_spec *look, char *out, size_t cap);

struct look_stages {
    struct gpu_budget *budget;
    const struct look_spec *look;
    const struct scene *scene;
    const struct gpu_scene *gpu;
    bool sky_on;
    struct look_sky sky;
    bool debug_on; /* look.debug: its pass takes the sky's place */
    struct look_debug_pass debug;
    struct look_ibl *ibl;
    struct look_shadows *shadows;
    double setup_ms; /* everything before the first frame, image-based lighting's captures included */
};

/* Builds what the look needs for this scene (captures and filters the
 * probes: the job's setup time). env: the environment image
 * look.ibl.environment names (read by the caller), else NULL. On failure err names the field where one
 * is to blame; the look is left finished. */
bool look_stages_init(struct look_stages *l, const struct look_spec *look,
                       const struct scene *scene, struct gpu_scene *gpu,
                       struct gpu_frame_block *frame_block, const struct gpu_caps *caps,
                       struct gpu_budget *budget, const char *defines,
                       const struct environment_image *env, char *err, size_t errlen);
/* Takes a zeroed or initialised look. */
void look_stages_finish(struct look_stages *l);

/* The passes the look adds to a frame, appended to passes (after the
 * technique's): "shadows" (run first) and "sky" or "debug" (run after the
 * technique, in sky_pass); -1 where the look has none. False when the
 * passes are full. */
bool look_stages_add_passes(const struct look_stages *l, struct gpu_passes *passes,
                             int *shadow_pass, int *sky_pass);

/* Before the technique's passes of frame: probes and maps bound, the
 * shadow pass run. Timed. False (err set) when the shadow atlas overflows
 * under overflow "fail". `timed`: the frame counts in the figures. */
bool look_stages_before(struct look_stages *l, const struct gpu_passes *passes, int shadow_pass,
                         int64_t frame, bool timed, char *err, size_t errlen);
/* After them: the sky pass, or look.debug's, into the technique's output.
 * Timed. */
void look_stages_after(struct look_stages *l, const struct gpu_passes *passes, int sky_pass,
                        GLuint output_fbo, int width, int height);

/* result.ibl, result.shadows, result.setup_ms and result.pbr (the
 * materials the roughness clamp touched) into result. */
void look_stages_describe(const struct look_stages *l, json_t *result);

#endif
