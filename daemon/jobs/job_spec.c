#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/job_spec.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>


bool job_error_set(struct job_error *err, const char *field, const char *fmt, ...)
{
    snprintf(err->field, sizeof(err->field), "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof(err->message), fmt, ap);
    va_end(ap);
    return false;
}

static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 40 || lb > 40)
        return 99;
    size_t row[41];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            size_t best = diag + cost;
            if (row[j] + 1 < best)
                best = row[j] + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* Rejects keys not in known, suggesting the closest one for typos. */
static bool check_keys(const json_t *obj, const char *prefix,
                       const char *const *known, struct job_error *err)
{
    const char *key;
    json_t *value;
    json_object_foreach((json_t *)obj, key, value) {
        bool found = false;
        const char *closest = NULL;
        size_t best = 3;
        for (const char *const *k = known; *k; k++) {
            if (strcmp(*k, key) == 0) {
                found = true;
                break;
            }
            size_t d = edit_distance(*k, key);
            if (d < best) {
                best = d;
                closest = *k;
            }
        }
        if (!found) {
            char field[64];
            snprintf(field, sizeof(field), "%s%.40s", prefix, key);
            if (closest)
                return job_error_set(err, field, "unknown field (did you mean '%s%s'?)",
                            prefix, closest);
            return job_error_set(err, field, "unknown field");
        }
    }
    return true;
}

static bool get_int(const json_t *obj, const char *key, const char *field,
                    long min, long max, int *out, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    /* Accept 300.0 from tools that write every number as a double, but never 300.5. */
    double d;
    if (json_is_integer(v))
        d = (double)json_integer_value(v);
    else if (json_is_real(v) && floor(json_real_value(v)) == json_real_value(v))
        d = json_real_value(v);
    else
        return job_error_set(err, field, "must be an integer from %ld to %ld", min, max);
    if (d < (double)min || d > (double)max)
        return job_error_set(err, field, "must be an integer from %ld to %ld", min, max);
    *out = (int)d;
    return true;
}

static bool get_number(const json_t *obj, const char *key, const char *field,
                       double min, double max, double *out,
                       struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_number(v) || !isfinite(json_number_value(v)) ||
        json_number_value(v) < min || json_number_value(v) > max)
        return job_error_set(err, field, "must be a number from %g to %g", min, max);
    *out = json_number_value(v);
    return true;
}

static bool get_bool(const json_t *obj, const char *key, const char *field,
                     bool *out, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_boolean(v))
        return job_error_set(err, field, "must be true or false");
    *out = json_is_true(v);
    return true;
}

static bool get_object(const json_t *obj, const char *key, const char *field,
                       json_t **out, struct job_error *err)
{
    *out = json_object_get(obj, key);
    if (*out && !json_is_object(*out))
        return job_error_set(err, field, "must be an object");
    return true;
}

/* A technique name from the registry; null gives "" where allowed. */
static bool get_technique(const json_t *v, const char *field, const char *const *techniques,
                          bool nullable, char *out, size_t cap, struct job_error *err)
{
    if (nullable && json_is_null(v)) {
        out[0] = '\0';
        return true;
    }
    char list[200] = "";
    for (const char *const *t = techniques; *t; t++) {
        if (json_is_string(v) && strcmp(*t, json_string_value(v)) == 0) {
            snprintf(out, cap, "%s", *t);
            return true;
        }
        size_t used = strlen(list);
        snprintf(list + used, sizeof(list) - used, "%s\"%s\"", used ? ", " : "", *t);
    }
    return job_error_set(err, field, "must be one of: %s%s", list, nullable ? ", or null" : "");
}

void job_spec_defaults(struct job_spec *out)
{
    memset(out, 0, sizeof(*out));
    snprintf(out->technique, sizeof(out->technique), "forward");
    out->frames = 300;
    out->warmup_frames = 10;
    out->capture_interval = 0;
    out->async_distance = 0.0;
    snprintf(out->scene.preset, sizeof(out->scene.preset), "grid");
    out->scene.lights = 10;
    out->scene.dynamic = false;
    out->scene.width = 1080;
    out->scene.height = 720;
    out->scene.sphere_segments = 32;
    out->scene.light_speed = 1.0;
    out->osl.resolution = 256;
    out->osl.texel_density = 1.0;
    out->osl.reshade = OSL_RESHADE_TOUCHED;
    out->repeat = 1;
    out->repeat_auto = false;
    out->reference[0] = '\0';
    metrics_options_defaults(&out->metrics);
}

