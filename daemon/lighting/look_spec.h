#ifndef SHADEBENCH_LOOK_SPEC_H
#define SHADEBENCH_LOOK_SPEC_H

/* A job's "look": what the image should look like, independent of the
 * technique that renders it (the reference renders with the same look, or
 * its own reference_look): the lighting model, the HDR target's format, the
 * resolve's exposure and tone curve, the post chain, image-based lighting
 * and shadows. Options, defaults, parsing with field-naming errors and the
 * JSON written back, from one option table. Techniques and the harness
 * render with it; jobs hold two. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"
#include "daemon/effects/post_spec.h"
#include "daemon/lighting/look_lighting.h"

enum look_lighting { LOOK_PHONG, LOOK_BLINN_PHONG, LOOK_PBR };
enum look_hdr { LOOK_HDR_RGBA32F, LOOK_HDR_RGBA16F };
/* none: a clamp, no encoding; srgb: a clamp and the sRGB encoding, no
 * curve; the curves write 8-bit sRGB (tone_curves.h). */
enum look_tonemap {
    LOOK_TONEMAP_NONE, LOOK_TONEMAP_REINHARD, LOOK_TONEMAP_ACES, LOOK_TONEMAP_SRGB,
    LOOK_TONEMAP_PBR_NEUTRAL, LOOK_TONEMAP_COUNT
};
extern const char *const look_tonemap_names[]; /* the JSON spelling, by enum */
/* A surface channel drawn in place of the lit image (none: the lit image),
 * each encoded as the Khronos glTF Sample Viewer writes its debug output
 * of the same name (docs/api.md, "look.debug"), so that the two compare
 * pixel for pixel. */
enum look_debug {
    LOOK_DEBUG_NONE,
    LOOK_DEBUG_SHADING_NORMAL,   /* world space, normal map applied: n * 0.5 + 0.5 */
    LOOK_DEBUG_GEOMETRIC_NORMAL, /* the interpolated vertex normal: n * 0.5 + 0.5 */
    LOOK_DEBUG_NORMAL_TEXTURE,   /* the normal map's texel, scaled: n * 0.5 + 0.5 */
    LOOK_DEBUG_TANGENT,          /* world space: t * 0.5 + 0.5 */
    LOOK_DEBUG_BITANGENT,        /* world space: b * 0.5 + 0.5 */
    LOOK_DEBUG_BASE_COLOR,       /* factor x texture x COLOR_0, linear to gamma 2.2 */
    LOOK_DEBUG_METALLIC,         /* grey */
    LOOK_DEBUG_ROUGHNESS,        /* grey, perceptual (before squaring) */
    LOOK_DEBUG_OCCLUSION,        /* the occlusion map's red, strength not applied */
    LOOK_DEBUG_EMISSIVE,         /* factor x strength x texture, linear to gamma 2.2 */
    LOOK_DEBUG_UV0,              /* TEXCOORD_0 in red and green */
    LOOK_DEBUG_UV1,              /* TEXCOORD_1 in red and green */
    LOOK_DEBUG_ALPHA,            /* base colour alpha (1 for opaque materials), grey */
};
extern const char *const look_debug_names[]; /* "none", "shading_normal", ... */
/* How the display-referred outputs (every tone map but none) are encoded:
 * the exact sRGB curve, or a plain gamma of 2.2, the Khronos glTF Sample
 * Viewer's (tone_curves.h), to compare with its images. */
enum look_transfer { LOOK_TRANSFER_SRGB, LOOK_TRANSFER_GAMMA_2_2 };

struct look_spec {
    int lighting;    /* enum look_lighting */
    int hdr;         /* enum look_hdr: the format of the HDR target techniques draw into */
    double exposure; /* scales the HDR colour in the resolve, before the tone curve */
    int tonemap;     /* enum look_tonemap */
    int transfer;    /* enum look_transfer */
    struct post_spec post;      /* effects the harness runs on the HDR output, in order */
    struct ibl_spec ibl;        /* image-based lighting (needs lighting pbr) */
    struct shadow_spec shadows; /* omni shadow maps for the point lights */
    int debug;       /* enum look_debug */
};

/* A Phong image in 32-bit floats, clamped, without effects, image-based
 * lighting or shadows. */
void look_spec_defaults(struct look_spec *look);

/* Reads the object v over look (defaults or earlier values); field is
 * "look" or "reference_look", the prefix of every error. */
bool look_spec_parse(const json_t *v, const char *field, struct look_spec *look,
                     struct job_error *err);

/* The look as understood, every field and effect option. New reference. */
json_t *look_spec_to_json(const struct look_spec *look);

#endif
