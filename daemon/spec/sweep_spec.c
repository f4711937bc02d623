#define _POSIX_C_SOURCE 200809L
#include "daemon/spec/sweep_spec.h"
#include "common/result_keys.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum param_type { PARAM_INT, PARAM_NUMBER, PARAM_BOOL, PARAM_CHOICE };

/* Every job field a sweep may vary, besides each technique's options
 * ("<technique>.<option>", from the catalogue), the job's aliases of them
 * and each effect's options. */
static const struct {
    const char *path;
    enum param_type type;
    int step; /* integers: valid values are from + k step (sphere segments are even) */
} PARAMS[] = {
    {"technique", PARAM_CHOICE, 0},        {"reference", PARAM_CHOICE, 0},
    {"frames", PARAM_INT, 1},              {"warmup_frames", PARAM_INT, 1},
    {"capture_interval", PARAM_INT, 1},    {"msaa", PARAM_INT, 1},
    {"scene.lights", PARAM_INT, 1},        {"scene.dynamic", PARAM_BOOL, 0},
    {"scene.width", PARAM_INT, 1},         {"scene.height", PARAM_INT, 1},
    {"scene.sphere_segments", PARAM_INT, 2}, {"scene.light_speed", PARAM_NUMBER, 0},
    {"look.lighting", PARAM_CHOICE, 0},    {"look.hdr", PARAM_CHOICE, 0},
    {"look.exposure", PARAM_NUMBER, 0},    {"look.tonemap", PARAM_CHOICE, 0},
    {"scene.preset", PARAM_CHOICE, 0},     {"scene.light_layout", PARAM_CHOICE, 0},
    {"scene.light_radius", PARAM_NUMBER, 0}, {"scene.light_intensity", PARAM_NUMBER, 0},
    {"scene.tessellation_error_px", PARAM_NUMBER, 0}, {"scene.camera", PARAM_CHOICE, 0},
    {"scene.materials", PARAM_CHOICE, 0},  {"scene.specular", PARAM_NUMBER, 0},
    {"scene.shininess", PARAM_NUMBER, 0},  {"scene.metallic", PARAM_NUMBER, 0},
    {"scene.roughness", PARAM_NUMBER, 0},  {"scene.teapot_segments", PARAM_INT, 1},
    {"scene.light_type", PARAM_CHOICE, 0}, {"scene.spot_angle_deg", PARAM_NUMBER, 0},
    {"scene.sun", PARAM_BOOL, 0},
    {"look.ibl.probes", PARAM_INT, 1},     {"look.ibl.resolution", PARAM_INT, 1},
    {"look.ibl.samples", PARAM_INT, 1},    {"look.ibl.blend", PARAM_INT, 1},
    {"look.shadows.atlas", PARAM_INT, 1},  {"look.shadows.tile", PARAM_INT, 1},
    {"look.shadows.bias", PARAM_NUMBER, 0}, {"look.shadows.normal_offset", PARAM_NUMBER, 0},
    {"look.shadows.pcf", PARAM_INT, 1},    {"look.shadows.layout", PARAM_CHOICE, 0},
    {"reference.supersample", PARAM_INT, 1}, {"temporal.frames", PARAM_INT, 1},
};
enum { NPARAMS = sizeof(PARAMS) / sizeof(PARAMS[0]) };

/* "look.post.<effect>.<option>": the option of every <effect> in the
 * base job's look.post (post hook: an effect's breaking point, e.g.
 * look.post.bloom.intensity against the finite criterion). */
#define POST_PARAM "look.post."
static const struct opt_field *post_param(const char *path, char *effect, size_t cap)
{
    if (strncmp(path, POST_PARAM, strlen(POST_PARAM)) != 0)
        return NULL;
    const char *name = path + strlen(POST_PARAM), *dot = strchr(name, '.');
    if (!dot || (size_t)(dot - name) >= cap)
        return NULL;
    snprintf(effect, cap, "%.*s", (int)(dot - name), name);
    int e = effect_find(effect);
    return e >= 0 ? opt_find(&effect_infos[e]->options, dot + 1) : NULL;
}

/* The type of a sweepable path; false when a sweep cannot vary it. */
static bool param_type(const struct technique_catalog *techniques, const char *path,
                       enum param_type *type)
{
    for (int i = 0; i < (int)NPARAMS; i++)
        if (strcmp(PARAMS[i].path, path) == 0) {
            *type = PARAMS[i].type;
            return true;
        }
    char effect[32];
    const char *canonical = job_spec_alias(path);
    const struct opt_field *opt = technique_catalog_option(techniques, canonical ? canonical : path);
    if (!opt)
        opt = post_param(path, effect, sizeof(effect));
    if (!opt)
        return false;
    *type = opt->type == OPT_INT ? PARAM_INT : opt->type == OPT_NUMBER ? PARAM_NUMBER
                                             : PARAM_CHOICE;
    return true;
}

