#define _POSIX_C_SOURCE 200809L
#include "client/workload.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/gate.h"
#include "client/junit.h"
#include "daemon/spec/job_spec.h"
#include "daemon/techniques/catalog.h"

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

/* The daemon's catalogue of techniques, for its own job parser: made once,
 * on first use (the client is single-threaded). NULL when it cannot be. */
static const struct technique_catalog *catalog(void)
{
    static struct technique_catalog c;
    static int state; /* 0 not tried, 1 ready, -1 failed */
    if (!state) {
        char why[256];
        state = technique_catalog_init(&c, why, sizeof(why)) ? 1 : -1;
    }
    return state > 0 ? &c : NULL;
}

/* spec as the daemon's parser understands it, defaults filled in: the same
 * for the job file as the user wrote it and for the spec the daemon echoes
 * (of the same version). NULL when it does not parse (a technique this
 * client does not know, a field it refuses). */
static json_t *parsed(const json_t *spec)
{
    const struct technique_catalog *cat = catalog();
    struct job_spec *js = cat ? malloc(sizeof(*js)) : NULL;
    struct job_error err;
    json_t *out = js && job_spec_parse(spec, cat, js, &err) ? job_spec_to_json(js) : NULL;
    free(js);
    return out;
}

/* Numbers compare by value (the daemon may write 20 or 20.0). */
static bool same_value(const json_t *a, const json_t *b)
{
    if (json_is_number(a) && json_is_number(b))
        return json_number_value(a) == json_number_value(b);
    return json_equal((json_t *)a, (json_t *)b);
}

/* Drops from o, recursively, every member equal to the same member of the
 * defaults: what is left is what sets this job apart, so that a field the
 * daemon adds later, with a default, changes no workload. */
static void drop_defaults(json_t *o, const json_t *defaults)
{
    const char *k;
    json_t *v;
    void *tmp;
    json_object_foreach_safe(o, tmp, k, v) {
        json_t *d = json_object_get(defaults, k);
        if (!d)
            continue;
        if (json_is_object(v) && json_is_object(d)) {
            drop_defaults(v, d);
            if (!json_object_size(v))
                json_object_del(o, k);
        } else if (same_value(v, d)) {
            json_object_del(o, k);
        }
    }
}

/* The fields that define the workload: not the ones that do not change
 * what is timed, nor objects other than the scene, the look and this
 * technique's own options (other techniques' options: the reference's, or
 * ones the daemon echoes). */
static json_t *semantic_fields(const json_t *spec)
{
    json_t *out = json_object();
    const char *tech = json_string_value(json_object_get(spec, "technique"));
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)spec, k, v) {
        if (gate_nonsemantic_field(k))
            continue;
        if (json_is_object(v) && strcmp(k, "scene") != 0 && strcmp(k, "look") != 0 &&
            (!tech || strcmp(k, tech) != 0))
            continue;
        json_object_set_new(out, k, normalised(v));
    }
    return out;
}

json_t *workload_canonical(const json_t *spec)
{
    if (!json_is_object(spec))
        return json_object();
    /* Parsed without the fields that change nothing timed, so that one the
     * parser refuses there (captures without frames, a reference this
     * client does not know) changes no workload. */
    json_t *given = semantic_fields(spec);
    json_t *full = parsed(given);
    if (!full)
        return given;
    json_decref(given);
    json_t *out = semantic_fields(full);
    json_decref(full);
    /* Against the defaults of the same technique. */
    json_t *bare = json_pack("{s:O}", "technique", json_object_get(out, "technique"));
    json_t *defaults = bare ? parsed(bare) : NULL;
    if (defaults) {
        json_t *tech = json_incref(json_object_get(out, "technique"));
        drop_defaults(out, defaults);
        json_object_set_new(out, "technique", tech); /* always named */
    }
    json_decref(defaults);
    json_decref(bare);
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
    /* What sets the workload apart, plus what shapes the work most even
     * where it is the default (the scene's preset, size, lights and their
     * motion), so that "10 lights" reads in the column; junit_job_name
     * hashes the workload itself (workload_key), which these leave alone. */
    json_t *c = workload_canonical(spec);
    json_t *full = json_is_object(spec) ? parsed(spec) : NULL;
    json_t *scene = json_object_get(full, "scene");
    if (json_is_object(scene)) {
        json_t *into = json_object_get(c, "scene");
        if (!json_is_object(into)) {
            into = json_object();
            json_object_set_new(c, "scene", into);
        }
        static const char *const shown[] = {"preset", "width", "height", "lights", "dynamic"};
        for (size_t i = 0; i < sizeof(shown) / sizeof(shown[0]); i++)
            if (json_object_get(scene, shown[i]) && !json_object_get(into, shown[i]))
                json_object_set(into, shown[i], json_object_get(scene, shown[i]));
    }
    junit_job_name(c, out, cap);
    json_decref(full);
    json_decref(c);
}

bool workload_quality_judged(const json_t *spec, char *why, size_t cap)
{
    why[0] = '\0';
    const struct technique_catalog *cat = catalog();
    struct job_spec *js = cat ? malloc(sizeof(*js)) : NULL;
    struct job_error err;
    bool parsed_ok = js && job_spec_parse(spec, cat, js, &err);
    bool judged = true;
    if (parsed_ok && !js->reference[0]) {
        snprintf(why, cap, "it names no \"reference\" technique to score its captures against "
                 "(add e.g. \"reference\": \"forward\")");
        judged = false;
    } else if (parsed_ok && job_spec_capture_count(js) == 0) {
        snprintf(why, cap, "it captures no frame (capture_interval %d over %d frames)",
                 js->capture_interval, js->frames);
        judged = false;
    } else if (!parsed_ok && json_is_object(spec) && !json_object_get(spec, "reference")) {
        /* A spec this client cannot parse (the daemon will say why, or it
         * is a newer daemon's): at least a reference must be named. */
        snprintf(why, cap, "it names no \"reference\" technique to score its captures against");
        judged = false;
    }
    free(js);
    return judged;
}