/* "repeat": N, or {"auto": true, "max": M}. */
static bool parse_repeat(const json_t *v, struct job_spec *out, struct job_error *err)
{
    if (json_is_object(v)) {
        static const char *const keys[] = {"auto", "max", NULL};
        out->repeat = 30;
        if (!check_keys(v, "repeat.", keys, err) ||
            !get_bool(v, "auto", "repeat.auto", &out->repeat_auto, err) ||
            !get_int(v, "max", "repeat.max", 3, 1000, &out->repeat, err))
            return false;
        if (!out->repeat_auto)
            return job_error_set(err, "repeat.auto", "must be true (or give repeat as a number of runs)");
        return true;
    }
    json_t *wrapped = json_pack("{s:O}", "repeat", v);
    bool ok = get_int(wrapped, "repeat", "repeat", 1, 1000, &out->repeat, err);
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
    if (!check_keys(v, "metrics.pdiff.", keys, err) ||
        !get_number(v, "fov", "metrics.pdiff.fov", 0.1, 179.0, &p->fov, err) ||
        !get_int(v, "threshold_pixels", "metrics.pdiff.threshold_pixels", 0, 1000000000,
                 &threshold, err) ||
        !get_number(v, "gamma", "metrics.pdiff.gamma", 0.1, 10.0, &p->gamma, err) ||
        !get_number(v, "luminance", "metrics.pdiff.luminance", 0.01, 100000.0,
                    &p->luminance, err) ||
        !get_number(v, "color_factor", "metrics.pdiff.color_factor", 0.0, 100.0,
                    &p->color_factor, err) ||
        !get_bool(v, "luminance_only", "metrics.pdiff.luminance_only", &p->luminance_only, err))
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
    if (!check_keys(v, "metrics.", METRIC_NAMES, err))
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
            if (!check_keys(opt, "metrics.flip.", keys, err) ||
                !get_number(opt, "pixels_per_degree", "metrics.flip.pixels_per_degree", 1.0,
                            1000.0, &m->flip_ppd, err))
                return false;
        }
    }
    if (!m->which)
        return job_error_set(err, "metrics", "switches every metric off: leave out reference instead");
    return true;
}

static bool parse_scene(const json_t *scene, struct scene_spec *s,
                        struct job_error *err)
{
    static const char *const keys[] = {"preset", "lights", "dynamic", "width",
                                       "height", "sphere_segments", "light_speed", NULL};
    if (!check_keys(scene, "scene.", keys, err))
        return false;
    json_t *preset = json_object_get(scene, "preset");
    if (preset) {
        if (!json_is_string(preset) || strcmp(json_string_value(preset), "grid") != 0)
            return job_error_set(err, "scene.preset", "must be one of: \"grid\"");
        snprintf(s->preset, sizeof(s->preset), "%s", json_string_value(preset));
    }
    if (!get_int(scene, "lights", "scene.lights", 0, 1024, &s->lights, err) ||
        !get_bool(scene, "dynamic", "scene.dynamic", &s->dynamic, err) ||
        !get_int(scene, "width", "scene.width", 16, 8192, &s->width, err) ||
        !get_int(scene, "height", "scene.height", 16, 8192, &s->height, err) ||
        !get_int(scene, "sphere_segments", "scene.sphere_segments", 8, 256,
                 &s->sphere_segments, err) ||
        !get_number(scene, "light_speed", "scene.light_speed", 0.0, 100.0, &s->light_speed, err))
        return false;
    if (s->sphere_segments % 2)
        return job_error_set(err, "scene.sphere_segments", "must be an even integer from 8 to 256");
    return true;
}

static bool parse_osl(const json_t *osl, struct osl_spec *o, struct job_error *err)
{
    static const char *const keys[] = {"resolution", "texel_density", "reshade", NULL};
    if (!check_keys(osl, "osl.", keys, err))
        return false;
    json_t *res = json_object_get(osl, "resolution");
    if (res) {
        static const char rule[] =
            "must be \"auto\" or a power of two from 8 to 1024";
        if (json_is_string(res)) {
            if (strcmp(json_string_value(res), "auto") != 0)
                return job_error_set(err, "osl.resolution", rule);
            o->resolution = 0;
        } else if (json_is_integer(res)) {
            json_int_t r = json_integer_value(res);
            if (r < 8 || r > 1024 || (r & (r - 1)) != 0)
                return job_error_set(err, "osl.resolution", rule);
            o->resolution = (int)r;
        } else {
            return job_error_set(err, "osl.resolution", rule);
        }
    }
    if (!get_number(osl, "texel_density", "osl.texel_density", 0.0625, 16.0,
                    &o->texel_density, err))
        return false;
    json_t *reshade = json_object_get(osl, "reshade");
    if (reshade) {
        const char *v = json_is_string(reshade) ? json_string_value(reshade) : "";
        if (strcmp(v, "touched") == 0)
            o->reshade = OSL_RESHADE_TOUCHED;
        else if (strcmp(v, "all") == 0)
            o->reshade = OSL_RESHADE_ALL;
        else
            return job_error_set(err, "osl.reshade", "must be one of: \"touched\", \"all\"");
    }
    return true;
}

