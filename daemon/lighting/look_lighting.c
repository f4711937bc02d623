#define _POSIX_C_SOURCE 200809L
#include "daemon/lighting/look_lighting.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "common/options.h"
#include "daemon/scene/scene_spec.h" /* scene_asset_name_valid */

const char *const ibl_environment_names[] = {"sky", "uniform", NULL};
const char *const shadow_overflow_names[] = {"drop_report", "fail", NULL};
const char *const shadow_layout_names[] = {"atlas", "cubes", NULL};

static bool parse_probe_list(const json_t *list, const char *field, struct ibl_spec *s,
                             struct job_error *err)
{
    if (json_array_size(list) < 1 || json_array_size(list) > IBL_MAX_PROBES)
        return job_error_set(err, field, "must list 1 to %d probes, or be a count from 0 to %d",
                             IBL_MAX_PROBES, IBL_MAX_PROBES);
    size_t i;
    json_t *p;
    json_array_foreach(list, i, p) {
        char f[96], prefix[96];
        snprintf(prefix, sizeof(prefix), "%s[%zu].", field, i);
        static const char *const keys[] = {"position", "radius", NULL};
        snprintf(f, sizeof(f), "%s[%zu]", field, i);
        if (!json_is_object(p))
            return job_error_set(err, f, "must be {\"position\": [x, y, z], \"radius\": r}");
        if (!jf_check_keys(p, prefix, keys, err))
            return false;
        json_t *pos = json_object_get(p, "position");
        snprintf(f, sizeof(f), "%s[%zu].position", field, i);
        if (!json_is_array(pos) || json_array_size(pos) != 3)
            return job_error_set(err, f, "must be three numbers [x, y, z]");
        for (int k = 0; k < 3; k++) {
            json_t *c = json_array_get(pos, (size_t)k);
            if (!json_is_number(c) || json_number_value(c) < -1e4 || json_number_value(c) > 1e4)
                return job_error_set(err, f, "must be three numbers from -10000 to 10000");
            s->probe[i].pos[k] = json_number_value(c);
        }
        snprintf(f, sizeof(f), "%s[%zu].radius", field, i);
        if (!json_object_get(p, "radius"))
            return job_error_set(err, f, "is required: the distance at which the probe's weight "
                                 "reaches 0");
        if (!jf_get_number(p, "radius", f, 0.01, 1e4, &s->probe[i].radius, err))
            return false;
    }
    s->probes = (int)json_array_size(list);
    s->placed = true;
    return true;
}

/* probes: a count (placed over the objects) or a list of positions and radii. */
static bool parse_probes(const json_t *v, const char *field, void *opts, struct job_error *err)
{
    struct ibl_spec *s = opts;
    if (json_is_array(v))
        return parse_probe_list(v, field, s, err);
    json_t *wrapped = json_pack("{s:O}", "probes", v);
    int count = s->probes;
    bool ok = jf_get_int(wrapped, "probes", field, 0, IBL_MAX_PROBES, &count, err);
    json_decref(wrapped);
    if (!ok)
        return job_error_set(err, field, "must be a count from 0 to %d, or a list of "
                             "{\"position\": [x, y, z], \"radius\": r}", IBL_MAX_PROBES);
    s->probes = count;
    s->placed = false;
    return true;
}

static json_t *probes_json(const void *opts)
{
    const struct ibl_spec *s = opts;
    if (!s->placed)
        return json_integer(s->probes);
    json_t *probes = json_array();
    for (int i = 0; i < s->probes; i++)
        json_array_append_new(probes, json_pack("{s:[f, f, f], s:f}", "position",
                                                s->probe[i].pos[0], s->probe[i].pos[1],
                                                s->probe[i].pos[2], "radius",
                                                s->probe[i].radius));
    return probes;
}

static const struct opt_hooks probe_hooks = {
    .parse = parse_probes, .to_json = probes_json, .type = "count_or_list",
    .rule = "must be a count from 0 to 32, or a list of {\"position\": [x, y, z], "
            "\"radius\": r}"};

/* environment: "sky", "uniform", or {"asset": NAME} (an uploaded HDR
 * image; "asset_sha256" pins it, as scene.asset_sha256 does). */
