#define _POSIX_C_SOURCE 200809L
#include "common/options.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Longest dotted option name, and longest key of one level. */
#define NAME_BYTES 64

static void *member(void *opts, const struct opt_field *f)
{
    return (unsigned char *)opts + f->offset;
}

static const void *cmember(const void *opts, const struct opt_field *f)
{
    return (const unsigned char *)opts + f->offset;
}

void opt_defaults(const struct opt_table *t, void *opts)
{
    memset(opts, 0, t->size);
    for (const struct opt_field *f = t->fields; f && f->name; f++) {
        void *p = member(opts, f);
        switch (f->type) {
        case OPT_INT:
        case OPT_CHOICE:
        case OPT_POW2:
        case OPT_POW2_OR_AUTO:
            *(int *)p = (int)f->def;
            break;
        case OPT_NUMBER:
            *(double *)p = f->def;
            break;
        case OPT_BOOL:
            *(bool *)p = f->def != 0;
            break;
        case OPT_INT_LIST:
            memcpy(p, f->def_list, (size_t)f->count * sizeof(int));
            break;
        case OPT_CUSTOM:
            if (f->hooks->defaults)
                f->hooks->defaults(opts);
            break;
        }
    }
}

/* The rule an option's value must follow ("must be an integer from 2 to
 * 32"), as errors and /v1/info state it. */
static void opt_rule(const struct opt_field *f, char *buf, size_t cap)
{
    switch (f->type) {
    case OPT_INT:
        snprintf(buf, cap, "must be an integer from %.0f to %.0f", f->min, f->max);
        break;
    case OPT_NUMBER:
        snprintf(buf, cap, "must be a number from %g to %g", f->min, f->max);
        break;
    case OPT_BOOL:
        snprintf(buf, cap, "must be true or false");
        break;
    case OPT_CHOICE: {
        char list[200];
        jf_list_choices(f->choices, list, sizeof(list));
        snprintf(buf, cap, "must be one of: %s", list);
        break;
    }
    case OPT_POW2:
        snprintf(buf, cap, "must be a power of two from %.0f to %.0f", f->min, f->max);
        break;
    case OPT_POW2_OR_AUTO:
        snprintf(buf, cap, "must be \"auto\"%s%s%s or a power of two from %.0f to %.0f",
                 f->auto_means ? " (" : "", f->auto_means ? f->auto_means : "",
                 f->auto_means ? ")" : "", f->min, f->max);
        break;
    case OPT_INT_LIST:
        snprintf(buf, cap, "must be a list of %d integers, each from %.0f to %.0f", f->count,
                 f->min, f->max);
        break;
    case OPT_CUSTOM:
        snprintf(buf, cap, "%s", f->hooks->rule ? f->hooks->rule : "");
        break;
    }
}

/* JSON integers, and reals without a fraction (tools that write every
 * number as a double). */
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

static bool is_pow2(double d)
{
    return d >= 1 && d <= (double)INT32_MAX && !((int64_t)d & ((int64_t)d - 1));
}

static bool read_value(const struct opt_field *f, const json_t *v, const char *field, void *opts,
                       struct job_error *err)
{
    char rule[256];
    opt_rule(f, rule, sizeof(rule));
    void *p = member(opts, f);
    double d;
    switch (f->type) {
    case OPT_INT:
        if (!whole_number(v, &d) || d < f->min || d > f->max)
            return job_error_set(err, field, "%s", rule);
        *(int *)p = (int)d;
        return true;
    case OPT_NUMBER:
        if (!json_is_number(v) || !isfinite(json_number_value(v)) ||
            json_number_value(v) < f->min || json_number_value(v) > f->max)
            return job_error_set(err, field, "%s", rule);
        *(double *)p = json_number_value(v);
        return true;
    case OPT_BOOL:
        if (!json_is_boolean(v))
            return job_error_set(err, field, "%s", rule);
        *(bool *)p = json_is_true(v);
        return true;
    case OPT_CHOICE:
        for (int i = 0; json_is_string(v) && f->choices[i]; i++)
            if (strcmp(json_string_value(v), f->choices[i]) == 0) {
                *(int *)p = i;
                return true;
            }
        return job_error_set(err, field, "%s", rule);
    case OPT_POW2_OR_AUTO:
        if (json_is_string(v) && strcmp(json_string_value(v), "auto") == 0) {
            *(int *)p = 0;
            return true;
        }
        /* fall through */
    case OPT_POW2:
        if (!whole_number(v, &d) || d < f->min || d > f->max || !is_pow2(d))
            return job_error_set(err, field, "%s", rule);
        *(int *)p = (int)d;
        return true;
    case OPT_INT_LIST:
        if (!json_is_array(v) || json_array_size(v) != (size_t)f->count)
            return job_error_set(err, field, "%s", rule);
        for (int i = 0; i < f->count; i++) {
            if (!whole_number(json_array_get(v, (size_t)i), &d) || d < f->min || d > f->max)
                return job_error_set(err, field, "%s", rule);
            ((int *)p)[i] = (int)d;
        }
        return true;
    case OPT_CUSTOM:
        return f->hooks->parse(v, field, opts, err);
    }
    return job_error_set(err, field, "unsupported option type");
}

