#ifndef SHADEBENCH_FIDELITY_SPEC_H
#define SHADEBENCH_FIDELITY_SPEC_H

/* A job's "fidelity": render the job's glTF asset with the Khronos glTF
 * Sample Viewer too (shadebench-reference, a child process) and compare
 * shadebench's captured image and its look.debug channels with the
 * viewer's, channel by channel (fidelity.h). The job's own "reference" (a
 * technique) is not used with it. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"
#include "daemon/reference/reference_files.h"

/* The channels, by their look.debug names ("lit": the job's own image);
 * each is drawn as the Sample Viewer writes its debug output of that name
 * (normals n * 0.5 + 0.5, base colour and emissive gamma-2.2 encoded, the
 * scalars as they are, uv (u, v, 0)). */
enum fidelity_channel {
    FIDELITY_LIT,
    FIDELITY_SHADING_NORMAL,
    FIDELITY_GEOMETRIC_NORMAL,
    FIDELITY_NORMAL_TEXTURE,
    FIDELITY_TANGENT,
    FIDELITY_BITANGENT,
    FIDELITY_BASE_COLOR,
    FIDELITY_METALLIC,
    FIDELITY_ROUGHNESS,
    FIDELITY_OCCLUSION,
    FIDELITY_EMISSIVE,
    FIDELITY_UV0,
    FIDELITY_UV1,
    FIDELITY_ALPHA,
    FIDELITY_CHANNELS
};
extern const char *const fidelity_channel_names[]; /* NULL-terminated */

struct fidelity_spec {
    bool enabled;
    unsigned channels; /* bit per enum fidelity_channel; lit always */
    struct reference_sampler sampler;
};

void fidelity_spec_defaults(struct fidelity_spec *f);
/* v: true, false, null, or {"channels": "all" | [names], "ibl_sampler": {...}}. */
bool fidelity_spec_parse(const json_t *v, struct fidelity_spec *f, struct job_error *err);
/* null when off. New reference. */
json_t *fidelity_spec_to_json(const struct fidelity_spec *f);
int fidelity_channel_count(const struct fidelity_spec *f);

#endif

/* What the Khronos viewer can be compared with: the job draws its glTF
 * asset (scene.asset: the viewer reads the same file), with the PBR
 * lighting, a tone curve the viewer has (none, srgb, aces, pbr_neutral),
 * no post effects, no shadows, image-based lighting from a uniform or an
 * uploaded environment without probes, one run, no technique reference.
 * False with the field and the rule. */
#include "daemon/lighting/look_spec.h"
#include "daemon/scene/scene_spec.h"
bool fidelity_spec_check_job(const struct fidelity_spec *f, const struct scene_spec *scene,
                             const struct look_spec *look, const char *reference, int repeat,
                             bool repeat_auto, int temporal_frames, int msaa,
                             struct job_error *err);

/* POST /v1/assets/NAME/fidelity's body as a job: {"technique", "width",
 * "height", "camera", "lights" (scene.light_rig), "look", "scene" (more
 * scene keys), "channels", "ibl_sampler", "labels", "timeout_s"}, every key
 * optional, into a job of one captured frame (no warm-up) of scene.asset
 * NAME, 320x240, with look.lighting "pbr" and look.transfer "gamma_2.2"
 * (the viewer's encoding) unless the look says otherwise, and "fidelity". A new reference, or NULL with the field and the rule. */
#define FIDELITY_DEFAULT_WIDTH 320
#define FIDELITY_DEFAULT_HEIGHT 240
json_t *fidelity_job_body(const char *asset, const json_t *body, struct job_error *err);