/* The grid an integer parameter's values lie on (sphere segments are even);
 * 1 for technique options, which take any integer in their range. */
static int param_step(const char *path)
{
    for (int i = 0; i < (int)NPARAMS; i++)
        if (strcmp(PARAMS[i].path, path) == 0)
            return PARAMS[i].step > 0 ? PARAMS[i].step : 1;
    return 1;
}

static bool unknown_param(const struct technique_catalog *techniques, struct job_error *err,
                          const char *field)
{
    (void)techniques;
    return job_error_set(err, field, "not a parameter a sweep can vary: scene, look and "
                         "top-level job fields, TECHNIQUE.OPTION or look.post.EFFECT.OPTION; "
                         "GET /v1/info lists them under \"sweepable\"");
}

/* Sets a post effect's option in every entry of that effect in look.post;
 * false when the list has none. */
static bool set_post_option(json_t *job, const char *effect, const char *option, json_t *value)
{
    json_t *list = json_object_get(json_object_get(job, "look"), "post");
    bool any = false;
    for (size_t i = 0; i < json_array_size(list); i++) {
        json_t *entry = json_array_get(list, i), *opts = NULL;
        if (json_is_string(entry) && strcmp(json_string_value(entry), effect) == 0) {
            opts = json_object();
            json_array_set_new(list, i, json_pack("{s:o}", effect, opts));
        } else if (json_is_object(entry)) {
            opts = json_object_get(entry, effect);
        }
        if (json_is_object(opts)) {
            json_object_set(opts, option, value);
            any = true;
        }
    }
    return any;
}

json_t *sweep_params_json(const struct technique_catalog *techniques)
{
    static const char *const types[] = {"integer", "number", "boolean", "choice"};
    json_t *o = json_object();
    for (int i = 0; i < (int)NPARAMS; i++)
        json_object_set_new(o, PARAMS[i].path, json_string(types[PARAMS[i].type]));
    for (int t = 0; t < techniques->count; t++) {
        const struct technique_info *info = techniques->infos[t];
        for (const struct opt_field *opt = info->options.fields; opt && opt->name; opt++) {
            char path[128];
            enum param_type type;
            snprintf(path, sizeof(path), "%s.%s", info->name, opt->name);
            if (param_type(techniques, path, &type))
                json_object_set_new(o, path, json_string(types[type]));
            const char *alias = job_spec_aliased(path);
            if (alias && param_type(techniques, alias, &type))
                json_object_set_new(o, alias, json_string(types[type]));
        }
    }
    /* Post hook: every effect's options, set in each entry of that effect. */
    for (int e = 0; effect_infos[e]; e++)
        for (const struct opt_field *opt = effect_infos[e]->options.fields; opt && opt->name;
             opt++) {
            char path[128];
            enum param_type type;
            snprintf(path, sizeof(path), POST_PARAM "%s.%s", effect_infos[e]->name, opt->name);
            if (param_type(techniques, path, &type))
                json_object_set_new(o, path, json_string(types[type]));
        }
    return o;
}

/* Removes the field at a dotted path, if the job has it. */
static void del_field(json_t *job, const char *path)
{
    const char *dot;
    while (json_is_object(job) && (dot = strchr(path, '.'))) {
        char head[64];
        snprintf(head, sizeof(head), "%.*s", (int)(dot - path), path);
        /* The dotted spelling an option table accepts too. */
        json_object_del(job, path);
        job = json_object_get(job, head);
        path = dot + 1;
    }
    if (json_is_object(job))
        json_object_del(job, path);
}

/* A copy of job with the field at a dotted path set to value, creating the
 * objects between. */
static json_t *with_field(const json_t *job, const char *path, json_t *value)
{
    json_t *copy = json_deep_copy(job);
    char effect[32];
    const struct opt_field *post = post_param(path, effect, sizeof(effect));
    if (post) {
        set_post_option(copy, effect, post->name, value);
        return copy;
    }
    /* A field a job may spell two ways (an alias and its option) is set in
     * the spelling the sweep names and dropped from the other, so that the
     * point does not give it twice. */
    const char *other = job_spec_alias(path);
    if (!other)
        other = job_spec_aliased(path);
    if (other)
        del_field(copy, other);
    /* reference.supersample over the shorthand "reference": "NAME" keeps
     * the name (the object form's technique defaults to the baseline). */
    json_t *ref = json_object_get(copy, "reference");
    if (!strncmp(path, "reference.", 10) && json_is_string(ref))
        json_object_set_new(copy, "reference", json_pack("{s:O}", "technique", ref));
    jf_set_path(copy, path, json_incref(value));
    return copy;
}

/* The technique a sweep scores against and times beside its points when
 * the base names none. */
