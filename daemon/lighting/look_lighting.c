#define _POSIX_C_SOURCE 200809L
#include "daemon/lighting/look_lighting.h"

#include <stdio.h>
#include <string.h>

const char *const ibl_environment_names[] = {"sky", "uniform", NULL};
const char *const shadow_overflow_names[] = {"drop_report", "fail", NULL};
const char *const shadow_layout_names[] = {"atlas", "cubes", NULL};

void ibl_spec_defaults(struct ibl_spec *s)
{
    memset(s, 0, sizeof(*s));
    s->environment = IBL_ENV_SKY;
    s->intensity = 1.0;
    s->resolution = 64;
    s->blend = 4; /* seed 002 blends the four most important probes */
    s->samples = 64;
}

void shadow_spec_defaults(struct shadow_spec *s)
{
    memset(s, 0, sizeof(*s));
    s->layout = SHADOW_LAYOUT_ATLAS;
    s->atlas = 4096;
    s->tile = 0;
    s->min_tile = 16;
    s->max_tile = 512;
    s->pcf = 1;
    s->bias = 0.02;
    s->normal_offset = 1.0;
    s->overflow = SHADOW_OVERFLOW_DROP_REPORT;
}

static bool is_pow2(int v) { return v > 0 && (v & (v - 1)) == 0; }

/* An integer that is a power of two in [lo, hi]. */
static bool get_pow2(const json_t *obj, const char *key, const char *field, int lo, int hi, int *out,
                     struct job_error *err)
{
    int v = *out;
    if (!jf_get_int(obj, key, field, lo, hi, &v, err) || !is_pow2(v))
        return job_error_set(err, field, "must be a power of two from %d to %d", lo, hi);
    *out = v;
    return true;
}

/* true / false / null switch with defaults; an object switches on. */
static bool get_switch(const json_t *v, const char *field, bool *enabled, bool *is_object,
                       struct job_error *err)
{
    *is_object = false;
    if (json_is_boolean(v) || json_is_null(v)) {
        *enabled = json_is_true(v);
        return true;
    }
    if (!json_is_object(v))
        return job_error_set(err, field, "must be true, false or an object of options");
    *enabled = true;
    *is_object = true;
    return true;
}

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

bool ibl_spec_parse(const json_t *v, const char *field, struct ibl_spec *s, struct job_error *err)
{
    bool object;
    if (!get_switch(v, field, &s->enabled, &object, err))
        return false;
    if (!object)
        return true;
    static const char *const keys[] = {"environment", "intensity", "probes", "resolution",
                                       "blend", "samples", NULL};
    char prefix[48], f[6][64];
    static const char *const names[] = {"environment", "intensity", "probes", "resolution",
                                        "blend", "samples"};
    snprintf(prefix, sizeof(prefix), "%s.", field);
    for (int i = 0; i < 6; i++)
        snprintf(f[i], sizeof(f[i]), "%s.%s", field, names[i]);
    if (!jf_check_keys(v, prefix, keys, err) ||
        !jf_get_choice(v, "environment", f[0], ibl_environment_names, &s->environment, err) ||
        !jf_get_number(v, "intensity", f[1], 0.0, 1000.0, &s->intensity, err) ||
        !get_pow2(v, "resolution", f[3], 8, 512, &s->resolution, err) ||
        !jf_get_int(v, "blend", f[4], 1, IBL_MAX_BLEND, &s->blend, err) ||
        !jf_get_int(v, "samples", f[5], 1, 4096, &s->samples, err))
        return false;
    json_t *probes = json_object_get(v, "probes");
    if (json_is_array(probes))
        return parse_probe_list(probes, f[2], s, err);
    if (probes && !jf_get_int(v, "probes", f[2], 0, IBL_MAX_PROBES, &s->probes, err))
        return job_error_set(err, f[2], "must be a count from 0 to %d, or a list of "
                             "{\"position\": [x, y, z], \"radius\": r}", IBL_MAX_PROBES);
    if (probes)
        s->placed = false;
    return true;
}

