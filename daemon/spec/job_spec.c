#define _POSIX_C_SOURCE 200809L
#include "daemon/spec/job_spec.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/spec/job_cost.h"


/* A technique name from the catalogue; null gives "" (index -1) where allowed. */
static bool get_technique(const json_t *v, const char *field,
                          const struct technique_catalog *techniques, bool nullable, char *out,
                          size_t cap, int *index, struct job_error *err)
{
    if (nullable && json_is_null(v)) {
        out[0] = '\0';
        *index = -1;
        return true;
    }
    int i = json_is_string(v) ? technique_catalog_find(techniques, json_string_value(v)) : -1;
    if (i >= 0) {
        snprintf(out, cap, "%s", techniques->infos[i]->name);
        *index = i;
        return true;
    }
    char list[400];
    technique_catalog_list(techniques, 0, list, sizeof(list));
    return job_error_set(err, field, "must be one of: %s%s", list, nullable ? ", or null" : "");
}

/* Top-level fields that became options of a technique, still accepted (and
 * written back) for the bodies and clients written before. */
static const struct {
    const char *field, *path;
} ALIASES[] = {
    {"async_distance", "osl.async_distance"},
};
enum { NALIASES = sizeof(ALIASES) / sizeof(ALIASES[0]) };

const char *job_spec_alias(const char *field)
{
    for (int i = 0; i < NALIASES; i++)
        if (strcmp(ALIASES[i].field, field) == 0)
            return ALIASES[i].path;
    return NULL;
}

const char *job_spec_aliased(const char *path)
{
    for (int i = 0; i < NALIASES; i++)
        if (strcmp(ALIASES[i].path, path) == 0)
            return ALIASES[i].field;
    return NULL;
}

/* The technique (catalogue index) and option an alias stands for; false
 * when the catalogue has no such option. */
static bool alias_target(const struct technique_catalog *c, int alias, int *technique,
                         const struct opt_field **opt)
{
    const char *path = ALIASES[alias].path, *dot = strchr(path, '.');
    char name[32];
    snprintf(name, sizeof(name), "%.*s", (int)(dot - path), path);
    *technique = technique_catalog_find(c, name);
    *opt = technique_catalog_option(c, path);
    return *technique >= 0 && *opt;
}

static double default_timeout_s, max_job_s, max_frame_s = JOB_DEFAULT_MAX_FRAME_S;
static int max_msaa;

void job_spec_set_max_frame_seconds(double seconds) { max_frame_s = seconds > 0 ? seconds : 0; }
double job_spec_max_frame_seconds(void) { return max_frame_s; }

void job_spec_set_max_msaa(int samples) { max_msaa = samples > 0 ? samples : 0; }
int job_spec_max_msaa(void) { return max_msaa; }

void job_spec_set_default_timeout(double seconds) { default_timeout_s = seconds; }
double job_spec_default_timeout(void) { return default_timeout_s; }
void job_spec_set_max_seconds(double seconds) { max_job_s = seconds > 0 ? seconds : 0; }
double job_spec_max_seconds(void) { return max_job_s; }

/* timeout_s within the daemon's limit: a job's own is refused above it, the
 * default is capped to it. */
static bool apply_max_seconds(const json_t *body, struct job_spec *out, struct job_error *err)
{
    if (max_job_s <= 0 || (out->timeout_s > 0 && out->timeout_s <= max_job_s))
        return true;
    if (json_object_get(body, "timeout_s"))
        return job_error_set(err, "timeout_s",
                             "%g s (0 is no limit) is more than this daemon lets a job run "
                             "(--max-job-seconds %g; /v1/info: limits.max_job_seconds)",
                             out->timeout_s, max_job_s);
    out->timeout_s = max_job_s;
    return true;
}