static const char *baseline(const struct technique_catalog *c)
{
    return c->baseline >= 0 ? c->infos[c->baseline]->name : "";
}

/* Every point measures quality against a reference (the baseline unless the
 * base names one), on at least its last frame. */
static json_t *point_defaults(const struct sweep_spec *s, json_t *job)
{
    if (!json_object_get(job, "reference") || json_is_null(json_object_get(job, "reference")))
        json_object_set_new(job, "reference", json_string(baseline(s->catalog)));
    json_t *ci = json_object_get(job, "capture_interval");
    if (!ci || json_integer_value(ci) == 0) {
        json_t *frames = json_object_get(job, "frames");
        json_object_set_new(job, "capture_interval",
                            json_integer(frames ? json_integer_value(frames) : JOB_DEFAULT_FRAMES));
    }
    if (s->kind == SWEEP_FIND && s->criterion == CRITERION_STABLE && !json_object_get(job, "repeat"))
        json_object_set_new(job, "repeat", json_pack("{s:b, s:i}", "auto", 1, "max", 10));
    return job;
}

/* A post effect's option can only vary where the base job runs the effect. */
static bool post_param_in_base(const json_t *base, const char *path, const char *field,
                               struct job_error *err)
{
    char effect[32];
    if (!post_param(path, effect, sizeof(effect)))
        return true;
    json_t *copy = json_deep_copy(base);
    bool any = set_post_option(copy, effect, "unused", json_null());
    json_decref(copy);
    return any || job_error_set(err, field, "the base job's look.post has no %s to vary", effect);
}

static bool check_point(const json_t *job, const struct technique_catalog *techniques, const char *field,
                        struct job_error *err)
{
    struct job_spec spec;
    struct job_error inner;
    if (job_spec_parse(job, techniques, &spec, &inner))
        return true;
    return job_error_set(err, field, "%s: %s", inner.field, inner.message);
}

/* A base job, or one with a swept value, checked as its points will run:
 * with the baseline as the reference when it names none and captures at
 * its last frame at least (point_defaults), so that fields needing a
 * reference (temporal, metrics) may be given. */
static bool check_as_point(const json_t *job, const struct technique_catalog *techniques,
                           const char *field, struct job_error *err)
{
    json_t *point = json_deep_copy(job);
    if (!json_object_get(point, "reference") || json_is_null(json_object_get(point, "reference")))
        json_object_set_new(point, "reference", json_string(baseline(techniques)));
    json_t *ci = json_object_get(point, "capture_interval"), *nf = json_object_get(point, "frames");
    if (!ci || (json_is_integer(ci) && json_integer_value(ci) == 0))
        json_object_set_new(point, "capture_interval",
                            json_integer(json_is_integer(nf) ? json_integer_value(nf)
                                                        : JOB_DEFAULT_FRAMES));
    bool ok = check_point(point, techniques, field, err);
    json_decref(point);
    return ok;
}

/* Point p of a grid, exactly as it will be submitted; the error names the
 * combination ("vary", point 3: frames=2, capture_interval=5) and the job
 * field and rule it breaks. */
static bool check_combination(const struct sweep_spec *s, size_t p, const struct technique_catalog *techniques,
                              struct job_error *err)
{
    json_t *values, *job = sweep_point_job(s, p, &values);
    struct job_spec spec;
    struct job_error inner;
    bool ok = job_spec_parse(job, techniques, &spec, &inner);
    if (!ok) {
        char combo[160] = "";
        size_t used = 0;
        for (int i = 0; i < s->nparams && used < sizeof(combo); i++) {
            char *v = json_dumps(json_object_get(values, s->params[i]), JSON_ENCODE_ANY | JSON_COMPACT);
            used += (size_t)snprintf(combo + used, sizeof(combo) - used, "%s%s=%.40s",
                                     i ? ", " : "", s->params[i], v ? v : "?");
            free(v);
        }
        job_error_set(err, "vary", "point %zu (%s) is not a valid job: %s: %s", p + 1, combo,
                      inner.field, inner.message);
    }
    json_decref(values);
    json_decref(job);
    return ok;
}

static bool workload_param(const char *path)
{
    /* reference.supersample too: scores against different references are
     * never compared (the verdict's fronts are per workload), so each
     * factor is a workload with its timed reference; msaa too: the
     * reference renders at the job's samples. */
    return strncmp(path, "scene.", 6) == 0 || strcmp(path, "frames") == 0 ||
           strcmp(path, "warmup_frames") == 0 || strcmp(path, "reference.supersample") == 0 ||
           strcmp(path, "msaa") == 0;
}

/* One timed point of the reference technique per workload of the grid (see
 * sweep_point_job), unless the reference is among the sweep's techniques. */
