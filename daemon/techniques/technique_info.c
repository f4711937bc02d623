#define _POSIX_C_SOURCE 200809L
#include "daemon/techniques/technique_info.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define MAX_KEYS 48

bool technique_catalog_add(struct technique_catalog *c, const struct technique_info *info)
{
    if (c->count >= TECHNIQUE_MAX || info->options_size > TECHNIQUE_OPTIONS_BYTES ||
        technique_catalog_find(c, info->name) >= 0)
        return false;
    c->infos[c->count++] = info;
    return true;
}

int technique_catalog_find(const struct technique_catalog *c, const char *name)
{
    for (int i = 0; i < c->count; i++)
        if (strcmp(c->infos[i]->name, name) == 0)
            return i;
    return -1;
}

void technique_catalog_list(const struct technique_catalog *c, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < c->count && used < cap; i++)
        used += (size_t)snprintf(buf + used, cap - used, "%s\"%s\"", i ? ", " : "",
                                 c->infos[i]->name);
}

static void *field_at(struct technique_options *o, const struct technique_option *opt)
{
    return o->bytes + opt->offset;
}

static const void *cfield_at(const struct technique_options *o, const struct technique_option *opt)
{
    return o->bytes + opt->offset;
}

void technique_options_defaults(const struct technique_info *t, struct technique_options *o)
{
    memset(o, 0, sizeof(*o));
    for (const struct technique_option *opt = t->options; opt && opt->name; opt++) {
        void *p = field_at(o, opt);
        switch (opt->type) {
        case TOPT_INT:
        case TOPT_CHOICE:
        case TOPT_POW2_OR_AUTO:
            *(int *)p = (int)opt->def;
            break;
        case TOPT_NUMBER:
            *(double *)p = opt->def;
            break;
        case TOPT_BOOL:
            *(bool *)p = opt->def != 0;
            break;
        case TOPT_INT_LIST:
            memcpy(p, opt->def_list, (size_t)opt->count * sizeof(int));
            break;
        }
    }
}

/* The rule text of an option, shared by error messages and /v1/info. */
static void option_rule(const struct technique_option *opt, char *buf, size_t cap)
{
    switch (opt->type) {
    case TOPT_INT:
        snprintf(buf, cap, "must be an integer from %.0f to %.0f", opt->min, opt->max);
        break;
    case TOPT_NUMBER:
        snprintf(buf, cap, "must be a number from %g to %g", opt->min, opt->max);
        break;
    case TOPT_BOOL:
        snprintf(buf, cap, "must be true or false");
        break;
    case TOPT_CHOICE: {
        char list[200];
        jf_list_choices(opt->choices, list, sizeof(list));
        snprintf(buf, cap, "must be one of: %s", list);
        break;
    }
    case TOPT_POW2_OR_AUTO:
        snprintf(buf, cap, "must be \"auto\" or a power of two from %.0f to %.0f", opt->min,
                 opt->max);
        break;
    case TOPT_INT_LIST:
        snprintf(buf, cap, "must be a list of %d integers, each from %.0f to %.0f", opt->count,
                 opt->min, opt->max);
        break;
    }
}

static bool whole_number(const json_t *v, double *out)
{
    if (json_is_integer(v)) {
        *out = (double)json_integer_value(v);
        return true;
    }
    if (json_is_real(v) && floor(json_real_value(v)) == json_real_value(v)) {
        *out = json_real_value(v);
        return true;
    }
    return false;
}