void job_spec_defaults(struct job_spec *out, const struct technique_catalog *techniques)
{
    memset(out, 0, sizeof(*out));
    out->catalog = techniques;
    /* A job that names no technique runs the baseline. */
    out->technique_index = techniques->baseline;
    if (techniques->baseline >= 0)
        snprintf(out->technique, sizeof(out->technique), "%s",
                 techniques->infos[techniques->baseline]->name);
    out->reference_index = -1;
    out->frames = JOB_DEFAULT_FRAMES;
    out->warmup_frames = JOB_DEFAULT_WARMUP_FRAMES;
    out->capture_interval = 0;
    scene_spec_defaults(&out->scene);
    look_spec_defaults(&out->look);
    out->reference_look = out->look;
    for (int i = 0; i < techniques->count; i++)
        opt_defaults(&techniques->infos[i]->options, out->options[i].bytes);
    out->repeat = 1;
    out->repeat_auto = false;
    out->reference[0] = '\0';
    out->reference_supersample = 1;
    fidelity_spec_defaults(&out->fidelity);
    out->temporal_frames = 0;
    metrics_options_defaults(&out->metrics);
    out->timeout_s = default_timeout_s;
    out->msaa = 1;
}

const void *job_spec_technique_options(const struct job_spec *spec)
{
    return spec->technique_index >= 0 ? spec->options[spec->technique_index].bytes : NULL;
}

void job_spec_needs(const struct job_spec *spec, bool reference, struct frame_needs *out)
{
    *out = (struct frame_needs){0};
    int t = reference ? spec->reference_index : spec->technique_index;
    const struct technique_info *info = t >= 0 ? spec->catalog->infos[t] : NULL;
    if (info && info->needs)
        info->needs(spec->options[t].bytes, out);
    post_spec_needs(reference ? &spec->reference_look.post : &spec->look.post, out);
}

const void *job_spec_reference_options(const struct job_spec *spec)
{
    return spec->reference_index >= 0 ? spec->options[spec->reference_index].bytes : NULL;
}

/* "reference": a technique name, null, or {"technique": NAME, "supersample":
 * N}; the object's technique defaults to the baseline, so that a sweep may
 * vary reference.supersample over a base job that names no reference. */
static bool parse_reference(const json_t *v, const struct technique_catalog *techniques,
                            struct job_spec *out, struct job_error *err)
{
    if (!json_is_object(v))
        return get_technique(v, "reference", techniques, true, out->reference,
                             sizeof(out->reference), &out->reference_index, err);
    static const char *const keys[] = {"technique", "supersample", NULL};
    if (!jf_check_keys(v, "reference.", keys, err))
        return false;
    json_t *name = json_object_get(v, "technique");
    if (name && !get_technique(name, "reference.technique", techniques, false, out->reference,
                               sizeof(out->reference), &out->reference_index, err))
        return false;
    if (!name) {
        if (techniques->baseline < 0)
            return job_error_set(err, "reference.technique", "must be given: no technique is "
                                 "the baseline");
        out->reference_index = techniques->baseline;
        snprintf(out->reference, sizeof(out->reference), "%s",
                 techniques->infos[techniques->baseline]->name);
    }
    return jf_get_int(v, "supersample", "reference.supersample", 1, JOB_MAX_SUPERSAMPLE,
                      &out->reference_supersample, err);
}

/* "temporal": {"frames": K}. */
static bool parse_temporal(const json_t *v, struct job_spec *out, struct job_error *err)
{
    static const char *const keys[] = {"frames", NULL};
    if (!json_is_object(v))
        return job_error_set(err, "temporal", "must be an object: {\"frames\": K}");
    if (!jf_check_keys(v, "temporal.", keys, err))
        return false;
    if (!json_object_get(v, "frames"))
        return job_error_set(err, "temporal.frames", "must be given (%d to %d)",
                             JOB_MIN_TEMPORAL_FRAMES, JOB_MAX_TEMPORAL_FRAMES);
    return jf_get_int(v, "frames", "temporal.frames", JOB_MIN_TEMPORAL_FRAMES,
                      JOB_MAX_TEMPORAL_FRAMES, &out->temporal_frames, err);
}

/* "repeat": N, or {"auto": true, "max": M}. */
static bool parse_repeat(const json_t *v, struct job_spec *out, struct job_error *err)
{
    if (json_is_object(v)) {
        static const char *const keys[] = {"auto", "max", NULL};
        out->repeat = 30;
        if (!jf_check_keys(v, "repeat.", keys, err) ||
            !jf_get_bool(v, "auto", "repeat.auto", &out->repeat_auto, err) ||
            !jf_get_int(v, "max", "repeat.max", 3, 1000, &out->repeat, err))
            return false;
        if (!out->repeat_auto)
            return job_error_set(err, "repeat.auto", "must be true (or give repeat as a number of runs)");
        return true;
    }
    json_t *wrapped = json_pack("{s:O}", "repeat", v);
    bool ok = jf_get_int(wrapped, "repeat", "repeat", 1, 1000, &out->repeat, err);
    json_decref(wrapped);
    if (!ok)
        snprintf(err->message, sizeof(err->message),
                 "must be a number of runs from 1 to 1000, or {\"auto\": true, \"max\": N}");
    return ok;
}