static bool add_reference_points(struct sweep_spec *out, const json_t *body,
                                 struct job_error *err)
{
    out->ngrid = out->npoints;
    json_t *flag = json_object_get(body, "time_reference");
    if (flag && !json_is_boolean(flag))
        return job_error_set(err, "time_reference", "must be true or false");
    if (json_is_false(flag))
        return true;
    json_t *r = json_object_get(out->base, "reference");
    if (json_is_object(r)) /* {"technique", "supersample"}: the technique is what is timed */
        r = json_object_get(r, "technique");
    const char *ref = json_is_string(r) ? json_string_value(r) : baseline(out->catalog);
    json_t *t = json_object_get(out->base, "technique");
    bool varied = false;
    for (int p = 0; p < out->nparams; p++) {
        if (strcmp(out->params[p], "technique") != 0)
            continue;
        varied = true;
        size_t i;
        json_t *v;
        json_array_foreach(out->values[p], i, v) if (json_is_string(v) &&
                                                     !strcmp(json_string_value(v), ref)) return true;
    }
    if (!varied && !strcmp(json_is_string(t) ? json_string_value(t) : baseline(out->catalog), ref))
        return true;
    /* Every combination of the workload parameters' values, first parameter
     * slowest (as in the grid). */
    out->reference_values = json_array();
    size_t combos = 1;
    for (int p = 0; p < out->nparams; p++)
        if (workload_param(out->params[p]))
            combos *= json_array_size(out->values[p]);
    for (size_t c = 0; c < combos; c++) {
        json_t *values = json_pack("{s:s}", "technique", ref);
        size_t rest = c;
        for (int p = out->nparams - 1; p >= 0; p--) {
            if (!workload_param(out->params[p]))
                continue;
            size_t n = json_array_size(out->values[p]);
            json_object_set(values, out->params[p], json_array_get(out->values[p], rest % n));
            rest /= n;
        }
        json_array_append_new(out->reference_values, values);
    }
    out->npoints += combos;
    return true;
}

/* "NAME OP X" with spaces or none around OP, X a plain decimal number
 * (digits with an optional fraction and exponent: no hexadecimal, inf or
 * nan, which strtod alone takes) that a double holds (no underflow to 0 or
 * a denormal) and that lies in [lo, hi]. -1: not of this form; 0: of it,
 * but X is refused (why says by which rule); 1: *x read. */
static int parse_threshold(const char *text, const char *name, const char *op, double lo,
                           double hi, const char *range, double *x, char *why, size_t whylen)
{
    size_t n = strlen(name), m = strlen(op);
    if (strncmp(text, name, n) != 0)
        return -1;
    const char *p = text + n;
    while (*p == ' ')
        p++;
    if (strncmp(p, op, m) != 0)
        return -1;
    p += m;
    while (*p == ' ')
        p++;
    const char *num = p;
    p += *p == '-' || *p == '+';
    size_t digits = strspn(p, "0123456789");
    p += digits;
    if (*p == '.') {
        size_t frac = strspn(p + 1, "0123456789");
        digits += frac;
        p += 1 + frac;
    }
    if (digits && (*p == 'e' || *p == 'E')) {
        const char *e = p + 1 + (p[1] == '-' || p[1] == '+');
        size_t exp = strspn(e, "0123456789");
        p = exp ? e + exp : p;
    }
    if (!digits || *p) {
        snprintf(why, whylen, "\"%s %s X\" needs X a decimal number like 0.95 (digits, an "
                 "optional fraction and exponent: no hexadecimal, inf or nan)", name, op);
        return 0;
    }
    errno = 0;
    char *end;
    double v = strtod(num, &end);
    if (errno == ERANGE || (v != 0 && fabs(v) < DBL_MIN)) {
        snprintf(why, whylen, "\"%s %s X\": %.40s %s", name, op, num,
                 fabs(v) < 1 ? "underflows (closer to 0 than a double holds at full precision)"
                             : "overflows a double");
        return 0;
    }
    if (!(v >= lo && v <= hi)) {
        snprintf(why, whylen, "\"%s %s X\" needs X from %g to %g (%s); %.40s is outside", name,
                 op, lo, hi, range, num);
        return 0;
    }
    *x = v;
    return 1;
}

