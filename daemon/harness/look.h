#ifndef SHADEBENCH_HARNESS_LOOK_H
#define SHADEBENCH_HARNESS_LOOK_H

/* The look's work that the harness does for every technique, so that each
 * technique only calls the lighting library: the #defines of the look, the
 * image-based lighting's setup and per-frame binding (ibl.h), the shadow
 * pass before the technique's passes (shadows.h), the sky pass after them
 * (sky.h, for scenes with a sky), and the HDR statistics of captured
 * frames (non-finite pixels, mean and peak: what the PBR model's clamp
 * keeps out, and the energy the furnace and roughness tests read).
 * Render thread only. */

#include <epoxy/gl.h>
#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/gpu/caps.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/pass.h"
#include "daemon/harness/ibl.h"
#include "daemon/harness/shadows.h"
#include "daemon/harness/sky.h"
#include "daemon/jobs/job_spec.h"
#include "daemon/scene/scene.h"

/* The #define lines of a look, for every program that lights: the model,
 * the environment, image-based lighting and shadows, with the constants C
 * owns (pbr_math.h, look_lighting.h) so that GLSL cannot disagree. */
void harness_look_defines(const struct look_spec *look, char *out, size_t cap);

struct harness_look {
    const struct look_spec *look;
    const struct scene *scene;
    bool sky_on;
    struct harness_sky sky;
    struct harness_ibl *ibl;
    struct harness_shadows *shadows;
    double setup_ms; /* everything before the first frame, image-based lighting's captures included */
};

/* Builds what the look needs for this scene (captures and filters the
 * probes: the job's setup time). On failure err names the field where one
 * is to blame; the look is left finished. */
bool harness_look_init(struct harness_look *l, const struct look_spec *look,
                       const struct scene *scene, struct gpu_scene *gpu,
                       struct gpu_frame_block *frame_block, const struct gpu_caps *caps,
                       const char *defines, char *err, size_t errlen);
/* Takes a zeroed or initialised look. */
void harness_look_finish(struct harness_look *l);

/* The passes the look adds to a frame, appended to passes (after the
 * technique's): "shadows" (run first) and "sky" (run after the technique);
 * -1 where the look has none. False when the passes are full. */
bool harness_look_add_passes(const struct harness_look *l, struct gpu_passes *passes,
                             int *shadow_pass, int *sky_pass);

/* Before the technique's passes of frame: probes and maps bound, the
 * shadow pass run. Timed. False (err set) when the shadow atlas overflows
 * under overflow "fail". `timed`: the frame counts in the figures. */
bool harness_look_before(struct harness_look *l, const struct gpu_passes *passes, int shadow_pass,
                         int64_t frame, bool timed, char *err, size_t errlen);
/* After them: the sky pass into the technique's output. Timed. */
void harness_look_after(struct harness_look *l, const struct gpu_passes *passes, int sky_pass,
                        GLuint output_fbo, int width, int height);

/* result.ibl, result.shadows, result.setup_ms and result.pbr (the
 * materials the roughness clamp touched) into result. */
void harness_look_describe(const struct harness_look *l, json_t *result);

/* HDR statistics of one captured frame. */
struct hdr_stats {
    long long nonfinite; /* pixels with a NaN or infinite R, G or B */
    double mean[3];      /* of the finite pixels */
    double min, max;     /* smallest and largest finite channel */
};

/* Reads the HDR colour attachment of fbo (w x h, RGBA float) into scratch
 * (4 w h floats, allocated by the caller outside the timed frames). */
void harness_hdr_stats(GLuint fbo, int w, int h, float *scratch, struct hdr_stats *out);
json_t *hdr_stats_json(const struct hdr_stats *s);

#endif