bool opt_parse_value(const struct opt_field *f, const json_t *v, const char *field, void *opts,
                     struct job_error *err)
{
    return read_value(f, v, field, opts, err);
}

static int field_index(const struct opt_table *t, const char *name)
{
    int i = 0;
    for (const struct opt_field *f = t->fields; f && f->name; f++, i++)
        if (strcmp(f->name, name) == 0)
            return i;
    return -1;
}

const struct opt_field *opt_find(const struct opt_table *t, const char *name)
{
    int i = field_index(t, name);
    return i >= 0 ? &t->fields[i] : NULL;
}

/* Some option's name continues path with a dot: path is a group. */
static bool is_group(const struct opt_table *t, const char *path)
{
    size_t len = strlen(path);
    for (const struct opt_field *f = t->fields; f && f->name; f++)
        if (strncmp(f->name, path, len) == 0 && f->name[len] == '.')
            return true;
    return false;
}

/* The keys an object at level ("" or "gbuffer.") may hold, in table order:
 * for "gbuffer.normal" at level "", both "gbuffer" and "gbuffer.normal". */
static int level_keys(const struct opt_table *t, const char *level, char (*keys)[NAME_BYTES],
                      int cap)
{
    int n = 0;
    size_t ll = strlen(level);
    for (const struct opt_field *f = t->fields; f && f->name; f++) {
        if (strncmp(f->name, level, ll) != 0)
            continue;
        const char *rest = f->name + ll;
        for (const char *end = strchr(rest, '.');; end = strchr(end + 1, '.')) {
            size_t len = end ? (size_t)(end - rest) : strlen(rest);
            bool seen = len >= NAME_BYTES;
            for (int i = 0; i < n && !seen; i++)
                seen = strlen(keys[i]) == len && strncmp(keys[i], rest, len) == 0;
            if (!seen && n < cap)
                snprintf(keys[n++], NAME_BYTES, "%.*s", (int)len, rest);
            if (!end)
                break;
        }
    }
    return n;
}

/* What a reader collected: each option's value, and how it was spelled. */
struct reader {
    const struct opt_table *t;
    const char *prefix;
    struct job_error *err;
    const json_t *value[OPT_MAX_FIELDS];
    char spelled[OPT_MAX_FIELDS][2 * NAME_BYTES];
};

/* `"a": {"b"}` for the keys a, b that led to a value. */
static void spell(const char *outer, const char *key, char *out, size_t cap)
{
    if (!outer[0]) {
        snprintf(out, cap, "\"%.63s\"", key);
        return;
    }
    /* outer is `"a"` or `"a": {"b"}`: the new key goes inside the last braces. */
    size_t depth = 0, len = strlen(outer);
    while (depth < len && outer[len - 1 - depth] == '}')
        depth++;
    snprintf(out, cap, "%.*s: {\"%.63s\"}%.*s", (int)(len - depth), outer, key, (int)depth,
             outer + len - depth);
}