static const char *const METRIC_NAMES[] = {"ssim", "pdiff", "psnr", "flip", NULL};

static bool parse_pdiff(const json_t *v, struct pdiff_options *p, struct job_error *err)
{
    static const char *const keys[] = {"fov", "threshold_pixels", "gamma", "luminance",
                                       "color_factor", "luminance_only", NULL};
    int threshold = (int)p->threshold_pixels;
    if (!jf_check_keys(v, "metrics.pdiff.", keys, err) ||
        !jf_get_number(v, "fov", "metrics.pdiff.fov", 0.1, 179.0, &p->fov, err) ||
        !jf_get_int(v, "threshold_pixels", "metrics.pdiff.threshold_pixels", 0, 1000000000,
                 &threshold, err) ||
        !jf_get_number(v, "gamma", "metrics.pdiff.gamma", 0.1, 10.0, &p->gamma, err) ||
        !jf_get_number(v, "luminance", "metrics.pdiff.luminance", 0.01, 100000.0,
                    &p->luminance, err) ||
        !jf_get_number(v, "color_factor", "metrics.pdiff.color_factor", 0.0, 100.0,
                    &p->color_factor, err) ||
        !jf_get_bool(v, "luminance_only", "metrics.pdiff.luminance_only", &p->luminance_only, err))
        return false;
    p->threshold_pixels = threshold;
    return true;
}

/* "metrics": ["ssim", "flip"] computes those only; {"pdiff": {"fov": 30},
 * "flip": false} configures or switches off single metrics, others stay on. */
static bool parse_metrics(const json_t *v, struct metrics_options *m, struct job_error *err)
{
    if (json_is_array(v)) {
        m->which = 0;
        size_t i;
        json_t *name;
        json_array_foreach(v, i, name) {
            unsigned bit = 0;
            for (int k = 0; METRIC_NAMES[k]; k++)
                if (json_is_string(name) && strcmp(json_string_value(name), METRIC_NAMES[k]) == 0)
                    bit = 1u << k;
            if (!bit)
                return job_error_set(err, "metrics", "must list metrics from: \"ssim\", \"pdiff\", "
                            "\"psnr\", \"flip\"");
            m->which |= bit;
        }
        if (!m->which)
            return job_error_set(err, "metrics", "must name at least one metric");
        return true;
    }
    if (!json_is_object(v))
        return job_error_set(err, "metrics", "must be an object or a list of metric names");
    if (!jf_check_keys(v, "metrics.", METRIC_NAMES, err))
        return false;
    for (int k = 0; METRIC_NAMES[k]; k++) {
        json_t *opt = json_object_get(v, METRIC_NAMES[k]);
        char field[32];
        snprintf(field, sizeof(field), "metrics.%s", METRIC_NAMES[k]);
        if (!opt)
            continue;
        if (json_is_boolean(opt)) {
            if (json_is_true(opt))
                m->which |= 1u << k;
            else
                m->which &= ~(1u << k);
            continue;
        }
        bool configurable = (1u << k) == METRIC_PDIFF || (1u << k) == METRIC_FLIP;
        if (!json_is_object(opt) || !configurable)
            return job_error_set(err, field, configurable ? "must be true, false or an options object"
                                                 : "must be true or false");
        m->which |= 1u << k;
        if ((1u << k) == METRIC_PDIFF && !parse_pdiff(opt, &m->pdiff, err))
            return false;
        if ((1u << k) == METRIC_FLIP) {
            static const char *const keys[] = {"pixels_per_degree", NULL};
            if (!jf_check_keys(opt, "metrics.flip.", keys, err) ||
                !jf_get_number(opt, "pixels_per_degree", "metrics.flip.pixels_per_degree", 1.0,
                            1000.0, &m->flip_ppd, err))
                return false;
        }
    }
    if (!m->which)
        return job_error_set(err, "metrics", "switches every metric off: leave out reference instead");
    return true;
}

static int by_label_key(const void *a, const void *b)
{
    return strcmp(((const struct job_label *)a)->key, ((const struct job_label *)b)->key);
}

