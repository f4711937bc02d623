#define _POSIX_C_SOURCE 200809L
#include "client/workload.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/gate.h"
#include "client/junit.h"

/* Integral reals become integers, recursively, so that 20.0 and 20 hash
 * alike (the daemon writes some numbers as reals, users write integers). */
static json_t *normalised(const json_t *v)
{
    if (json_is_real(v)) {
        double d = json_real_value(v);
        if (d == floor(d) && fabs(d) < 9e15)
            return json_integer((json_int_t)d);
        return json_real(d);
    }
    if (json_is_object(v)) {
        json_t *o = json_object();
        const char *k;
        json_t *x;
        json_object_foreach((json_t *)v, k, x) json_object_set_new(o, k, normalised(x));
        return o;
    }
    if (json_is_array(v)) {
        json_t *a = json_array();
        size_t i;
        json_t *x;
        json_array_foreach(v, i, x) json_array_append_new(a, normalised(x));
        return a;
    }
    return json_deep_copy(v);
}

json_t *workload_canonical(const json_t *spec)
{
    json_t *out = json_object();
    if (!json_is_object(spec))
        return out;
    const char *tech = json_string_value(json_object_get(spec, "technique"));
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)spec, k, v) {
        if (gate_nonsemantic_field(k))
            continue;
        /* Objects other than the scene, the look and this technique's own
         * options are other techniques' options (the reference's, or ones
         * the daemon echoes): they change nothing that is timed. */
        if (json_is_object(v) && strcmp(k, "scene") != 0 && strcmp(k, "look") != 0 &&
            (!tech || strcmp(k, tech) != 0))
            continue;
        json_object_set_new(out, k, normalised(v));
    }
    return out;
}

static uint64_t fnv1a64(const char *s)
{
    uint64_t h = 14695981039346656037ull;
    for (; s && *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211ull;
    return h;
}

void workload_key(const json_t *spec, char *out, size_t cap)
{
    json_t *c = workload_canonical(spec);
    char *text = json_dumps(c, JSON_SORT_KEYS | JSON_COMPACT);
    const char *tech = json_string_value(json_object_get(c, "technique"));
    snprintf(out, cap, "%s#%016llx", tech ? tech : "job", (unsigned long long)fnv1a64(text));
    free(text);
    json_decref(c);
}

void workload_describe(const json_t *spec, char *out, size_t cap)
{
    json_t *c = workload_canonical(spec);
    char name[320], key[96];
    junit_job_name(c, name, sizeof(name));
    workload_key(spec, key, sizeof(key));
    const char *hash = strchr(key, '#');
    char *mark = strstr(name, " #");
    if (mark && hash && strlen(mark) >= 10)
        memcpy(mark + 2, hash + 1, 8);
    snprintf(out, cap, "%s", name);
    json_decref(c);
}
