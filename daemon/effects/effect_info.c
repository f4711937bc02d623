#define _POSIX_C_SOURCE 200809L
#include "daemon/effects/effect_info.h"

#include <stdio.h>
#include <string.h>

/* ---- bloom ------------------------------------------------------------ */

static const char *const bloom_kernels[] = {"separable", "2d", NULL};
static const char *const bloom_passes[] = {"bright", "down", "blur_h", "blur_v", "blur",
                                           "up",     "composite", NULL};

static const struct technique_option bloom_options_table[] = {
    {.name = "threshold", .type = TOPT_NUMBER, .def = 1.0, .min = 0.0, .max = 1e6,
     .summary = "luminance above which light blooms (1 = what the resolve clips)",
     .offset = offsetof(struct bloom_options, threshold)},
    {.name = "kernel", .type = TOPT_CHOICE, .def = BLOOM_SEPARABLE, .choices = bloom_kernels,
     .summary = "separable: a horizontal then a vertical pass of 2r+1 taps; 2d: one pass of "
                "(2r+1)^2 taps (seed 001's slow version)",
     .offset = offsetof(struct bloom_options, kernel)},
    {.name = "radius", .type = TOPT_INT, .def = 4, .min = 2, .max = 32,
     .summary = "Gaussian taps each side of the centre (sigma = radius / 2)",
     .offset = offsetof(struct bloom_options, radius)},
    {.name = "intensity", .type = TOPT_NUMBER, .def = 1.0, .min = 0.0, .max = 1e30,
     .summary = "scale of the blurred light added back; huge values overflow a 16-bit "
                "target (look.hdr rgba16f), and chained, even a 32-bit one, on purpose: "
                "the result counts the non-finite pixels",
     .offset = offsetof(struct bloom_options, intensity)},
    {.name = "downsample", .type = TOPT_INT, .def = 0, .min = 0, .max = 5,
     .summary = "0 blurs at full size; n blurs a mip chain of n halvings and adds the levels "
                "back up (wider glow for the same taps)",
     .offset = offsetof(struct bloom_options, downsample)},
    {0},
};

static int bloom_active_passes(const void *opts, const char **out)
{
    const struct bloom_options *o = opts;
    int n = 0;
    out[n++] = "bright";
    if (o->downsample > 1)
        out[n++] = "down";
    if (o->kernel == BLOOM_2D) {
        out[n++] = "blur";
    } else {
        out[n++] = "blur_h";
        out[n++] = "blur_v";
    }
    if (o->downsample > 1)
        out[n++] = "up";
    out[n++] = "composite";
    return n;
}

const struct effect_info bloom_info = {
    .name = "bloom",
    .summary = "bright pass with a threshold, Gaussian blur (separable or 2d, optionally over "
               "a mip chain), added back to the colour",
    .passes = bloom_passes,
    .options = bloom_options_table,
    .options_size = sizeof(struct bloom_options),
    .active_passes = bloom_active_passes,
};

/* ---- toon ------------------------------------------------------------- */

static const char *const toon_edge_choices[] = {"sobel", "depth_diff", "none", NULL};
static const char *const toon_passes[] = {"shade", NULL};

static const struct technique_option toon_options_table[] = {
    {.name = "levels", .type = TOPT_INT, .def = 4, .min = 2, .max = 32,
     .summary = "steps of the luminance ramp",
     .offset = offsetof(struct toon_options, levels)},
    {.name = "edges", .type = TOPT_CHOICE, .def = TOON_EDGES_SOBEL, .choices = toon_edge_choices,
     .summary = "sobel: Sobel operator on view depth and normals (seed 001); depth_diff: the "
                "largest depth difference to 4 neighbours (seed 003); none: ramp only",
     .offset = offsetof(struct toon_options, edges)},
    {.name = "threshold", .type = TOPT_NUMBER, .def = 0.1, .min = 0.001, .max = 100.0,
     .summary = "relative view-depth difference (|dz| / z) that makes an outline",
     .offset = offsetof(struct toon_options, threshold)},
    {.name = "normal_threshold", .type = TOPT_NUMBER, .def = 1.0, .min = 0.01, .max = 16.0,
     .summary = "sobel: gradient of the view normals that makes an outline",
     .offset = offsetof(struct toon_options, normal_threshold)},
    {.name = "thickness", .type = TOPT_INT, .def = 1, .min = 1, .max = 8,
     .summary = "pixels between the centre and the samples the edge test compares",
     .offset = offsetof(struct toon_options, thickness)},
    {0},
};