/* "labels": {"commit": "abc123", "branch": "main"}. Sorted by key, so that
 * the spec as understood does not depend on the order they were sent in. */
static bool parse_labels(const json_t *v, struct job_spec *out, struct job_error *err)
{
    if (!json_is_object(v))
        return job_error_set(err, "labels", "must be an object of strings, like "
                             "{\"commit\": \"abc123\", \"branch\": \"main\"}");
    if (json_object_size(v) > JOB_MAX_LABELS)
        return job_error_set(err, "labels", "at most %d labels", JOB_MAX_LABELS);
    const char *key;
    json_t *value;
    out->nlabels = 0;
    json_object_foreach((json_t *)v, key, value) {
        char field[64];
        snprintf(field, sizeof(field), "labels.%s", key);
        size_t klen = strlen(key);
        bool key_ok = klen >= 1 && klen <= JOB_LABEL_KEY_MAX;
        for (size_t i = 0; key_ok && i < klen; i++)
            key_ok = (key[i] >= 'a' && key[i] <= 'z') || (key[i] >= 'A' && key[i] <= 'Z') ||
                     (key[i] >= '0' && key[i] <= '9') || key[i] == '_' || key[i] == '-' ||
                     key[i] == '.';
        if (!key_ok)
            return job_error_set(err, field, "label names are 1 to %d characters of A-Z, a-z, "
                                 "0-9, '_', '-' and '.'", JOB_LABEL_KEY_MAX);
        if (!json_is_string(value))
            return job_error_set(err, field, "must be a string");
        const char *s = json_string_value(value);
        size_t vlen = json_string_length(value);
        if (vlen > JOB_LABEL_VALUE_MAX)
            return job_error_set(err, field, "must be at most %d bytes (got %zu)",
                                 JOB_LABEL_VALUE_MAX, vlen);
        for (size_t i = 0; i < vlen; i++)
            if ((unsigned char)s[i] < 0x20 || s[i] == 0x7f)
                return job_error_set(err, field, "must not contain control characters");
        struct job_label *l = &out->labels[out->nlabels++];
        snprintf(l->key, sizeof(l->key), "%s", key);
        snprintf(l->value, sizeof(l->value), "%s", s);
    }
    qsort(out->labels, (size_t)out->nlabels, sizeof(out->labels[0]), by_label_key);
    return true;
}

/* Whether a job body's scene is drawn through the asset path (scene.asset,
 * or the textured preset), before the scene itself is parsed. */
static bool asset_scene_body(const json_t *scene)
{
    const char *preset = json_string_value(json_object_get(scene, "preset"));
    return json_object_get(scene, "asset") || (preset && strcmp(preset, "textured") == 0);
}

bool job_spec_parse(const json_t *body, const struct technique_catalog *techniques,
                    struct job_spec *out, struct job_error *err)
{
    static const char *const fixed[] = {"technique", "frames", "warmup_frames",
                                        "capture_interval", "scene", "look", "reference",
                                        "reference_look", "metrics", "repeat", "labels",
                                        "timeout_s", "temporal", "msaa", "fidelity",
                                        "accept_sliced_timing"};
    enum { NFIXED = sizeof(fixed) / sizeof(fixed[0]) };
    /* Every technique's options live under its own name; an alias is known
     * when the catalogue has the option it stands for. */
    const char *keys[NFIXED + NALIASES + TECHNIQUE_MAX + 1];
    int nkeys = 0;
    for (int i = 0; i < NFIXED; i++)
        keys[nkeys++] = fixed[i];
    for (int a = 0; a < NALIASES; a++) {
        int t;
        const struct opt_field *opt;
        if (alias_target(techniques, a, &t, &opt))
            keys[nkeys++] = ALIASES[a].field;
    }
    for (int i = 0; i < techniques->count; i++)
        keys[nkeys++] = techniques->infos[i]->name;
    keys[nkeys] = NULL;

    job_spec_defaults(out, techniques);
    memset(err, 0, sizeof(*err));
    if (!json_is_object(body))
        return job_error_set(err, "body", "the job must be a JSON object");
    if (!jf_check_keys(body, "", keys, err))
        return false;

