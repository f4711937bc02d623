#define _POSIX_C_SOURCE 200809L
#include "client/junit.h"

#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "client/gate.h"
#include "client/workload.h"

void junit_init(struct junit *j) { memset(j, 0, sizeof(*j)); }

void junit_finish(struct junit *j)
{
    if (!j)
        return;
    for (size_t i = 0; i < j->count; i++)
        json_decref(j->cases[i].properties);
    free(j->cases);
    memset(j, 0, sizeof(*j));
}

static bool has_name(const struct junit *j, const char *classname, const char *name)
{
    for (size_t i = 0; i < j->count; i++)
        if (!strcmp(j->cases[i].name, name) && !strcmp(j->cases[i].classname, classname))
            return true;
    return false;
}

struct junit_case *junit_add(struct junit *j, const char *classname, const char *name)
{
    if (j->count == j->cap) {
        size_t cap = j->cap ? j->cap * 2 : 16;
        struct junit_case *grown = realloc(j->cases, cap * sizeof(*grown));
        if (!grown)
            return NULL;
        j->cases = grown;
        j->cap = cap;
    }
    char unique[sizeof(j->cases[0].name)];
    snprintf(unique, sizeof(unique), "%s", name);
    for (int k = 2; has_name(j, classname, unique) && k < 10000; k++)
        snprintf(unique, sizeof(unique), "%.380s (%d)", name, k);
    struct junit_case *c = &j->cases[j->count++];
    memset(c, 0, sizeof(*c));
    snprintf(c->classname, sizeof(c->classname), "%s", classname);
    snprintf(c->name, sizeof(c->name), "%s", unique);
    c->properties = json_object();
    return c;
}

static void vappend(char *dst, size_t cap, const char *fmt, va_list ap)
{
    size_t used = strlen(dst);
    if (used + 1 < cap)
        vsnprintf(dst + used, cap - used, fmt, ap);
}

void junit_fail(struct junit_case *c, const char *type, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (!c->failure[0] || c->inconclusive)
        snprintf(c->failure_type, sizeof(c->failure_type), "%s", type);
    if (c->failure[0] && strlen(c->failure) + 3 < sizeof(c->failure))
        strcat(c->failure, "; ");
    vappend(c->failure, sizeof(c->failure), fmt, ap);
    va_end(ap);
}

void junit_inconclusive(struct junit_case *c, bool fail, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    c->inconclusive = true;
    char *dst = fail ? c->failure : c->skipped;
    size_t cap = fail ? sizeof(c->failure) : sizeof(c->skipped);
    if (fail && !c->failure[0])
        snprintf(c->failure_type, sizeof(c->failure_type), "%s", JUNIT_INCONCLUSIVE);
    if (dst[0] && strlen(dst) + 3 < cap)
        strcat(dst, "; ");
    vappend(dst, cap, fmt, ap);
    va_end(ap);
}

void junit_skip(struct junit_case *c, const char *tag, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    snprintf(c->skip_tag, sizeof(c->skip_tag), "%s", tag);
    if (c->skipped[0] && strlen(c->skipped) + 3 < sizeof(c->skipped))
        strcat(c->skipped, "; ");
    vappend(c->skipped, sizeof(c->skipped), fmt, ap);
    va_end(ap);
}

void junit_out(struct junit_case *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (c->output[0] && strlen(c->output) + 2 < sizeof(c->output))
        strcat(c->output, "\n");
    vappend(c->output, sizeof(c->output), fmt, ap);
    va_end(ap);
}

void junit_prop_num(struct junit_case *c, const char *name, double value)
{
    if (c->properties && isfinite(value))
        json_object_set_new(c->properties, name, json_real(value));
}

void junit_prop_str(struct junit_case *c, const char *name, const char *value)
{
    if (c->properties && value)
        json_object_set_new(c->properties, name, json_string(value));
}

size_t junit_failures(const struct junit *j)
{
    size_t n = 0;
    for (size_t i = 0; i < j->count; i++)
        n += j->cases[i].failure[0] != '\0';
    return n;
}

size_t junit_real_failures(const struct junit *j)
{
    size_t n = 0;
    for (size_t i = 0; i < j->count; i++)
        n += j->cases[i].failure[0] != '\0' && !j->cases[i].inconclusive;
    return n;
}

size_t junit_undecided(const struct junit *j)
{
    size_t n = 0;
    for (size_t i = 0; i < j->count; i++)
        n += j->cases[i].inconclusive;
    return n;
}

size_t junit_judged_nothing(const struct junit *j)
{
    size_t n = 0;
    for (size_t i = 0; i < j->count; i++)
        n += j->cases[i].skip_tag[0] && !j->cases[i].failure[0] && !j->cases[i].inconclusive;
    return n;
}