static bool parse_value(const struct technique_option *opt, const json_t *v, const char *field,
                        struct technique_options *o, struct job_error *err)
{
    char rule[256];
    option_rule(opt, rule, sizeof(rule));
    void *p = field_at(o, opt);
    double d;
    switch (opt->type) {
    case TOPT_INT:
        if (!whole_number(v, &d) || d < opt->min || d > opt->max)
            return job_error_set(err, field, "%s", rule);
        *(int *)p = (int)d;
        return true;
    case TOPT_NUMBER:
        if (!json_is_number(v) || !isfinite(json_number_value(v)) ||
            json_number_value(v) < opt->min || json_number_value(v) > opt->max)
            return job_error_set(err, field, "%s", rule);
        *(double *)p = json_number_value(v);
        return true;
    case TOPT_BOOL:
        if (!json_is_boolean(v))
            return job_error_set(err, field, "%s", rule);
        *(bool *)p = json_is_true(v);
        return true;
    case TOPT_CHOICE:
        for (int i = 0; json_is_string(v) && opt->choices[i]; i++)
            if (strcmp(json_string_value(v), opt->choices[i]) == 0) {
                *(int *)p = i;
                return true;
            }
        return job_error_set(err, field, "%s", rule);
    case TOPT_POW2_OR_AUTO:
        if (json_is_string(v) && strcmp(json_string_value(v), "auto") == 0) {
            *(int *)p = 0;
            return true;
        }
        if (!json_is_integer(v))
            return job_error_set(err, field, "%s", rule);
        {
            json_int_t r = json_integer_value(v);
            if (r < (json_int_t)opt->min || r > (json_int_t)opt->max || (r & (r - 1)) != 0)
                return job_error_set(err, field, "%s", rule);
            *(int *)p = (int)r;
        }
        return true;
    case TOPT_INT_LIST:
        if (!json_is_array(v) || json_array_size(v) != (size_t)opt->count)
            return job_error_set(err, field, "%s", rule);
        for (int i = 0; i < opt->count; i++) {
            if (!whole_number(json_array_get(v, (size_t)i), &d) || d < opt->min || d > opt->max)
                return job_error_set(err, field, "%s", rule);
            ((int *)p)[i] = (int)d;
        }
        return true;
    }
    return job_error_set(err, field, "unsupported option type");
}

/* The distinct next path components of the options under level ("" or
 * "gbuffer."), in declaration order. */
static int level_keys(const struct technique_info *t, const char *level, const char **keys,
                      size_t *lens, int cap)
{
    int n = 0;
    size_t ll = strlen(level);
    for (const struct technique_option *opt = t->options; opt && opt->name; opt++) {
        if (strncmp(opt->name, level, ll) != 0)
            continue;
        const char *rest = opt->name + ll, *dot = strchr(rest, '.');
        size_t len = dot ? (size_t)(dot - rest) : strlen(rest);
        bool seen = false;
        for (int i = 0; i < n && !seen; i++)
            seen = lens[i] == len && strncmp(keys[i], rest, len) == 0;
        if (!seen && n < cap) {
            keys[n] = rest;
            lens[n++] = len;
        }
    }
    return n;
}

static const struct technique_option *find_option(const struct technique_info *t, const char *name)
{
    for (const struct technique_option *opt = t->options; opt && opt->name; opt++)
        if (strcmp(opt->name, name) == 0)
            return opt;
    return NULL;
}

static bool parse_level(const struct technique_info *t, const json_t *obj, const char *level,
                        struct technique_options *o, struct job_error *err)
{
    const char *keys[MAX_KEYS];
    size_t lens[MAX_KEYS];
    int n = level_keys(t, level, keys, lens, MAX_KEYS);
    char names[MAX_KEYS][48];
    const char *known[MAX_KEYS + 1];
    for (int i = 0; i < n; i++) {
        snprintf(names[i], sizeof(names[i]), "%.*s", (int)lens[i], keys[i]);
        known[i] = names[i];
    }
    known[n] = NULL;
    char prefix[96];
    snprintf(prefix, sizeof(prefix), "%s.%s", t->name, level);
    if (!json_is_object(obj))
        return job_error_set(err, level[0] ? prefix : t->name, "must be an object");
    if (!jf_check_keys(obj, prefix, known, err))
        return false;
    for (int i = 0; i < n; i++) {
        json_t *v = json_object_get(obj, names[i]);
        if (!v)
            continue;
        char path[160], field[256];
        snprintf(path, sizeof(path), "%.100s%.47s", level, names[i]);
        snprintf(field, sizeof(field), "%s.%s", t->name, path);
        const struct technique_option *opt = find_option(t, path);
        if (opt) {
            if (!parse_value(opt, v, field, o, err))
                return false;
            continue;
        }
        char sub[200];
        snprintf(sub, sizeof(sub), "%s.", path);
        if (!json_is_object(v))
            return job_error_set(err, field, "must be an object");
        if (!parse_level(t, v, sub, o, err))
            return false;
    }
    return true;
}