    json_t *tech = json_object_get(body, "technique");
    if (tech && !get_technique(tech, "technique", techniques, false, out->technique,
                               sizeof(out->technique), &out->technique_index, err))
        return false;
    if (out->technique_index < 0)
        return job_error_set(err, "technique", "must be given: no technique is the baseline "
                             "a job runs by default");
    json_t *ref = json_object_get(body, "reference");
    if (ref && !parse_reference(ref, techniques, out, err))
        return false;
    /* An alias first, so that the technique's own object may state the
     * same value again, and a different one is caught below. */
    for (int a = 0; a < NALIASES; a++) {
        json_t *v = json_object_get(body, ALIASES[a].field);
        int t;
        const struct opt_field *opt;
        if (v && (!alias_target(techniques, a, &t, &opt) ||
                  !opt_parse_value(opt, v, ALIASES[a].field, out->options[t].bytes, err)))
            return false;
    }
    for (int i = 0; i < techniques->count; i++) {
        json_t *opts = json_object_get(body, techniques->infos[i]->name);
        if (!opts)
            continue;
        const struct technique_info *t = techniques->infos[i];
        if (!opt_parse(&t->options, opts, t->name, out->options[i].bytes, err))
            return false;
        out->options_given |= 1u << i;
    }
    for (int a = 0; a < NALIASES; a++) {
        json_t *v = json_object_get(body, ALIASES[a].field);
        int t;
        const struct opt_field *opt;
        if (!v || !alias_target(techniques, a, &t, &opt))
            continue;
        struct opt_values again = out->options[t];
        opt_parse_value(opt, v, ALIASES[a].field, again.bytes, err);
        if (memcmp(&again, &out->options[t], sizeof(again)) != 0)
            return job_error_set(err, ALIASES[a].field, "is an alias of %s, which the job "
                                 "gives another value: give one of them", ALIASES[a].path);
    }
    /* What runs is always written back; the bit records only the rest, so
     * that the spec is the same after a round trip. */
    out->options_given &= ~(1u << out->technique_index);
    if (out->reference_index >= 0)
        out->options_given &= ~(1u << out->reference_index);
    /* An asset scene is shown display-referred unless the look says
     * otherwise (docs/scenes.md, "Asset scenes' defaults"): Khronos PBR
     * Neutral keeps base colours and compresses what would clip. */
    bool asset_scene = asset_scene_body(json_object_get(body, "scene"));
    if (asset_scene)
        out->look.tonemap = LOOK_TONEMAP_PBR_NEUTRAL;
    json_t *look;
    if (!jf_get_object(body, "look", "look", &look, err) ||
        (look && !look_spec_parse(look, "look", &out->look, err)))
        return false;
    /* The reference renders with the same look unless told otherwise; a
     * reference_look is a whole look, read over the defaults. */
    json_t *ref_look;
    out->reference_look = out->look;
    /* ...less its anti-aliasing effects (TAA): the reference is the truth
     * they approximate, supersampled or not. */
    post_spec_drop_antialiasing(&out->reference_look.post);
    if (!jf_get_object(body, "reference_look", "reference_look", &ref_look, err))
        return false;
    if (ref_look) {
        look_spec_defaults(&out->reference_look);
        if (asset_scene)
            out->reference_look.tonemap = LOOK_TONEMAP_PBR_NEUTRAL;
        out->reference_look_given = true;
        /* Probes and shadow maps are made once a run, for both: a
         * reference_look takes the look's, or states them the same. */
        if (!json_object_get(ref_look, "ibl"))
            out->reference_look.ibl = out->look.ibl;
        if (!json_object_get(ref_look, "shadows"))
            out->reference_look.shadows = out->look.shadows;
        if (!look_spec_parse(ref_look, "reference_look", &out->reference_look, err))
            return false;
        if (memcmp(&out->reference_look.ibl, &out->look.ibl, sizeof(out->look.ibl)) != 0)
            return job_error_set(err, "reference_look.ibl", "must equal look.ibl (leave it out): "
                                 "the probes are captured once for the job and its reference");
        if (memcmp(&out->reference_look.shadows, &out->look.shadows,
                   sizeof(out->look.shadows)) != 0)
            return job_error_set(err, "reference_look.shadows", "must equal look.shadows (leave "
                                 "it out): the shadow maps are rendered once a frame for both");
    }
    json_t *metrics = json_object_get(body, "metrics");
    if (metrics && !parse_metrics(metrics, &out->metrics, err))
        return false;
    json_t *repeat = json_object_get(body, "repeat");
    if (repeat && !parse_repeat(repeat, out, err))
        return false;
    json_t *labels = json_object_get(body, "labels");
    if (labels && !parse_labels(labels, out, err))
        return false;
    json_t *temporal = json_object_get(body, "temporal");
    if (temporal && !parse_temporal(temporal, out, err))
        return false;
    if (!jf_get_int(body, "frames", "frames", 1, 1000000, &out->frames, err) ||
        !jf_get_int(body, "warmup_frames", "warmup_frames", 0, 10000,
                 &out->warmup_frames, err) ||
        !jf_get_int(body, "capture_interval", "capture_interval", 0, 1000000,
                 &out->capture_interval, err) ||
        !jf_get_number(body, "timeout_s", "timeout_s", 0.0, 1e7, &out->timeout_s, err) ||
        !apply_max_seconds(body, out, err) ||
        !jf_get_int(body, "msaa", "msaa", 1, 8, &out->msaa, err) ||
        !jf_get_bool(body, "accept_sliced_timing", "accept_sliced_timing",
                     &out->accept_sliced_timing, err))
        return false;
    if (out->msaa & (out->msaa - 1))
        return job_error_set(err, "msaa", "must be 1, 2, 4 or 8 (samples a pixel)");
    if (max_msaa && out->msaa > max_msaa)
        return job_error_set(err, "msaa", "must be at most %d: this device's limit (/v1/info: "
                             "device.caps.max_msaa, the least of GL_MAX_SAMPLES, "
                             "GL_MAX_COLOR_TEXTURE_SAMPLES and GL_MAX_DEPTH_TEXTURE_SAMPLES)",
                             max_msaa);