static size_t junit_skipped(const struct junit *j)
{
    size_t n = 0;
    for (size_t i = 0; i < j->count; i++)
        n += j->cases[i].skipped[0] != '\0' && !j->cases[i].failure[0];
    return n;
}

void xml_escaped(FILE *f, const char *s)
{
    for (; s && *s; s++)
        switch (*s) {
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '&': fputs("&amp;", f); break;
        case '"': fputs("&quot;", f); break;
        default:
            if ((unsigned char)*s >= 0x20 || *s == '\n' || *s == '\t')
                fputc(*s, f);
        }
}

static void prop_text(const json_t *v, char *out, size_t cap)
{
    if (json_is_string(v))
        snprintf(out, cap, "%s", json_string_value(v));
    else if (json_is_number(v))
        snprintf(out, cap, "%.6g", json_number_value(v));
    else
        snprintf(out, cap, "?");
}

bool junit_write(const struct junit *j, const char *path, const char *suite, double time_s)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return false;
    size_t failures = junit_failures(j), skipped = junit_skipped(j);
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<testsuites name=\"shadebench\" tests=\"%zu\" failures=\"%zu\" skipped=\"%zu\" "
            "time=\"%.3f\">\n", j->count, failures, skipped, time_s);
    fprintf(f, "  <testsuite name=\"");
    xml_escaped(f, suite);
    fprintf(f, "\" tests=\"%zu\" failures=\"%zu\" errors=\"0\" skipped=\"%zu\" time=\"%.3f\">\n",
            j->count, failures, skipped, time_s);
    char text[256];
    for (size_t i = 0; i < j->count; i++) {
        const struct junit_case *c = &j->cases[i];
        fprintf(f, "    <testcase classname=\"");
        xml_escaped(f, c->classname);
        fprintf(f, "\" name=\"");
        xml_escaped(f, c->name);
        fprintf(f, "\" time=\"%.3f\">\n", c->time_s > 0 ? c->time_s : 0.0);
        if (json_object_size(c->properties)) {
            fprintf(f, "      <properties>\n");
            const char *key;
            json_t *v;
            json_object_foreach(c->properties, key, v) {
                prop_text(v, text, sizeof(text));
                fprintf(f, "        <property name=\"");
                xml_escaped(f, key);
                fprintf(f, "\" value=\"");
                xml_escaped(f, text);
                fprintf(f, "\"/>\n");
            }
            fprintf(f, "      </properties>\n");
        }
        if (c->failure[0]) {
            fprintf(f, "      <failure type=\"");
            xml_escaped(f, c->failure_type[0] ? c->failure_type : JUNIT_JOB_FAILED);
            fprintf(f, "\" message=\"");
            xml_escaped(f, c->failure);
            fprintf(f, "\"/>\n");
        } else if (c->skipped[0]) {
            fprintf(f, "      <skipped message=\"");
            xml_escaped(f, c->skipped);
            fprintf(f, "\"/>\n");
        }
        if (c->output[0]) {
            fprintf(f, "      <system-out>");
            xml_escaped(f, c->output);
            fprintf(f, "</system-out>\n");
        }
        fprintf(f, "    </testcase>\n");
    }
    fprintf(f, "  </testsuite>\n</testsuites>\n");
    return fclose(f) == 0;
}

/* The case's word in the log, and its colour: green, red, yellow. */
static const char *case_tag(const struct junit_case *c, const char **color)
{
    if (c->failure[0]) {
        *color = "\033[1;31m";
        return c->inconclusive ? "INCONCLUSIVE" : "FAIL";
    }
    *color = "\033[1;33m";
    if (c->inconclusive)
        return "INCONCLUSIVE";
    if (c->skip_tag[0])
        return c->skip_tag;
    *color = "\033[1;32m";
    return "PASS";
}

void junit_print(const struct junit *j, FILE *f, bool color)
{
    char text[256];
    for (size_t i = 0; i < j->count; i++) {
        const struct junit_case *c = &j->cases[i];
        const char *on;
        const char *tag = case_tag(c, &on);
        fprintf(f, "%s%s%s %s (%.2f s)", color ? on : "", tag, color ? "\033[0m" : "", c->name,
                c->time_s);
        const char *key;
        json_t *v;
        const char *sep = ": ";
        json_object_foreach(c->properties, key, v) {
            prop_text(v, text, sizeof(text));
            fprintf(f, "%s%s=%s", sep, key, text);
            sep = ", ";
        }
        fputc('\n', f);
        if (c->failure[0])
            fprintf(f, "    failure (%s): %s\n", c->failure_type, c->failure);
        else if (c->skipped[0])
            fprintf(f, "    %s: %s\n", c->inconclusive ? "not decided" : "not judged", c->skipped);
        if (c->output[0])
            fprintf(f, "    %s\n", c->output);
    }
}

