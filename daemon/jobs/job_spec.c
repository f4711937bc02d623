#define _POSIX_C_SOURCE 200809L
#include "daemon/jobs/job_spec.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>


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

static double default_timeout_s;

void job_spec_set_default_timeout(double seconds) { default_timeout_s = seconds; }
double job_spec_default_timeout(void) { return default_timeout_s; }

void job_spec_defaults(struct job_spec *out)
{
    memset(out, 0, sizeof(*out));
    snprintf(out->technique, sizeof(out->technique), "forward");
    out->frames = 300;
    out->warmup_frames = 10;
    out->capture_interval = 0;
    out->async_distance = 0.0;
    scene_spec_defaults(&out->scene);
    out->osl.resolution = 256;
    out->osl.texel_density = 1.0;
    out->osl.reshade = OSL_RESHADE_TOUCHED;
    out->repeat = 1;
    out->repeat_auto = false;
    out->reference[0] = '\0';
    metrics_options_defaults(&out->metrics);
    out->timeout_s = default_timeout_s;
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

static bool parse_osl(const json_t *osl, struct osl_spec *o, struct job_error *err)
{
    static const char *const keys[] = {"resolution", "texel_density", "reshade", NULL};
    if (!jf_check_keys(osl, "osl.", keys, err))
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
    if (!jf_get_number(osl, "texel_density", "osl.texel_density", 0.0625, 16.0,
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
                                       "timeout_s", NULL};
    job_spec_defaults(out);
    memset(err, 0, sizeof(*err));
    if (!json_is_object(body))
        return job_error_set(err, "body", "the job must be a JSON object");
    if (!jf_check_keys(body, "", keys, err))
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
    if (!jf_get_int(body, "frames", "frames", 1, 1000000, &out->frames, err) ||
        !jf_get_int(body, "warmup_frames", "warmup_frames", 0, 10000,
                 &out->warmup_frames, err) ||
        !jf_get_int(body, "capture_interval", "capture_interval", 0, 1000000,
                 &out->capture_interval, err) ||
        !jf_get_number(body, "async_distance", "async_distance", 0.0, 1e6,
                    &out->async_distance, err) ||
        !jf_get_number(body, "timeout_s", "timeout_s", 0.0, 1e7, &out->timeout_s, err))
        return false;

    json_t *scene, *osl;
    if (!jf_get_object(body, "scene", "scene", &scene, err) ||
        (scene && !scene_spec_parse(scene, &out->scene, err)) ||
        !jf_get_object(body, "osl", "osl", &osl, err) ||
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
        "{s:s, s:i, s:i, s:i, s:f, s:o, s:{s:o, s:f, s:s}}",
        "technique", spec->technique, "frames", spec->frames, "warmup_frames",
        spec->warmup_frames, "capture_interval", spec->capture_interval,
        "async_distance", spec->async_distance, "scene", scene_spec_to_json(&spec->scene),
        "osl", "resolution", res, "texel_density", spec->osl.texel_density,
        "reshade", spec->osl.reshade == OSL_RESHADE_ALL ? "all" : "touched");
    json_object_set_new(out, "repeat",
                        spec->repeat_auto ? json_pack("{s:b, s:i}", "auto", 1, "max", spec->repeat)
                                          : json_integer(spec->repeat));
    json_object_set_new(out, "reference",
                        spec->reference[0] ? json_string(spec->reference) : json_null());
    json_object_set_new(out, "timeout_s", json_real(spec->timeout_s));
    if (spec->reference[0])
        json_object_set_new(out, "metrics", metrics_to_json(&spec->metrics));
    return out;
}