bool shadow_spec_parse(const json_t *v, const char *field, struct shadow_spec *s,
                       struct job_error *err)
{
    bool object;
    if (!get_switch(v, field, &s->enabled, &object, err))
        return false;
    if (!object)
        return true;
    static const char *const keys[] = {"layout", "atlas", "tile", "min_tile", "max_tile", "pcf",
                                       "bias", "normal_offset", "overflow", NULL};
    char prefix[48], f[9][64];
    for (int i = 0; i < 9; i++)
        snprintf(f[i], sizeof(f[i]), "%s.%s", field, keys[i]);
    snprintf(prefix, sizeof(prefix), "%s.", field);
    if (!jf_check_keys(v, prefix, keys, err) ||
        !jf_get_choice(v, "layout", f[0], shadow_layout_names, &s->layout, err) ||
        !get_pow2(v, "atlas", f[1], 256, SHADOW_MAX_ATLAS, &s->atlas, err) ||
        !get_pow2(v, "min_tile", f[3], SHADOW_MIN_TILE, SHADOW_MAX_ATLAS, &s->min_tile, err) ||
        !get_pow2(v, "max_tile", f[4], SHADOW_MIN_TILE, SHADOW_MAX_ATLAS, &s->max_tile, err) ||
        !jf_get_int(v, "pcf", f[5], 0, 3, &s->pcf, err) ||
        !jf_get_number(v, "bias", f[6], 0.0, 10.0, &s->bias, err) ||
        !jf_get_number(v, "normal_offset", f[7], 0.0, 16.0, &s->normal_offset, err) ||
        !jf_get_choice(v, "overflow", f[8], shadow_overflow_names, &s->overflow, err))
        return false;
    json_t *tile = json_object_get(v, "tile");
    if (json_is_string(tile) && strcmp(json_string_value(tile), "auto") == 0)
        s->tile = 0;
    else if (tile && !get_pow2(v, "tile", f[2], SHADOW_MIN_TILE, SHADOW_MAX_ATLAS, &s->tile, err))
        return job_error_set(err, f[2], "must be \"auto\" (sized by importance on screen) or a "
                             "power of two from %d to %d", SHADOW_MIN_TILE, SHADOW_MAX_ATLAS);
    /* A light's six faces must fit the atlas at the smallest size it may take. */
    int smallest = s->tile ? s->tile : s->min_tile;
    if (smallest * 4 > s->atlas)
        return job_error_set(err, s->tile ? f[2] : f[3], "%d leaves no room for one light's six "
                             "faces in a %d atlas: at most atlas / 4", smallest, s->atlas);
    if (s->min_tile > s->max_tile)
        return job_error_set(err, f[3], "must be at most max_tile (%d)", s->max_tile);
    if (s->layout == SHADOW_LAYOUT_CUBES && !s->tile)
        s->tile = s->max_tile < 256 ? s->max_tile : 256;
    return true;
}

json_t *ibl_spec_to_json(const struct ibl_spec *s)
{
    if (!s->enabled)
        return json_false();
    json_t *probes;
    if (s->placed) {
        probes = json_array();
        for (int i = 0; i < s->probes; i++)
            json_array_append_new(probes, json_pack("{s:[f, f, f], s:f}", "position",
                                                    s->probe[i].pos[0], s->probe[i].pos[1],
                                                    s->probe[i].pos[2], "radius",
                                                    s->probe[i].radius));
    } else {
        probes = json_integer(s->probes);
    }
    return json_pack("{s:s, s:f, s:o, s:i, s:i, s:i}", "environment",
                     ibl_environment_names[s->environment], "intensity", s->intensity, "probes",
                     probes, "resolution", s->resolution, "blend", s->blend, "samples",
                     s->samples);
}

json_t *shadow_spec_to_json(const struct shadow_spec *s)
{
    if (!s->enabled)
        return json_false();
    return json_pack("{s:s, s:i, s:o, s:i, s:i, s:i, s:f, s:f, s:s}", "layout",
                     shadow_layout_names[s->layout], "atlas", s->atlas, "tile",
                     s->tile ? json_integer(s->tile) : json_string("auto"), "min_tile",
                     s->min_tile, "max_tile", s->max_tile, "pcf", s->pcf, "bias", s->bias,
                     "normal_offset", s->normal_offset, "overflow",
                     shadow_overflow_names[s->overflow]);
}