static void scalar_text(const json_t *v, char *out, size_t cap)
{
    if (json_is_string(v))
        snprintf(out, cap, "%s", json_string_value(v));
    else if (json_is_number(v))
        snprintf(out, cap, "%g", json_number_value(v));
    else if (json_is_boolean(v))
        snprintf(out, cap, "%s", json_is_true(v) ? "true" : "false");
    else {
        char *t = json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT | JSON_SORT_KEYS);
        snprintf(out, cap, "%s", t ? t : "?");
        free(t);
    }
}

static int by_string(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* Keys of an object in sorted order (the names must not depend on the
 * order the daemon writes them in). Returns a malloc'ed array. */
static const char **sorted_keys(const json_t *o, size_t *n)
{
    *n = json_object_size(o);
    const char **keys = malloc((*n ? *n : 1) * sizeof(*keys));
    size_t k = 0;
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)o, key, v) if (keys) keys[k++] = key;
    if (keys)
        qsort(keys, k, sizeof(*keys), by_string);
    return keys;
}

static void put(char *out, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void put(char *out, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vappend(out, cap, fmt, ap);
    va_end(ap);
}

void junit_job_name(const json_t *spec, char *out, size_t cap)
{
    /* At most 240 characters, so that a check's suffix always fits. */
    char name[241] = "";
    size_t ncap = sizeof(name) < cap ? sizeof(name) : cap;
    const char *tech = json_string_value(json_object_get(spec, "technique"));
    put(name, ncap, "%s", tech ? tech : "job");
    size_t n;
    const char **keys = sorted_keys(spec, &n);
    char text[128];
    /* Technique options: top-level scalars that are set, and the object
     * named after this technique. */
    for (size_t i = 0; keys && i < n; i++) {
        const char *k = keys[i];
        json_t *v = json_object_get(spec, k);
        if (gate_nonsemantic_field(k) || !strcmp(k, "technique") || !strcmp(k, "scene") ||
            !strcmp(k, "frames") || !strcmp(k, "warmup_frames"))
            continue;
        if (json_is_object(v) || !strcmp(k, "look")) {
            if (!tech || strcmp(k, tech) != 0 || json_object_size(v) == 0)
                continue; /* another technique's options, the look (hashed below), or none */
            size_t m;
            const char **sub = sorted_keys(v, &m);
            put(name, ncap, " %s(", k);
            for (size_t s = 0, shown = 0; sub && s < m; s++) {
                json_t *sv = json_object_get(v, sub[s]);
                /* An option the spec also states at the top level (an
                 * alias kept for older clients) is named there, once. */
                if (json_equal(sv, json_object_get(spec, sub[s])))
                    continue;
                scalar_text(sv, text, sizeof(text));
                put(name, ncap, "%s%s=%s", shown++ ? " " : "", sub[s], text);
            }
            put(name, ncap, ")");
            free(sub);
            continue;
        }
        if ((json_is_number(v) && json_number_value(v) == 0) || json_is_false(v) ||
            json_is_null(v))
            continue;
        scalar_text(v, text, sizeof(text));
        put(name, ncap, " %s=%s", k, text);
    }
    free(keys);
    /* The scene by what shapes the work most: preset, size, lights, their
     * motion; each only when the spec names it, so that a name made from
     * the spec as the user wrote it does not change when the daemon's
     * defaults do. */
    json_t *scene = json_object_get(spec, "scene");
    if (json_is_object(scene)) {
        const char *preset = json_string_value(json_object_get(scene, "preset"));
        json_t *w = json_object_get(scene, "width"), *h = json_object_get(scene, "height");
        json_t *lights = json_object_get(scene, "lights"), *dyn = json_object_get(scene, "dynamic");
        if (preset)
            put(name, ncap, " %s", preset);
        if (json_is_number(w) && json_is_number(h))
            put(name, ncap, " %gx%g", json_number_value(w), json_number_value(h));
        else if (json_is_number(w) || json_is_number(h))
            put(name, ncap, " %s %g", w ? "width" : "height", json_number_value(w ? w : h));
        if (json_is_number(lights))
            put(name, ncap, " %g lights", json_number_value(lights));
        if (json_is_boolean(dyn))
            put(name, ncap, " %s", json_is_true(dyn) ? "moving" : "still");
    }
    /* The rest (layout, camera, materials, the look, warm-up, ...) changes
     * the workload too, but spelled out it would bury the name: it goes in
     * as the workload's hash, the one history and the gate print for it
     * (workload_key, over the whole workload, stable across runs). */
    char key[96];
    workload_key(spec, key, sizeof(key));
    const char *hash = strchr(key, '#');
    put(name, ncap, " #%.8s", hash ? hash + 1 : "00000000");
    json_t *frames = json_object_get(spec, "frames");
    if (json_is_number(frames))
        put(name, ncap, ", %g frames", json_number_value(frames));
    snprintf(out, cap, "%s", name);
}