static bool collect(struct reader *r, const json_t *obj, const char *level, const char *spelled)
{
    char keys[2 * OPT_MAX_FIELDS][NAME_BYTES];
    const char *known[2 * OPT_MAX_FIELDS + 1];
    int n = level_keys(r->t, level, keys, 2 * OPT_MAX_FIELDS);
    for (int i = 0; i < n; i++)
        known[i] = keys[i];
    known[n] = NULL;
    char prefix[160];
    snprintf(prefix, sizeof(prefix), "%s.%s", r->prefix, level);
    if (!jf_check_keys(obj, prefix, known, r->err))
        return false;
    for (int i = 0; i < n; i++) {
        const json_t *v = json_object_get(obj, keys[i]);
        if (!v)
            continue;
        char path[2 * NAME_BYTES], here[2 * NAME_BYTES];
        snprintf(path, sizeof(path), "%.63s%.63s", level, keys[i]);
        spell(spelled, keys[i], here, sizeof(here));
        int k = field_index(r->t, path);
        if (k >= 0 && k < OPT_MAX_FIELDS) {
            if (r->value[k]) {
                char field[200];
                snprintf(field, sizeof(field), "%s.%s", r->prefix, path);
                return job_error_set(r->err, field, "given twice, as %s and as %s: give it once",
                                     r->spelled[k], here);
            }
            r->value[k] = v;
            memcpy(r->spelled[k], here, sizeof(here));
            continue;
        }
        if (!is_group(r->t, path))
            continue; /* a longer key than NAME_BYTES: refused by no table */
        if (!json_is_object(v)) {
            char field[200];
            snprintf(field, sizeof(field), "%s.%s", r->prefix, path);
            return job_error_set(r->err, field, "must be an object");
        }
        char sub[2 * NAME_BYTES + 1];
        snprintf(sub, sizeof(sub), "%s.", path);
        if (!collect(r, v, sub, here))
            return false;
    }
    return true;
}

bool opt_parse(const struct opt_table *t, const json_t *obj, const char *prefix, void *opts,
               struct job_error *err)
{
    if (!json_is_object(obj))
        return job_error_set(err, prefix, "must be an object");
    struct reader *r = calloc(1, sizeof(*r));
    if (!r)
        return job_error_set(err, prefix, "out of memory");
    r->t = t;
    r->prefix = prefix;
    r->err = err;
    bool ok = collect(r, obj, "", "");
    /* In table order, whatever order the body gave them in. */
    int i = 0;
    for (const struct opt_field *f = t->fields; ok && f && f->name; f++, i++) {
        if (i >= OPT_MAX_FIELDS || !r->value[i])
            continue;
        char field[200];
        snprintf(field, sizeof(field), "%s.%s", prefix, f->name);
        ok = read_value(f, r->value[i], field, opts, err);
    }
    free(r);
    return ok && (!t->check || t->check(opts, prefix, err));
}

static json_t *value_json(const struct opt_field *f, const void *opts)
{
    const void *p = cmember(opts, f);
    switch (f->type) {
    case OPT_INT:
    case OPT_POW2:
        return json_integer(*(const int *)p);
    case OPT_NUMBER:
        return json_real(*(const double *)p);
    case OPT_BOOL:
        return json_boolean(*(const bool *)p);
    case OPT_CHOICE:
        return json_string(f->choices[*(const int *)p]);
    case OPT_POW2_OR_AUTO:
        return *(const int *)p ? json_integer(*(const int *)p) : json_string("auto");
    case OPT_INT_LIST: {
        json_t *a = json_array();
        for (int i = 0; i < f->count; i++)
            json_array_append_new(a, json_integer(((const int *)p)[i]));
        return a;
    }
    case OPT_CUSTOM:
        return f->hooks->to_json(opts);
    }
    return json_null();
}

json_t *opt_to_json(const struct opt_table *t, const void *opts)
{
    json_t *out = json_object();
    for (const struct opt_field *f = t->fields; f && f->name; f++)
        jf_set_path(out, f->name, value_json(f, opts));
    return out;
}

static const char *type_name(const struct opt_field *f)
{
    static const char *const names[] = {"integer", "number", "boolean", "choice",
                                        "power_of_two", "power_of_two_or_auto", "integer_list"};
    return f->type == OPT_CUSTOM ? (f->hooks->type ? f->hooks->type : "object") : names[f->type];
}