/* false with why naming the rule broken. */
static bool parse_criterion(const char *text, struct sweep_spec *s, char *why, size_t whylen)
{
    snprintf(s->criterion_text, sizeof(s->criterion_text), "%s", text);
    snprintf(why, whylen, "must be one of \"pdiff_pass\", \"stable\", \"finite\", "
             "\"no_overflow\", \"ssim >= X\", \"ssim_min >= X\", \"flip_max <= X\", "
             "\"flicker_max <= X\"");
    int r;
    double x;
    if (strcmp(text, "pdiff_pass") == 0)
        s->criterion = CRITERION_PDIFF_PASS;
    else if (strcmp(text, "stable") == 0)
        s->criterion = CRITERION_STABLE;
    else if (strcmp(text, "finite") == 0)
        s->criterion = CRITERION_FINITE;
    else if (strcmp(text, "no_overflow") == 0)
        s->criterion = CRITERION_NO_OVERFLOW;
    else if ((r = parse_threshold(text, "ssim_min", ">=", -1, 1, "SSIM's range", &x, why,
                                  whylen)) >= 0) {
        if (r == 0)
            return false;
        s->criterion = CRITERION_SSIM_MIN, s->threshold = x;
    } else if ((r = parse_threshold(text, "ssim", ">=", -1, 1, "SSIM's range", &x, why,
                                    whylen)) >= 0) {
        /* The mean SSIM over the frame (the thesis's figure), of the worst
         * capture; "ssim_min" is its smallest local window. */
        if (r == 0)
            return false;
        s->criterion = CRITERION_SSIM_MEAN, s->threshold = x;
    } else if ((r = parse_threshold(text, "flip_max", "<=", 0, 1, "FLIP's range", &x, why,
                                    whylen)) >= 0) {
        if (r == 0)
            return false;
        s->criterion = CRITERION_FLIP_MAX, s->threshold = x;
    } else if ((r = parse_threshold(text, "flicker_max", "<=", 0, 1, "flicker's range", &x,
                                    why, whylen)) >= 0) {
        if (r == 0)
            return false;
        s->criterion = CRITERION_FLICKER_MAX, s->threshold = x;
    } else {
        return false;
    }
    return true;
}

bool sweep_thesis_size(const json_t *body, struct thesis_size *out, struct job_error *err)
{
    /* Powers of two, so that OSL's tiles stay a power of two (from 32). */
    static const double scales[] = {1, 0.5, 0.25, 0.125};
    double scale = 1;
    json_t *v = json_object_get(body, "scale");
    if (v) {
        scale = json_is_number(v) ? json_number_value(v) : 0;
        size_t i = 0;
        while (i < sizeof(scales) / sizeof(scales[0]) && scale != scales[i])
            i++;
        if (i == sizeof(scales) / sizeof(scales[0]))
            return job_error_set(err, "scale", "must be 1, 0.5, 0.25 or 0.125 (the thesis's "
                                 "1080x720 frame and OSL's 256-texel tiles shrink alike)");
    }
    out->scale = scale;
    out->width = (int)(1080 * scale);
    out->height = (int)(720 * scale);
    out->osl_resolution = (int)(256 * scale);
    return true;
}

/* The thesis's experiment (chapter 3.3): forward and OSL (256 texels an
 * object, whole tiles: the thesis's OSL, pinned since the defaults moved on;
 * async distance 20) with still and moving lights on the grid at
 * 1080x720, repeated, captures judged with SSIM and PerceptualDiff at 22.6
 * degrees. frames, warmup_frames and repeat may be lowered to fit a slow
 * machine, and scale shrinks the frame and OSL's tiles alike (the same
 * texels per pixel as the thesis's). */
static json_t *thesis_sweep(const json_t *body, struct job_error *err)
{
    static const char *const keys[] = {"preset", "frames", "warmup_frames", "repeat", "scale",
                                       NULL};
    int n = 300, warmup = 10, repeat = 5;
    struct thesis_size size;
    if (!jf_check_keys(body, "", keys, err) ||
        !jf_get_int(body, "frames", "frames", 1, 100000, &n, err) ||
        !jf_get_int(body, "warmup_frames", "warmup_frames", 0, 10000, &warmup, err) ||
        !jf_get_int(body, "repeat", "repeat", 1, 1000, &repeat, err) ||
        !sweep_thesis_size(body, &size, err))
        return NULL;
    json_t *base = json_pack(
        "{s:s, s:i, s:i, s:i, s:{s:i, s:f, s:s}, s:i, s:s, s:{s:b, s:{s:f}, s:b, s:b},"
        " s:{s:s, s:i, s:b, s:i, s:i}}",
        "technique", "forward", "frames", n, "warmup_frames", warmup, "capture_interval",
        n >= 3 ? n / 3 : n, "osl", "resolution", size.osl_resolution, "async_distance", 20.0,
        "visibility", "all", "repeat", repeat,
        "reference", "forward", "metrics",
        "ssim", 1, "pdiff", "fov", 22.6, "psnr", 0, "flip", 0, "scene", "preset", "grid", "lights",
        10, "dynamic", 0, "width", size.width, "height", size.height);
    return json_pack("{s:o, s:{s:[b, b], s:[s, s]}}", "base", base, "vary", "scene.dynamic", 0, 1,
                     "technique", "forward", "osl");
}