static int toon_active_passes(const void *opts, const char **out)
{
    (void)opts;
    out[0] = "shade";
    return 1;
}

const struct effect_info toon_info = {
    .name = "toon",
    .summary = "colour ramp of a few levels plus outlines from depth (and normals) edges",
    .passes = toon_passes,
    .options = toon_options_table,
    .options_size = sizeof(struct toon_options),
    .active_passes = toon_active_passes,
};

/* ---- ssao ------------------------------------------------------------- */

static const char *const ssao_passes[] = {"ao", "blur", "apply", NULL};

static const struct technique_option ssao_options_table[] = {
    {.name = "samples", .type = TOPT_INT, .def = 16, .min = 4, .max = 64,
     .summary = "hemisphere samples per pixel (a fixed kernel: frame k is a function of k)",
     .offset = offsetof(struct ssao_options, samples)},
    {.name = "radius", .type = TOPT_NUMBER, .def = 1.0, .min = 0.01, .max = 100.0,
     .summary = "hemisphere radius in world units",
     .offset = offsetof(struct ssao_options, radius)},
    {.name = "bias", .type = TOPT_NUMBER, .def = 0.025, .min = 0.0, .max = 10.0,
     .summary = "depth bias against self-occlusion, world units",
     .offset = offsetof(struct ssao_options, bias)},
    {.name = "blur", .type = TOPT_BOOL, .def = 1,
     .summary = "blur the occlusion over the 4x4 noise tile before applying it (seed 002)",
     .offset = offsetof(struct ssao_options, blur)},
    {.name = "intensity", .type = TOPT_NUMBER, .def = 1.0, .min = 0.0, .max = 8.0,
     .summary = "exponent on the occlusion term: 0 leaves the image, 1 as computed",
     .offset = offsetof(struct ssao_options, intensity)},
    {0},
};

static int ssao_active_passes(const void *opts, const char **out)
{
    const struct ssao_options *o = opts;
    out[0] = "ao";
    out[1] = o->blur ? "blur" : "apply";
    return 2;
}

const struct effect_info ssao_info = {
    .name = "ssao",
    .summary = "screen-space ambient occlusion: hemisphere samples against the depth "
               "texture, normals from the technique's g-buffer or rebuilt from depth",
    .passes = ssao_passes,
    .options = ssao_options_table,
    .options_size = sizeof(struct ssao_options),
    .active_passes = ssao_active_passes,
};

/* ---- the registry and the chain --------------------------------------- */

const struct effect_info *const effect_infos[] = {&bloom_info, &toon_info, &ssao_info, NULL};

int effect_find(const char *name)
{
    for (int i = 0; effect_infos[i]; i++)
        if (strcmp(effect_infos[i]->name, name) == 0)
            return i;
    return -1;
}

/* The generic technique option parser reads an effect's table through a
 * technique_info named after the entry's path, so that its errors read
 * "look.post[1].radius". */
static struct technique_info shim(const struct effect_info *e, const char *path)
{
    return (struct technique_info){.name = path,
                                   .summary = e->summary,
                                   .passes = e->passes,
                                   .options = e->options,
                                   .options_size = e->options_size};
}

