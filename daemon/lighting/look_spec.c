#define _POSIX_C_SOURCE 200809L
#include "daemon/lighting/look_spec.h"

#include <stddef.h>
#include <stdio.h>

static const char *const lighting_names[] = {"phong", "blinn_phong", "pbr", NULL};
static const char *const hdr_names[] = {"rgba32f", "rgba16f", NULL};
static const char *const transfer_names[] = {"srgb", "gamma_2.2", NULL};
const char *const look_tonemap_names[] = {"none", "reinhard", "aces", "srgb", "pbr_neutral",
                                          NULL};
const char *const look_debug_names[] = {"none",           "shading_normal", "geometric_normal",
                                        "normal_texture", "tangent",        "bitangent",
                                        "base_color",     "metallic",       "roughness",
                                        "occlusion",      "emissive",       "uv0",
                                        "uv1",            "alpha",          NULL};

static bool parse_post(const json_t *v, const char *field, void *opts, struct job_error *err)
{
    return post_spec_parse(v, field, &((struct look_spec *)opts)->post, err);
}

static json_t *post_json(const void *opts)
{
    return post_spec_to_json(&((const struct look_spec *)opts)->post);
}

static void ibl_defaults(void *opts) { ibl_spec_defaults(&((struct look_spec *)opts)->ibl); }

static bool parse_ibl(const json_t *v, const char *field, void *opts, struct job_error *err)
{
    return ibl_spec_parse(v, field, &((struct look_spec *)opts)->ibl, err);
}

static json_t *ibl_json(const void *opts)
{
    return ibl_spec_to_json(&((const struct look_spec *)opts)->ibl);
}

static void shadow_defaults(void *opts)
{
    shadow_spec_defaults(&((struct look_spec *)opts)->shadows);
}

static bool parse_shadows(const json_t *v, const char *field, void *opts, struct job_error *err)
{
    return shadow_spec_parse(v, field, &((struct look_spec *)opts)->shadows, err);
}

static json_t *shadow_json(const void *opts)
{
    return shadow_spec_to_json(&((const struct look_spec *)opts)->shadows);
}

static const struct opt_hooks post_hooks = {
    .parse = parse_post, .to_json = post_json, .type = "list",
    .rule = "must be a list of effects, each a name or {\"name\": {options}}, run in order"};
static const struct opt_hooks ibl_hooks = {
    .defaults = ibl_defaults, .parse = parse_ibl, .to_json = ibl_json, .type = "switch",
    .rule = "must be true, false or an object of options"};
static const struct opt_hooks shadow_hooks = {
    .defaults = shadow_defaults, .parse = parse_shadows, .to_json = shadow_json,
    .type = "switch", .rule = "must be true, false or an object of options"};

static const struct opt_field fields[] = {
    {.name = "lighting", .type = OPT_CHOICE, .def = LOOK_PHONG, .choices = lighting_names,
     .summary = "the lighting model every technique's light loop evaluates",
     .offset = offsetof(struct look_spec, lighting)},
    {.name = "hdr", .type = OPT_CHOICE, .def = LOOK_HDR_RGBA32F, .choices = hdr_names,
     .summary = "the format of the HDR target techniques draw into",
     .offset = offsetof(struct look_spec, hdr)},
    {.name = "exposure", .type = OPT_NUMBER, .def = 1.0, .min = 1.0 / 1024.0, .max = 1024.0,
     .summary = "scales the HDR colour in the resolve, before the tone curve",
     .offset = offsetof(struct look_spec, exposure)},
    {.name = "tonemap", .type = OPT_CHOICE, .def = LOOK_TONEMAP_NONE, .choices = look_tonemap_names,
     .summary = "the resolve's tone curve: none clamps (linear, no encoding); srgb clamps and "
                "encodes sRGB; reinhard, aces and pbr_neutral (Khronos PBR Neutral) compress "
                "highlights, then encode sRGB",
     .offset = offsetof(struct look_spec, tonemap)},
    {.name = "transfer", .type = OPT_CHOICE, .def = LOOK_TRANSFER_SRGB,
     .choices = transfer_names,
     .summary = "how the tone maps' display-referred output is encoded: srgb (IEC 61966-2-1) "
                "or gamma_2.2 (the Khronos glTF Sample Viewer's); none is never encoded",
     .offset = offsetof(struct look_spec, transfer)},
    {.name = "post", .type = OPT_CUSTOM, .hooks = &post_hooks,
     .summary = "post effects run on the HDR output in order (/v1/info's \"effects\")",
     .offset = offsetof(struct look_spec, post)},
    {.name = "ibl", .type = OPT_CUSTOM, .hooks = &ibl_hooks,
     .summary = "image-based lighting from an environment and light probes (needs pbr)",
     .offset = offsetof(struct look_spec, ibl)},
    {.name = "shadows", .type = OPT_CUSTOM, .hooks = &shadow_hooks,
     .summary = "omni shadow maps for the point lights",
     .offset = offsetof(struct look_spec, shadows)},
    {.name = "debug", .type = OPT_CHOICE, .def = LOOK_DEBUG_NONE, .choices = look_debug_names,
     .summary = "a surface channel in place of the lit image, encoded as the Khronos glTF "
                "Sample Viewer's debug output of that name (no exposure, tone curve or post)",
     .offset = offsetof(struct look_spec, debug)},
    {0},
};

/* The split sum lights a metallic-roughness material: nothing else. */
static bool check(void *opts, const char *prefix, struct job_error *err)
{
    const struct look_spec *look = opts;
    if (look->ibl.enabled && look->lighting != LOOK_PBR) {
        char field[64];
        snprintf(field, sizeof(field), "%s.ibl", prefix);
        return job_error_set(err, field, "needs %s.lighting \"pbr\"", prefix);
    }
    /* A channel is written as it is: an effect would change it. */
    if (look->debug != LOOK_DEBUG_NONE && look->post.count > 0) {
        char field[64];
        snprintf(field, sizeof(field), "%s.post", prefix);
        return job_error_set(err, field, "must be empty with %s.debug \"%s\" (a channel is "
                             "written as it is)", prefix, look_debug_names[look->debug]);
    }
    return true;
}

static const struct opt_table table = {
    .fields = fields, .size = sizeof(struct look_spec), .check = check};

void look_spec_defaults(struct look_spec *look) { opt_defaults(&table, look); }

bool look_spec_parse(const json_t *v, const char *field, struct look_spec *look,
                     struct job_error *err)
{
    return opt_parse(&table, v, field, look, err);
}

json_t *look_spec_to_json(const struct look_spec *look)
{
    json_t *out = opt_to_json(&table, look);
    /* A lit job's look reads as it did before debug channels existed, so
     * that its records and workload keys stay comparable with older ones. */
    if (out && look->debug == LOOK_DEBUG_NONE)
        json_object_del(out, "debug");
    return out;
}