json_t *opt_describe(const struct opt_table *t)
{
    json_t *options = json_object();
    void *defaults = calloc(1, t->size ? t->size : 1);
    if (!defaults)
        return options;
    opt_defaults(t, defaults);
    for (const struct opt_field *f = t->fields; f && f->name; f++) {
        char rule[256];
        opt_rule(f, rule, sizeof(rule));
        json_t *d = json_pack("{s:s, s:o, s:s, s:s, s:b}", "type", type_name(f), "default",
                              value_json(f, defaults), "rule", rule, "summary",
                              f->summary ? f->summary : "", "sweepable", f->type != OPT_CUSTOM);
        if (f->type == OPT_CHOICE) {
            json_t *ch = json_array();
            for (int k = 0; f->choices[k]; k++)
                json_array_append_new(ch, json_string(f->choices[k]));
            json_object_set_new(d, "choices", ch);
        } else if (f->type != OPT_BOOL && f->type != OPT_CUSTOM) {
            json_object_set_new(d, "min", json_real(f->min));
            json_object_set_new(d, "max", json_real(f->max));
        }
        json_object_set_new(options, f->name, d);
    }
    free(defaults);
    return options;
}

json_t *opt_part_json(const char *name, const char *summary, const char *const *passes,
                      const struct opt_table *t)
{
    json_t *list = json_array();
    for (int p = 0; passes && passes[p]; p++)
        json_array_append_new(list, json_string(passes[p]));
    return json_pack("{s:s, s:s, s:o, s:o}", "name", name, "summary", summary, "passes", list,
                     "options", opt_describe(t));
}

/* Bytes of the member an option writes (custom options: none known). */
static size_t member_bytes(const struct opt_field *f)
{
    switch (f->type) {
    case OPT_NUMBER:
        return sizeof(double);
    case OPT_BOOL:
        return sizeof(bool);
    case OPT_INT_LIST:
        return (size_t)(f->count > 0 ? f->count : 0) * sizeof(int);
    case OPT_CUSTOM:
        return 0;
    default:
        return sizeof(int);
    }
}

static bool default_ok(const struct opt_field *f)
{
    switch (f->type) {
    case OPT_INT:
    case OPT_NUMBER:
        return f->def >= f->min && f->def <= f->max && f->min <= f->max;
    case OPT_POW2:
        return f->def >= f->min && f->def <= f->max && is_pow2(f->def);
    case OPT_POW2_OR_AUTO:
        return f->def == 0 || (f->def >= f->min && f->def <= f->max && is_pow2(f->def));
    case OPT_CHOICE: {
        int n = 0;
        while (f->choices && f->choices[n])
            n++;
        return f->def >= 0 && f->def < n;
    }
    case OPT_INT_LIST:
        if (!f->def_list || f->count < 1)
            return false;
        for (int i = 0; i < f->count; i++)
            if (f->def_list[i] < f->min || f->def_list[i] > f->max)
                return false;
        return true;
    case OPT_CUSTOM:
        return f->hooks && f->hooks->parse && f->hooks->to_json;
    case OPT_BOOL:
        return true;
    }
    return false;
}

bool opt_table_check(const struct opt_table *t, const char *owner, char *err, size_t errlen)
{
    int n = 0;
    for (const struct opt_field *f = t->fields; f && f->name; f++, n++) {
        size_t len = strlen(f->name);
        if (n >= OPT_MAX_FIELDS) {
            snprintf(err, errlen, "%s: more than %d options", owner, OPT_MAX_FIELDS);
            return false;
        }
        if (len == 0 || len >= NAME_BYTES || f->name[0] == '.' || f->name[len - 1] == '.' ||
            strstr(f->name, "..")) {
            snprintf(err, errlen, "%s: option \"%s\": names are 1 to %d characters, dots only "
                     "between parts", owner, f->name, NAME_BYTES - 1);
            return false;
        }
        if (field_index(t, f->name) != n || is_group(t, f->name)) {
            snprintf(err, errlen, "%s: option %s is declared twice, or is also a group of "
                     "options", owner, f->name);
            return false;
        }
        if (f->offset + member_bytes(f) > t->size) {
            snprintf(err, errlen, "%s: option %s lies outside the options struct (%zu bytes)",
                     owner, f->name, t->size);
            return false;
        }
        if (!default_ok(f)) {
            snprintf(err, errlen, "%s: option %s: its default, choices, range or hooks are "
                     "missing or do not agree", owner, f->name);
            return false;
        }
    }
    return true;
}