static bool parse_entry(const json_t *entry, const char *path, struct post_effect *out,
                        struct job_error *err)
{
    const char *names[EFFECT_REGISTRY_MAX + 1];
    int count = 0;
    for (; effect_infos[count] && count < EFFECT_REGISTRY_MAX; count++)
        names[count] = effect_infos[count]->name;
    names[count] = NULL;
    char list[120];
    jf_list_choices(names, list, sizeof(list));
    const char *name = NULL;
    const json_t *opts = NULL;
    if (json_is_string(entry)) {
        name = json_string_value(entry);
    } else if (json_is_object(entry) && json_object_size(entry) == 1) {
        char prefix[80];
        snprintf(prefix, sizeof(prefix), "%s.", path);
        if (!jf_check_keys(entry, prefix, names, err))
            return false;
        name = json_object_iter_key(json_object_iter((json_t *)entry));
        opts = json_object_iter_value(json_object_iter((json_t *)entry));
    }
    int index = name ? effect_find(name) : -1;
    if (index < 0)
        return job_error_set(err, path, "must be an effect name (%s) or an object with one of "
                             "them holding its options, as {\"bloom\": {\"radius\": 8}}", list);
    const struct effect_info *e = effect_infos[index];
    out->effect = index;
    struct technique_info t = shim(e, path);
    technique_options_defaults(&t, &out->options);
    if (!opts)
        return true;
    if (!json_is_object(opts))
        return job_error_set(err, path, "the options of %s must be an object, as "
                             "{\"%s\": {...}}", e->name, e->name);
    if (!technique_options_parse(&t, opts, &out->options, err))
        return false;
    if (e->check && !e->check(out->options.bytes, err)) {
        char rel[sizeof(err->field)];
        snprintf(rel, sizeof(rel), "%s", err->field);
        snprintf(err->field, sizeof(err->field), "%.40s.%.20s", path, rel);
        return false;
    }
    return true;
}

bool post_spec_parse(const json_t *list, const char *field, struct post_spec *out,
                     struct job_error *err)
{
    memset(out, 0, sizeof(*out));
    if (!json_is_array(list))
        return job_error_set(err, field, "must be a list of effects, each a name or "
                             "{\"name\": {options}}, run in order");
    if (json_array_size(list) > POST_MAX_EFFECTS)
        return job_error_set(err, field, "chains at most %d effects", POST_MAX_EFFECTS);
    for (size_t i = 0; i < json_array_size(list); i++) {
        char path[48];
        snprintf(path, sizeof(path), "%.30s[%d]", field, (int)i % 100);
        if (!parse_entry(json_array_get(list, i), path, &out->effects[i], err))
            return false;
        out->count++;
    }
    int passes = post_spec_pass_names(out, NULL, 0);
    if (passes > POST_MAX_PASSES)
        return job_error_set(err, field, "needs %d timed passes; a chain may run at most %d "
                             "(bloom takes 3 to 6, toon 1, ssao 2)", passes, POST_MAX_PASSES);
    return true;
}

json_t *post_spec_to_json(const struct post_spec *p)
{
    json_t *list = json_array();
    for (int i = 0; i < p->count; i++) {
        const struct effect_info *e = effect_infos[p->effects[i].effect];
        struct technique_info t = shim(e, e->name);
        json_array_append_new(list, json_pack("{s:o}", e->name,
                                              technique_options_to_json(&t, &p->effects[i].options)));
    }
    return list;
}

void post_effect_label(const struct post_spec *p, int i, char *buf, size_t cap)
{
    int same = 0;
    for (int k = 0; k <= i; k++)
        same += p->effects[k].effect == p->effects[i].effect;
    const char *name = effect_infos[p->effects[i].effect]->name;
    if (same > 1)
        snprintf(buf, cap, "%s%d", name, same);
    else
        snprintf(buf, cap, "%s", name);
}

int post_spec_pass_names(const struct post_spec *p, char (*names)[POST_PASS_NAME_BYTES], int cap)
{
    int n = 0;
    for (int i = 0; i < p->count; i++) {
        const struct effect_info *e = effect_infos[p->effects[i].effect];
        const char *passes[EFFECT_MAX_PASSES];
        int np = e->active_passes(post_effect_options(p, i), passes);
        char label[24];
        post_effect_label(p, i, label, sizeof(label));
        for (int k = 0; k < np; k++, n++)
            if (n < cap)
                snprintf(names[n], POST_PASS_NAME_BYTES, "%s.%s", label, passes[k]);
    }
    return n;
}

json_t *effect_catalog_json(void)
{
    /* Described by the techniques' own code: same shape as /v1/info's
     * "techniques", so clients read both alike. */
    struct technique_info shims[EFFECT_REGISTRY_MAX];
    struct technique_catalog c = {.count = 0};
    for (int i = 0; effect_infos[i] && i < EFFECT_REGISTRY_MAX; i++) {
        shims[i] = shim(effect_infos[i], effect_infos[i]->name);
        c.infos[c.count++] = &shims[i];
    }
    return technique_catalog_json(&c);
}