static bool parse_into(const json_t *body, const struct technique_catalog *techniques,
                       struct sweep_spec *out, struct job_error *err)
{
    memset(out, 0, sizeof(*out));
    memset(err, 0, sizeof(*err));
    out->catalog = techniques;
    if (!json_is_object(body))
        return job_error_set(err, "body", "the sweep must be a JSON object");
    json_t *preset = json_object_get(body, "preset");
    if (preset) {
        if (!json_is_string(preset) || strcmp(json_string_value(preset), "thesis") != 0)
            return job_error_set(err, "preset", "must be \"thesis\"");
        json_t *expanded = thesis_sweep(body, err);
        if (!expanded)
            return false;
        bool ok = sweep_spec_parse(expanded, techniques, out, err);
        json_decref(expanded);
        out->thesis = ok;
        return ok;
    }
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)body, key, v) if (strcmp(key, "base") && strcmp(key, "vary") &&
                                                  strcmp(key, "find") &&
                                                  strcmp(key, "time_reference"))
        return job_error_set(err, key, "unknown field (a sweep has base and vary, or base and "
                             "find, and time_reference)");
    json_t *base = json_object_get(body, "base");
    if (!json_is_object(base))
        return job_error_set(err, "base", "must be a job object");
    if (!check_as_point(base, techniques, "base", err))
        return false;
    json_t *vary = json_object_get(body, "vary"), *find = json_object_get(body, "find");
    if (!!vary == !!find)
        return job_error_set(err, vary ? "find" : "vary", "give exactly one of vary and find");
    out->base = json_incref(base);

    if (vary) {
        out->kind = SWEEP_VARY;
        if (!json_is_object(vary) || json_object_size(vary) < 1 || json_object_size(vary) > SWEEP_MAX_PARAMS)
            return job_error_set(err, "vary", "must be an object of one or two parameters, each with a list of values");
        out->npoints = 1;
        json_object_foreach(vary, key, v) {
            char field[96];
            snprintf(field, sizeof(field), "vary.%.*s", (int)jf_utf8_prefix(key, 40), key);
            enum param_type unused;
            if (!param_type(techniques, key, &unused))
                return unknown_param(techniques, err, field);
            if (!post_param_in_base(base, key, field, err))
                return false;
            if (!json_is_array(v) || json_array_size(v) == 0)
                return job_error_set(err, field, "must be a non-empty list of values");
            snprintf(out->params[out->nparams], sizeof(out->params[0]), "%s", key);
            out->values[out->nparams++] = json_incref(v);
            out->npoints *= json_array_size(v);
            if (out->npoints > SWEEP_MAX_POINTS)
                return job_error_set(err, "vary", "makes more than %d points", SWEEP_MAX_POINTS);
            size_t i;
            json_t *value;
            json_array_foreach(v, i, value) {
                snprintf(field, sizeof(field), "vary.%.*s[%zu]", (int)jf_utf8_prefix(key, 40),
                         key, i);
                json_t *job = with_field(base, key, value);
                bool ok = check_as_point(job, techniques, field, err);
                json_decref(job);
                if (!ok)
                    return false;
            }
        }
        /* Each value may be fine alone and a combination still refused
         * (frames 2 with capture_interval 5): every point is parsed as the
         * job it will run, so that no sweep fails after earlier points ran;
         * the timed reference points too. */
        out->ngrid = out->npoints;
        for (size_t p = 0; p < out->npoints; p++)
            if (!check_combination(out, p, techniques, err))
                return false;
        size_t grid = out->npoints;
        if (!add_reference_points(out, body, err))
            return false;
        for (size_t p = grid; p < out->npoints; p++)
            if (!check_combination(out, p, techniques, err))
                return false;
        return true;
    }

    out->kind = SWEEP_FIND;
    if (!json_is_object(find))
        return job_error_set(err, "find", "must be an object: param, from, to, while");
    json_object_foreach(find, key, v) if (strcmp(key, "param") && strcmp(key, "from") &&
                                          strcmp(key, "to") && strcmp(key, "while") &&
                                          strcmp(key, "steps")) {
        char field[64];
        snprintf(field, sizeof(field), "find.%.*s", (int)jf_utf8_prefix(key, 40), key);
        return job_error_set(err, field, "unknown field (param, from, to, while, steps)");
    }
    const char *param = json_string_value(json_object_get(find, "param"));
    enum param_type type;
    if (!param)
        return job_error_set(err, "find.param", "must name a parameter");
    if (!param_type(techniques, param, &type))
        return unknown_param(techniques, err, "find.param");
    if (!post_param_in_base(base, param, "find.param", err))
        return false;
    if (type != PARAM_INT && type != PARAM_NUMBER)
        return job_error_set(err, "find.param", "%s is not numeric: find bisects a numeric parameter", param);
    snprintf(out->params[0], sizeof(out->params[0]), "%s", param);
    out->nparams = 1;
    out->integer = type == PARAM_INT;
    out->step = type == PARAM_INT ? param_step(param) : 0;
    json_t *from = json_object_get(find, "from"), *to = json_object_get(find, "to");
    if (!json_is_number(from))
        return job_error_set(err, "find.from", "must be a number");
    if (!json_is_number(to) || json_number_value(to) <= json_number_value(from))
        return job_error_set(err, "find.to", "must be a number above find.from");
    out->from = json_number_value(from);
    out->to = json_number_value(to);
    if (out->integer && (out->from != floor(out->from) || out->to != floor(out->to)))
        return job_error_set(err, out->from != floor(out->from) ? "find.from" : "find.to",
                    "must be an integer: %s is an integer parameter", param);
    const char *crit = json_string_value(json_object_get(find, "while"));
    char why[200];
    if (!parse_criterion(crit ? crit : "", out, why, sizeof(why)))
        return job_error_set(err, "find.while", "%s", why);
    /* Flicker is measured over frames in a row at each capture, which the
     * base job asks for. */
    if (out->criterion == CRITERION_FLICKER_MAX && !json_object_get(base, "temporal"))
        return job_error_set(err, "find.while", "\"flicker_max <= X\" needs base.temporal "
                             "({\"frames\": K}, K from %d to %d): flicker is measured over K "
                             "frames in a row at each capture", JOB_MIN_TEMPORAL_FRAMES,
                             JOB_MAX_TEMPORAL_FRAMES);
    if (out->criterion == CRITERION_NO_OVERFLOW) {
        char list[200];
        technique_catalog_list(techniques, TECHNIQUE_BOUNDED_LIGHT_LISTS, list, sizeof(list));
        snprintf(out->unjudged_text, sizeof(out->unjudged_text),
                 "\"no_overflow\" needs bounded light lists (%s) or look.shadows, and the job "
                 "has neither", list[0] ? list : "no technique has them");
    }
    out->max_probes = 10;
    json_t *steps = json_object_get(find, "steps");
    if (steps) {
        if (!json_is_integer(steps) || json_integer_value(steps) < 2 || json_integer_value(steps) > 64)
            return job_error_set(err, "find.steps", "must be an integer from 2 to 64 (probes at most)");
        out->max_probes = (int)json_integer_value(steps);
    }
    out->npoints = (size_t)out->max_probes;
    for (int end = 0; end < 2; end++) {
        json_t *job = sweep_probe_job(out, end ? out->to : out->from);
        bool ok = check_point(job, techniques, end ? "find.to" : "find.from", err);
        json_decref(job);
        if (!ok)
            return false;
    }
    return true;
}