    json_t *scene;
    if (!jf_get_object(body, "scene", "scene", &scene, err) ||
        (scene && !scene_spec_parse(scene, &out->scene, err)))
        return false;

    if (!fidelity_spec_parse(json_object_get(body, "fidelity"), &out->fidelity, err) ||
        !fidelity_spec_check_job(&out->fidelity, &out->scene, &out->look, out->reference,
                                 out->repeat, out->repeat_auto, out->temporal_frames, out->msaa,
                                 err))
        return false;
    if (out->fidelity.enabled && out->capture_interval == 0 &&
        !json_object_get(body, "capture_interval"))
        out->capture_interval = out->frames; /* the last frame is compared */
    if (out->fidelity.enabled && out->capture_interval == 0)
        return job_error_set(err, "fidelity", "needs capture_interval > 0: the captured frames "
                             "are compared");
    /* A reference with no word on captures scores the last frame, as a
     * sweep's point does; an explicit 0 asks for no captures at all. */
    if (out->reference[0] && out->capture_interval == 0 && !json_object_get(body, "capture_interval"))
        out->capture_interval = out->frames;
    if (out->reference[0] && out->capture_interval == 0)
        return job_error_set(err, "reference", "needs capture_interval > 0: metrics compare the "
                    "captured frames with the reference's");
    if (metrics && !out->reference[0])
        return job_error_set(err, "metrics", "needs a reference technique to compare with");
    /* GL 4.5 guarantees textures and viewports of 16384 a side (the
     * device may allow more; run.c checks its own limits too). */
    if (out->reference_supersample > 1 &&
        ((long)out->scene.width * out->reference_supersample > JOB_SUPERSAMPLE_MAX_SIDE ||
         (long)out->scene.height * out->reference_supersample > JOB_SUPERSAMPLE_MAX_SIDE))
        return job_error_set(err, "reference.supersample", "renders %dx%d at %dx%d, more than "
                             "the %d a side every OpenGL 4.5 device takes: lower it or the size",
                             out->scene.width, out->scene.height,
                             out->scene.width * out->reference_supersample,
                             out->scene.height * out->reference_supersample,
                             JOB_SUPERSAMPLE_MAX_SIDE);
    if (temporal && !out->reference[0])
        return job_error_set(err, "temporal", "needs a reference technique: flicker compares "
                             "the technique's change from frame to frame with the reference's");
    if (ref_look && !out->reference[0])
        return job_error_set(err, "reference_look", "needs a reference technique to render "
                             "with it");
    if (out->reference[0] && (out->metrics.which & METRIC_SSIM) &&
        (out->scene.width < SSIM_WINDOW || out->scene.height < SSIM_WINDOW))
        return job_error_set(err, "metrics.ssim", "needs frames of at least 11x11 pixels");
    if (out->capture_interval > out->frames)
        return job_error_set(err, "capture_interval",
                    "must be 0 (no captures) or at most frames (%d)", out->frames);
    /* Frame k is a pure function of k: a history starts afresh its length
     * before each captured frame, which a capture closer than that to the
     * one before would cut short. */
    struct frame_needs needs, ref_needs = {0};
    job_spec_needs(out, false, &needs);
    if (out->reference[0])
        job_spec_needs(out, true, &ref_needs);
    int history = needs.history_frames > ref_needs.history_frames ? needs.history_frames
                                                                  : ref_needs.history_frames;
    if (history && job_spec_capture_count(out) > 1 && out->capture_interval <= history)
        return job_error_set(err, "capture_interval",
                    "must be more than the %d frames of history the technique and look.post "
                    "keep (frame k is a pure function of k: each history starts afresh %d "
                    "frames before each captured frame), or capture one frame",
                    history, history);
    if (needs.history_frames && job_spec_capture_count(out) > 0 &&
        out->capture_interval - 1 + out->warmup_frames < needs.history_frames)
        return job_error_set(err, "warmup_frames",
                    "must be at least %d: the first captured frame (%d) needs the %d frames of "
                    "history the technique and look.post keep drawn before it",
                    needs.history_frames - out->capture_interval + 1, out->capture_interval,
                    needs.history_frames);
    if (job_spec_capture_count(out) > JOB_MAX_CAPTURES)
        return job_error_set(err, "capture_interval", "would capture %d frames; at most %d a job",
                             job_spec_capture_count(out), JOB_MAX_CAPTURES);
    /* Captured frames are kept in memory until the timed run ends, so that
     * encoding never lands inside the measurement: bound that memory. */
    double bytes = (double)job_spec_capture_count(out) * out->scene.width *
                   out->scene.height * 4.0;
    if (bytes > JOB_MAX_CAPTURE_BYTES)
        return job_error_set(err, "capture_interval",
                    "would keep %d captures of %dx%d (%.0f MiB) in memory; the "
                    "limit is %.0f MiB, raise capture_interval",
                    job_spec_capture_count(out), out->scene.width,
                    out->scene.height, bytes / 1048576.0,
                    JOB_MAX_CAPTURE_BYTES / 1048576.0);
    /* Admission: the estimate of the memory it holds, against what a job
     * may take (job_cost.h; no limit unless the daemon set one). */
    struct job_cost cost;
    job_cost_estimate(out, &cost);
    return job_cost_admit(&cost, err);
}