static bool parse_environment(const json_t *v, const char *field, void *opts,
                              struct job_error *err)
{
    struct ibl_spec *s = opts;
    static const char rule[] = "must be \"sky\", \"uniform\" or {\"asset\": NAME} (an "
                               "equirectangular .hdr stored with PUT /v1/assets/NAME)";
    s->env_asset[0] = s->env_sha256[0] = '\0';
    if (json_is_string(v)) {
        for (int i = 0; ibl_environment_names[i]; i++)
            if (strcmp(json_string_value(v), ibl_environment_names[i]) == 0) {
                s->environment = i;
                return true;
            }
        return job_error_set(err, field, "%s", rule);
    }
    static const char *const keys[] = {"asset", "asset_sha256", NULL};
    char prefix[96];
    snprintf(prefix, sizeof(prefix), "%s.", field);
    if (!json_is_object(v))
        return job_error_set(err, field, "%s", rule);
    if (!jf_check_keys(v, prefix, keys, err))
        return false;
    const char *name = json_string_value(json_object_get(v, "asset"));
    char f[96];
    snprintf(f, sizeof(f), "%s.asset", field);
    if (!name || !scene_asset_name_valid(name))
        return job_error_set(err, f, "must be the name of a stored environment (GET "
                             "/v1/assets): 1 to %d letters, digits, '.', '_' or '-', not "
                             "starting with '.'", IBL_ENV_ASSET_NAME_MAX);
    snprintf(s->env_asset, sizeof(s->env_asset), "%s", name);
    json_t *h = json_object_get(v, "asset_sha256");
    if (h) {
        const char *hex = json_is_string(h) ? json_string_value(h) : "";
        bool ok = strlen(hex) == 64;
        for (int i = 0; ok && i < 64; i++)
            ok = (hex[i] >= '0' && hex[i] <= '9') || (hex[i] >= 'a' && hex[i] <= 'f');
        snprintf(f, sizeof(f), "%s.asset_sha256", field);
        if (!ok)
            return job_error_set(err, f, "must be 64 lowercase hexadecimal digits (the "
                                 "asset's SHA-256)");
        memcpy(s->env_sha256, hex, 65);
    }
    s->environment = IBL_ENV_ASSET;
    return true;
}

static json_t *environment_json(const void *opts)
{
    const struct ibl_spec *s = opts;
    if (s->environment != IBL_ENV_ASSET)
        return json_string(ibl_environment_names[s->environment]);
    json_t *o = json_pack("{s:s}", "asset", s->env_asset);
    if (o && s->env_sha256[0])
        json_object_set_new(o, "asset_sha256", json_string(s->env_sha256));
    return o;
}

static const struct opt_hooks environment_hooks = {
    .parse = parse_environment, .to_json = environment_json, .type = "choice_or_object",
    .rule = "\"sky\", \"uniform\" or {\"asset\": NAME}: an uploaded equirectangular .hdr"};

static const struct opt_field ibl_fields[] = {
    {.name = "environment", .type = OPT_CUSTOM, .hooks = &environment_hooks,
     .summary = "sky: an analytic sky with a sun; uniform: constant radiance (the white "
                "furnace's); {\"asset\": NAME}: an uploaded equirectangular HDR image (PUT "
                "/v1/assets/NAME.hdr), prefiltered as the sky is",
     .offset = offsetof(struct ibl_spec, environment)},
    {.name = "intensity", .type = OPT_NUMBER, .def = 1.0, .min = 0.0, .max = 1000.0,
     .summary = "scales the environment's radiance",
     .offset = offsetof(struct ibl_spec, intensity)},
    {.name = "probes", .type = OPT_CUSTOM, .hooks = &probe_hooks,
     .summary = "light probes capturing the scene: a count placed over the objects, or a "
                "list; 0 lights with the environment alone",
     .offset = offsetof(struct ibl_spec, probes)},
    {.name = "resolution", .type = OPT_POW2, .def = 64, .min = 8, .max = 512,
     .summary = "capture cube face edge (the prefiltered map's level 0)",
     .offset = offsetof(struct ibl_spec, resolution)},
    /* seed 002 blends the four most important probes */
    {.name = "blend", .type = OPT_INT, .def = 4, .min = 1, .max = IBL_MAX_BLEND,
     .summary = "probes blended per pixel, the most important first",
     .offset = offsetof(struct ibl_spec, blend)},
    {.name = "samples", .type = OPT_INT, .def = 64, .min = 1, .max = 4096,
     .summary = "GGX samples per prefiltered texel",
     .offset = offsetof(struct ibl_spec, samples)},
    {0},
};

static const struct opt_table ibl_table = {.fields = ibl_fields, .size = sizeof(struct ibl_spec)};