bool sweep_spec_parse(const json_t *body, const struct technique_catalog *techniques, struct sweep_spec *out,
                      struct job_error *err)
{
    /* A refusal may come after base and values were taken: release them, so
     * that a refused sweep holds nothing (finishing it again is harmless). */
    if (parse_into(body, techniques, out, err))
        return true;
    sweep_spec_finish(out);
    return false;
}

void sweep_spec_finish(struct sweep_spec *s)
{
    if (!s)
        return;
    json_decref(s->base);
    json_decref(s->reference_values);
    for (int i = 0; i < 2; i++)
        json_decref(s->values[i]);
    memset(s, 0, sizeof(*s));
}

json_t *sweep_point_job(const struct sweep_spec *s, size_t index, json_t **values)
{
    if (s->kind == SWEEP_VARY && index >= s->ngrid) {
        /* A timed reference point: timed like the others, nothing to judge. */
        json_t *v = json_array_get(s->reference_values, index - s->ngrid);
        *values = json_deep_copy(v);
        json_t *job = json_deep_copy(s->base);
        const char *key;
        json_t *value;
        json_object_foreach(v, key, value) {
            json_t *next = with_field(job, key, value);
            json_decref(job);
            job = next;
        }
        json_object_del(job, "reference");
        json_object_del(job, "metrics");
        json_object_del(job, "temporal"); /* flicker is against a reference, too */
        json_object_set_new(job, "capture_interval", json_integer(0));
        return job;
    }
    json_t *job = json_deep_copy(s->base);
    json_t *chosen[SWEEP_MAX_PARAMS];
    /* Row-major: the last parameter varies fastest. */
    for (int p = s->nparams - 1; p >= 0; p--) {
        size_t n = json_array_size(s->values[p]);
        chosen[p] = json_array_get(s->values[p], index % n);
        index /= n;
        json_t *next = with_field(job, s->params[p], chosen[p]);
        json_decref(job);
        job = next;
    }
    /* values keep the order of vary: the first is the charts' axis. */
    *values = json_object();
    for (int p = 0; p < s->nparams; p++)
        json_object_set(*values, s->params[p], chosen[p]);
    return point_defaults(s, job);
}

