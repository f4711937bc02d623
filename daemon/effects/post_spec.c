#define _POSIX_C_SOURCE 200809L
#include "daemon/effects/post_spec.h"

#include <stdio.h>
#include <string.h>

static bool parse_entry(const json_t *entry, const char *path, struct post_effect *out,
                        struct job_error *err)
{
    const char *names[EFFECT_REGISTRY_MAX + 1];
    int count = 0;
    for (; effect_infos[count] && count < EFFECT_REGISTRY_MAX; count++)
        names[count] = effect_infos[count]->name;
    names[count] = NULL;
    char list[160];
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
                             "them holding its options, as {\"%s\": {...}}", list,
                             count ? names[0] : "name");
    const struct effect_info *e = effect_infos[index];
    out->effect = index;
    opt_defaults(&e->options, out->options.bytes);
    if (!opts)
        return true;
    if (!json_is_object(opts))
        return job_error_set(err, path, "the options of %s must be an object, as "
                             "{\"%s\": {...}}", e->name, e->name);
    return opt_parse(&e->options, opts, path, out->options.bytes, err);
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
                             "(/v1/info lists the passes of each effect)", passes,
                             POST_MAX_PASSES);
    return true;
}

json_t *post_spec_to_json(const struct post_spec *p)
{
    json_t *list = json_array();
    for (int i = 0; i < p->count; i++) {
        const struct effect_info *e = effect_infos[p->effects[i].effect];
        json_array_append_new(list, json_pack("{s:o}", e->name,
                                              opt_to_json(&e->options, post_effect_options(p, i))));
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

void post_spec_needs(const struct post_spec *p, struct frame_needs *out)
{
    for (int i = 0; i < p->count; i++) {
        const struct effect_info *e = effect_infos[p->effects[i].effect];
        if (!e->needs)
            continue;
        struct frame_needs n = {0};
        e->needs(post_effect_options(p, i), &n);
        frame_needs_merge(out, &n);
    }
}

int post_spec_drop_antialiasing(struct post_spec *p)
{
    int kept = 0;
    for (int i = 0; i < p->count; i++)
        if (!(effect_infos[p->effects[i].effect]->flags & EFFECT_ANTIALIASING))
            p->effects[kept++] = p->effects[i];
    int dropped = p->count - kept;
    p->count = kept;
    return dropped;
}