bool job_spec_parse(const json_t *body, const char *const *techniques,
                    struct job_spec *out, struct job_error *err)
{
    static const char *const keys[] = {"technique", "frames", "warmup_frames",
                                       "capture_interval", "async_distance",
                                       "scene", "osl", "reference", "metrics", "repeat",
                                       NULL};
    job_spec_defaults(out);
    memset(err, 0, sizeof(*err));
    if (!json_is_object(body))
        return job_error_set(err, "body", "the job must be a JSON object");
    if (!check_keys(body, "", keys, err))
        return false;

    json_t *tech = json_object_get(body, "technique");
    if (tech && !get_technique(tech, "technique", techniques, false, out->technique,
                               sizeof(out->technique), err))
        return false;
    json_t *ref = json_object_get(body, "reference");
    if (ref && !get_technique(ref, "reference", techniques, true, out->reference,
                              sizeof(out->reference), err))
        return false;
    json_t *metrics = json_object_get(body, "metrics");
    if (metrics && !parse_metrics(metrics, &out->metrics, err))
        return false;
    json_t *repeat = json_object_get(body, "repeat");
    if (repeat && !parse_repeat(repeat, out, err))
        return false;
    if (!get_int(body, "frames", "frames", 1, 1000000, &out->frames, err) ||
        !get_int(body, "warmup_frames", "warmup_frames", 0, 10000,
                 &out->warmup_frames, err) ||
        !get_int(body, "capture_interval", "capture_interval", 0, 1000000,
                 &out->capture_interval, err) ||
        !get_number(body, "async_distance", "async_distance", 0.0, 1e6,
                    &out->async_distance, err))
        return false;

    json_t *scene, *osl;
    if (!get_object(body, "scene", "scene", &scene, err) ||
        (scene && !parse_scene(scene, &out->scene, err)) ||
        !get_object(body, "osl", "osl", &osl, err) ||
        (osl && !parse_osl(osl, &out->osl, err)))
        return false;

    if (out->reference[0] && out->capture_interval == 0)
        return job_error_set(err, "reference", "needs capture_interval > 0: metrics compare the "
                    "captured frames with the reference's");
    if (metrics && !out->reference[0])
        return job_error_set(err, "metrics", "needs a reference technique to compare with");
    if (out->reference[0] && (out->metrics.which & METRIC_SSIM) &&
        (out->scene.width < SSIM_WINDOW || out->scene.height < SSIM_WINDOW))
        return job_error_set(err, "metrics.ssim", "needs frames of at least 11x11 pixels");
    if (out->capture_interval > out->frames)
        return job_error_set(err, "capture_interval",
                    "must be 0 (no captures) or at most frames (%d)", out->frames);
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
    return true;
}

bool job_spec_parse_text(const char *text, size_t len,
                         const char *const *techniques, struct job_spec *out,
                         struct job_error *err)
{
    json_error_t jerr;
    json_t *body = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!body) {
        job_spec_defaults(out);
        return job_error_set(err, "body", "malformed JSON at line %d, column %d: %s",
                    jerr.line, jerr.column, jerr.text);
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
    json_t *res = spec->osl.resolution ? json_integer(spec->osl.resolution)
                                       : json_string("auto");
    json_t *out = json_pack(
        "{s:s, s:i, s:i, s:i, s:f, s:{s:s, s:i, s:b, s:i, s:i, s:i, s:f}, s:{s:o, s:f, s:s}}",
        "technique", spec->technique, "frames", spec->frames, "warmup_frames",
        spec->warmup_frames, "capture_interval", spec->capture_interval,
        "async_distance", spec->async_distance, "scene", "preset",
        spec->scene.preset, "lights", spec->scene.lights, "dynamic",
        spec->scene.dynamic, "width", spec->scene.width, "height",
        spec->scene.height, "sphere_segments", spec->scene.sphere_segments, "light_speed",
        spec->scene.light_speed,
        "osl", "resolution", res, "texel_density", spec->osl.texel_density,
        "reshade", spec->osl.reshade == OSL_RESHADE_ALL ? "all" : "touched");
    json_object_set_new(out, "repeat",
                        spec->repeat_auto ? json_pack("{s:b, s:i}", "auto", 1, "max", spec->repeat)
                                          : json_integer(spec->repeat));
    json_object_set_new(out, "reference",
                        spec->reference[0] ? json_string(spec->reference) : json_null());
    if (spec->reference[0])
        json_object_set_new(out, "metrics", metrics_to_json(&spec->metrics));
    return out;
}

json_t *job_error_to_json(const struct job_error *err)
{
    return json_pack("{s:{s:s, s:s}}", "error", "field", err->field, "message",
                     err->message);
}