json_t *sweep_probe_job(const struct sweep_spec *s, double v)
{
    /* Bisection halves the range; on a field with a step (sphere segments
     * are even) a probe goes down to the step's grid, so that it is valid
     * whenever both ends are. */
    if (s->integer && s->step > 1)
        v = s->from + floor((llround(v) - s->from) / s->step) * s->step;
    json_t *value = s->integer ? json_integer((json_int_t)llround(v)) : json_real(v);
    json_t *job = with_field(s->base, s->params[0], value);
    json_decref(value);
    return point_defaults(s, job);
}

bool sweep_criterion_holds(const struct sweep_spec *s, const json_t *result)
{
    json_t *q = json_object_get(result, RK_QUALITY);
    switch (s->criterion) {
    case CRITERION_PDIFF_PASS:
        return q && json_integer_value(json_object_get(q, RK_PDIFF_FAILED_CAPTURES)) == 0;
    case CRITERION_SSIM_MIN: {
        json_t *w = json_object_get(json_object_get(q, RK_WORST_SSIM_MIN), "value");
        return w && json_number_value(w) >= s->threshold;
    }
    case CRITERION_FLIP_MAX: {
        json_t *w = json_object_get(json_object_get(q, RK_WORST_FLIP), "max");
        return w && json_number_value(w) <= s->threshold;
    }
    case CRITERION_SSIM_MEAN: {
        json_t *w = json_object_get(json_object_get(q, RK_WORST_SSIM), "value");
        return w && json_number_value(w) >= s->threshold;
    }
    case CRITERION_FLICKER_MAX: {
        json_t *w = json_object_get(json_object_get(q, RK_WORST_FLICKER), "value");
        return w && json_number_value(w) <= s->threshold;
    }
    case CRITERION_STABLE:
        return json_is_true(json_object_get(json_object_get(result, RK_REPEAT), RK_STABLE));
    case CRITERION_FINITE:
        return json_is_true(json_object_get(json_object_get(result, RK_NONFINITE), RK_FINITE));
    case CRITERION_NO_OVERFLOW: {
        json_int_t lists, shadows;
        sweep_overflow_frames(result, &lists, &shadows);
        return lists <= 0 && shadows <= 0;
    }
    }
    return false;
}

const char *sweep_criterion_unjudged(const struct sweep_spec *s, const json_t *result)
{
    if (s->criterion != CRITERION_NO_OVERFLOW)
        return NULL;
    json_int_t lists, shadows;
    sweep_overflow_frames(result, &lists, &shadows);
    return lists < 0 && shadows < 0 ? s->unjudged_text : NULL;
}

void sweep_overflow_frames(const json_t *result, json_int_t *light_lists, json_int_t *shadows)
{
    const char *tech = json_string_value(json_object_get(result, RK_TECHNIQUE));
    json_t *own = tech ? json_object_get(result, tech) : NULL;
    json_t *f = json_object_get(json_object_get(own, RK_OVERFLOW), RK_OVERFLOW_FRAMES);
    *light_lists = json_is_integer(f) ? json_integer_value(f) : -1;
    f = json_object_get(json_object_get(json_object_get(result, RK_SHADOWS), RK_OVERFLOW),
                        RK_FRAMES_WITH_DROPS);
    *shadows = json_is_integer(f) ? json_integer_value(f) : -1;
}

void sweep_bisect(double from, double to, bool integer, int max_probes,
                  int (*holds)(double v, void *ctx), void *ctx, struct bisect_result *out)
{
    memset(out, 0, sizeof(*out));
    int h = holds(from, ctx);
    out->probes = 1;
    if (h < 0) {
        out->outcome = BISECT_ABORTED;
        return;
    }
    if (h == 0) {
        out->outcome = BISECT_FAILS_EVERYWHERE;
        out->first_failing = from;
        return;
    }
    h = holds(to, ctx);
    out->probes = 2;
    if (h < 0) {
        out->outcome = BISECT_ABORTED;
        out->value = from;
        return;
    }
    if (h == 1) {
        out->outcome = BISECT_HOLDS_EVERYWHERE;
        out->value = to;
        return;
    }
    double lo = from, hi = to, resolution = integer ? 1.0 : (to - from) / 1000.0;
    while (hi - lo > resolution && out->probes < max_probes) {
        double mid = integer ? floor((lo + hi) / 2.0) : (lo + hi) / 2.0;
        if (mid <= lo || mid >= hi)
            break;
        h = holds(mid, ctx);
        out->probes++;
        if (h < 0) {
            out->outcome = BISECT_ABORTED;
            out->value = lo;
            out->first_failing = hi;
            return;
        }
        if (h)
            lo = mid;
        else
            hi = mid;
    }
    out->outcome = BISECT_BOUNDARY;
    out->value = lo;
    out->first_failing = hi;
}