bool technique_options_parse(const struct technique_info *t, const json_t *obj,
                             struct technique_options *o, struct job_error *err)
{
    if (!parse_level(t, obj, "", o, err))
        return false;
    return !t->check || t->check(o->bytes, err);
}

static json_t *value_json(const struct technique_option *opt, const void *p)
{
    switch (opt->type) {
    case TOPT_INT:
        return json_integer(*(const int *)p);
    case TOPT_NUMBER:
        return json_real(*(const double *)p);
    case TOPT_BOOL:
        return json_boolean(*(const bool *)p);
    case TOPT_CHOICE:
        return json_string(opt->choices[*(const int *)p]);
    case TOPT_POW2_OR_AUTO:
        return *(const int *)p ? json_integer(*(const int *)p) : json_string("auto");
    case TOPT_INT_LIST: {
        json_t *a = json_array();
        for (int i = 0; i < opt->count; i++)
            json_array_append_new(a, json_integer(((const int *)p)[i]));
        return a;
    }
    }
    return json_null();
}

/* Sets value at a dotted path inside obj, creating the objects between. */
static void set_path(json_t *obj, const char *path, json_t *value)
{
    const char *dot;
    while ((dot = strchr(path, '.'))) {
        char head[48];
        snprintf(head, sizeof(head), "%.*s", (int)(dot - path), path);
        json_t *inner = json_object_get(obj, head);
        if (!json_is_object(inner)) {
            inner = json_object();
            json_object_set_new(obj, head, inner);
        }
        obj = inner;
        path = dot + 1;
    }
    json_object_set_new(obj, path, value);
}

json_t *technique_options_to_json(const struct technique_info *t, const struct technique_options *o)
{
    json_t *out = json_object();
    for (const struct technique_option *opt = t->options; opt && opt->name; opt++)
        set_path(out, opt->name, value_json(opt, cfield_at(o, opt)));
    return out;
}

static const char *type_name(enum topt_type type)
{
    static const char *const names[] = {"integer", "number", "boolean", "choice",
                                        "power_of_two_or_auto", "integer_list"};
    return names[type];
}

json_t *technique_catalog_json(const struct technique_catalog *c)
{
    json_t *list = json_array();
    for (int i = 0; i < c->count; i++) {
        const struct technique_info *t = c->infos[i];
        json_t *passes = json_array(), *options = json_object();
        for (int p = 0; t->passes && t->passes[p]; p++)
            json_array_append_new(passes, json_string(t->passes[p]));
        struct technique_options defaults;
        technique_options_defaults(t, &defaults);
        for (const struct technique_option *opt = t->options; opt && opt->name; opt++) {
            char rule[256];
            option_rule(opt, rule, sizeof(rule));
            json_t *d = json_pack("{s:s, s:o, s:s, s:s, s:b}", "type", type_name(opt->type),
                                  "default", value_json(opt, cfield_at(&defaults, opt)),
                                  "rule", rule, "summary", opt->summary ? opt->summary : "",
                                  "sweepable", 1);
            if (opt->type == TOPT_CHOICE) {
                json_t *ch = json_array();
                for (int k = 0; opt->choices[k]; k++)
                    json_array_append_new(ch, json_string(opt->choices[k]));
                json_object_set_new(d, "choices", ch);
            } else if (opt->type != TOPT_BOOL) {
                json_object_set_new(d, "min", json_real(opt->min));
                json_object_set_new(d, "max", json_real(opt->max));
            }
            json_object_set_new(options, opt->name, d);
        }
        json_array_append_new(list, json_pack("{s:s, s:s, s:o, s:o}", "name", t->name, "summary",
                                              t->summary, "passes", passes, "options", options));
    }
    return list;
}

const struct technique_option *technique_catalog_option(const struct technique_catalog *c,
                                                        const char *path)
{
    const char *dot = strchr(path, '.');
    if (!dot)
        return NULL;
    for (int i = 0; i < c->count; i++) {
        size_t len = strlen(c->infos[i]->name);
        if ((size_t)(dot - path) == len && strncmp(path, c->infos[i]->name, len) == 0)
            return find_option(c->infos[i], dot + 1);
    }
    return NULL;
}