bool job_spec_parse_text(const char *text, size_t len,
                         const struct technique_catalog *techniques, struct job_spec *out,
                         struct job_error *err)
{
    json_error_t jerr;
    /* Jansson stops at a NUL byte as at the end of the text: whatever
     * follows one would go unread. JSON text has none. */
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        job_spec_defaults(out, techniques);
        return job_error_set(err, "body", "must be JSON text, which has no NUL byte (one at "
                             "byte %zu)", (size_t)(nul - text));
    }
    json_t *body = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!body) {
        job_spec_defaults(out, techniques);
        return job_error_set(err, "body", "malformed JSON at line %d, column %d: %s",
                    jerr.line, jerr.column, jerr.text);
    }
    if (!jf_check_numbers(text, len, err)) {
        json_decref(body);
        job_spec_defaults(out, techniques);
        return false;
    }
    bool ok = job_spec_parse(body, techniques, out, err);
    json_decref(body);
    return ok;
}

int job_spec_runs(const struct job_spec *spec) { return spec->repeat; }

int job_spec_capture_count(const struct job_spec *spec)
{
    return spec->capture_interval > 0 ? spec->frames / spec->capture_interval : 0;
}

bool job_spec_is_capture_frame(const struct job_spec *spec, int frame)
{
    return spec->capture_interval > 0 && frame > 0 &&
           frame % spec->capture_interval == 0;
}