static const struct opt_field shadow_fields[] = {
    {.name = "layout", .type = OPT_CHOICE, .def = SHADOW_LAYOUT_ATLAS,
     .choices = shadow_layout_names,
     .summary = "atlas: every light's six faces in one 2D atlas, sized by importance; cubes: "
                "one cube map per light, all tile x tile",
     .offset = offsetof(struct shadow_spec, layout)},
    {.name = "atlas", .type = OPT_POW2, .def = 4096, .min = 256, .max = SHADOW_MAX_ATLAS,
     .summary = "atlas edge in texels: the memory bound of either layout",
     .offset = offsetof(struct shadow_spec, atlas)},
    {.name = "tile", .type = OPT_POW2_OR_AUTO, .def = 0, .min = SHADOW_MIN_TILE,
     .max = SHADOW_MAX_ATLAS, .auto_means = "sized by importance on screen",
     .summary = "face edge for every light", .offset = offsetof(struct shadow_spec, tile)},
    {.name = "min_tile", .type = OPT_POW2, .def = 16, .min = SHADOW_MIN_TILE,
     .max = SHADOW_MAX_ATLAS, .summary = "auto's smallest face edge",
     .offset = offsetof(struct shadow_spec, min_tile)},
    {.name = "max_tile", .type = OPT_POW2, .def = 512, .min = SHADOW_MIN_TILE,
     .max = SHADOW_MAX_ATLAS, .summary = "auto's largest face edge",
     .offset = offsetof(struct shadow_spec, max_tile)},
    {.name = "pcf", .type = OPT_INT, .def = 1, .min = 0, .max = 3,
     .summary = "filter radius in texels: (2 pcf + 1)^2 bilinear compares",
     .offset = offsetof(struct shadow_spec, pcf)},
    {.name = "bias", .type = OPT_NUMBER, .def = 0.02, .min = 0.0, .max = 10.0,
     .summary = "depth bias along the light ray, world units",
     .offset = offsetof(struct shadow_spec, bias)},
    {.name = "normal_offset", .type = OPT_NUMBER, .def = 1.0, .min = 0.0, .max = 16.0,
     .summary = "receiver moved along its normal, in shadow-map texels",
     .offset = offsetof(struct shadow_spec, normal_offset)},
    {.name = "overflow", .type = OPT_CHOICE, .def = SHADOW_OVERFLOW_DROP_REPORT,
     .choices = shadow_overflow_names,
     .summary = "when the atlas cannot hold every light's maps: drop the least important "
                "lights' shadows and report them, or fail the frame",
     .offset = offsetof(struct shadow_spec, overflow)},
    {0},
};

static bool shadow_check(void *opts, const char *prefix, struct job_error *err)
{
    struct shadow_spec *s = opts;
    char field[64];
    /* A light's six faces must fit the atlas at the smallest size it may take. */
    int smallest = s->tile ? s->tile : s->min_tile;
    if (smallest * 4 > s->atlas) {
        snprintf(field, sizeof(field), "%s.%s", prefix, s->tile ? "tile" : "min_tile");
        return job_error_set(err, field, "%d leaves no room for one light's six faces in a %d "
                             "atlas: at most atlas / 4", smallest, s->atlas);
    }
    if (s->min_tile > s->max_tile) {
        snprintf(field, sizeof(field), "%s.min_tile", prefix);
        return job_error_set(err, field, "must be at most max_tile (%d)", s->max_tile);
    }
    if (s->layout == SHADOW_LAYOUT_CUBES && !s->tile)
        s->tile = s->max_tile < 256 ? s->max_tile : 256;
    return true;
}

static const struct opt_table shadow_table = {
    .fields = shadow_fields, .size = sizeof(struct shadow_spec), .check = shadow_check};

void ibl_spec_defaults(struct ibl_spec *s) { opt_defaults(&ibl_table, s); }

void shadow_spec_defaults(struct shadow_spec *s) { opt_defaults(&shadow_table, s); }

/* true, false or null switch it with the options as they stand; an object
 * switches it on and sets options. */
static bool parse_switch(const struct opt_table *t, const json_t *v, const char *field,
                         bool *enabled, void *opts, struct job_error *err)
{
    if (json_is_boolean(v) || json_is_null(v)) {
        *enabled = json_is_true(v);
        return true;
    }
    if (!json_is_object(v))
        return job_error_set(err, field, "must be true, false or an object of options");
    *enabled = true;
    return opt_parse(t, v, field, opts, err);
}

bool ibl_spec_parse(const json_t *v, const char *field, struct ibl_spec *s, struct job_error *err)
{
    return parse_switch(&ibl_table, v, field, &s->enabled, s, err);
}

bool shadow_spec_parse(const json_t *v, const char *field, struct shadow_spec *s,
                       struct job_error *err)
{
    return parse_switch(&shadow_table, v, field, &s->enabled, s, err);
}

json_t *ibl_spec_to_json(const struct ibl_spec *s)
{
    return s->enabled ? opt_to_json(&ibl_table, s) : json_false();
}

json_t *shadow_spec_to_json(const struct shadow_spec *s)
{
    return s->enabled ? opt_to_json(&shadow_table, s) : json_false();
}