static json_t *metrics_to_json(const struct metrics_options *m)
{
    json_t *o = json_object();
    const struct pdiff_options *p = &m->pdiff;
    if (m->which & METRIC_SSIM)
        json_object_set_new(o, "ssim", json_true());
    if (m->which & METRIC_PDIFF)
        json_object_set_new(o, "pdiff",
                            json_pack("{s:f, s:I, s:f, s:f, s:f, s:b}", "fov", p->fov,
                                      "threshold_pixels", (json_int_t)p->threshold_pixels,
                                      "gamma", p->gamma, "luminance", p->luminance,
                                      "color_factor", p->color_factor, "luminance_only",
                                      p->luminance_only));
    if (m->which & METRIC_PSNR)
        json_object_set_new(o, "psnr", json_true());
    if (m->which & METRIC_FLIP)
        json_object_set_new(o, "flip", json_pack("{s:f}", "pixels_per_degree", m->flip_ppd));
    for (int k = 0; METRIC_NAMES[k]; k++)
        if (!(m->which & (1u << k)))
            json_object_set_new(o, METRIC_NAMES[k], json_false());
    return o;
}

json_t *job_spec_to_json(const struct job_spec *spec)
{
    json_t *out = json_pack("{s:s, s:i, s:i, s:i}", "technique", spec->technique, "frames",
                            spec->frames, "warmup_frames", spec->warmup_frames,
                            "capture_interval", spec->capture_interval);
    const struct technique_catalog *c = spec->catalog;
    /* Aliases keep their place for the clients that read them there. */
    for (int a = 0; c && a < NALIASES; a++) {
        int t;
        const struct opt_field *opt;
        if (!alias_target(c, a, &t, &opt))
            continue;
        json_t *options = opt_to_json(&c->infos[t]->options, spec->options[t].bytes);
        json_t *v = json_object_get(options, opt->name);
        if (v)
            json_object_set(out, ALIASES[a].field, v);
        json_decref(options);
    }
    json_object_set_new(out, "scene", scene_spec_to_json(&spec->scene));
    json_object_set_new(out, "look", look_spec_to_json(&spec->look));
    /* The options of what runs (technique and reference) and of whatever the
     * body set, so that the spec round-trips. */
    for (int i = 0; c && i < c->count; i++)
        if (i == spec->technique_index || i == spec->reference_index ||
            (spec->options_given & (1u << i)))
            json_object_set_new(out, c->infos[i]->name,
                                opt_to_json(&c->infos[i]->options, spec->options[i].bytes));
    json_object_set_new(out, "repeat",
                        spec->repeat_auto ? json_pack("{s:b, s:i}", "auto", 1, "max", spec->repeat)
                                          : json_integer(spec->repeat));
    /* The shorthand whenever it says it all, so that specs without a
     * supersampled reference read as they always did. */
    json_object_set_new(out, "reference",
                        !spec->reference[0] ? json_null()
                        : spec->reference_supersample > 1
                            ? json_pack("{s:s, s:i}", "technique", spec->reference,
                                        "supersample", spec->reference_supersample)
                            : json_string(spec->reference));
    if (spec->temporal_frames)
        json_object_set_new(out, "temporal", json_pack("{s:i}", "frames", spec->temporal_frames));
    json_object_set_new(out, "timeout_s", json_real(spec->timeout_s));
    json_object_set_new(out, "msaa", json_integer(spec->msaa));
    /* Only when set, so that the specs of whole-timed jobs read (and hash)
     * as they always did. */
    if (spec->accept_sliced_timing)
        json_object_set_new(out, "accept_sliced_timing", json_true());
    if (spec->reference[0])
        json_object_set_new(out, "metrics", metrics_to_json(&spec->metrics));
    if (spec->reference_look_given)
        json_object_set_new(out, "reference_look", look_spec_to_json(&spec->reference_look));
    if (spec->fidelity.enabled)
        json_object_set_new(out, "fidelity", fidelity_spec_to_json(&spec->fidelity));
    json_t *labels = json_object();
    for (int i = 0; i < spec->nlabels; i++)
        json_object_set_new(labels, spec->labels[i].key, json_string(spec->labels[i].value));
    json_object_set_new(out, "labels", labels);
    return out;
}


bool job_spec_names_asset(const struct job_spec *spec)
{
    const struct ibl_spec *a = &spec->look.ibl, *b = &spec->reference_look.ibl;
    return spec->scene.asset[0] || (a->enabled && a->environment == IBL_ENV_ASSET) ||
           (b->enabled && b->environment == IBL_ENV_ASSET);
}
