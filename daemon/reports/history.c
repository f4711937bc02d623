/* A workload's history: one measurement's jobs and the changes the gate
 * would flag between them (history.h). */
#include "daemon/reports/history.h"

#include <math.h>
#include <string.h>

bool history_ignored_field(const char *key, bool other_technique)
{
    /* client/gate.c's gate_nonsemantic_field, the gate's list. */
    static const char *const skip[] = {"labels", "repeat", "capture_interval", "reference",
                                       "metrics", "timeout_s", "reference_look", NULL};
    if (other_technique)
        return true;
    for (const char *const *s = skip; *s; s++)
        if (strcmp(*s, key) == 0)
            return true;
    return false;
}

static bool same_value(const json_t *a, const json_t *b)
{
    if (json_is_number(a) && json_is_number(b))
        return json_number_value(a) == json_number_value(b);
    if (json_is_object(a) && json_is_object(b)) {
        if (json_object_size(a) != json_object_size(b))
            return false;
        const char *k;
        json_t *v;
        json_object_foreach((json_t *)a, k, v) {
            if (!same_value(v, json_object_get(b, k)))
                return false;
        }
        return true;
    }
    if (json_is_array(a) && json_is_array(b)) {
        if (json_array_size(a) != json_array_size(b))
            return false;
        for (size_t i = 0; i < json_array_size(a); i++)
            if (!same_value(json_array_get(a, i), json_array_get(b, i)))
                return false;
        return true;
    }
    return a && b && json_equal((json_t *)a, (json_t *)b);
}

/* Every key of a that counts is in b with the same value. */
static bool covers(const json_t *a, const json_t *b, const char *technique,
                   bool (*is_technique)(void *ctx, const char *key), void *ctx)
{
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)a, k, v) {
        bool other = strcmp(k, technique) != 0 && is_technique && is_technique(ctx, k);
        if (history_ignored_field(k, other))
            continue;
        if (!same_value(v, json_object_get(b, k)))
            return false;
    }
    return true;
}

bool history_same_workload(const json_t *a, const json_t *b,
                           bool (*is_technique)(void *ctx, const char *key), void *ctx)
{
    const char *ta = json_string_value(json_object_get(a, "technique"));
    const char *tb = json_string_value(json_object_get(b, "technique"));
    if (!ta || !tb || strcmp(ta, tb) != 0)
        return false;
    return covers(a, b, ta, is_technique, ctx) && covers(b, a, ta, is_technique, ctx);
}

static bool figure(const json_t *p, double *m, double *lo, double *hi)
{
    json_t *ci = json_object_get(p, "ci95");
    *m = json_number_value(json_object_get(p, "median"));
    *lo = json_number_value(json_array_get(ci, 0));
    *hi = json_number_value(json_array_get(ci, 1));
    return json_is_number(json_object_get(p, "median")) && json_array_size(ci) == 2 && *m > 0 &&
           *lo > 0 && *hi >= *lo;
}

json_t *history_changes(const json_t *points, double min_effect)
{
    json_t *out = json_array();
    const json_t *prev = NULL;
    double pm = 0, plo = 0, phi = 0;
    size_t i;
    json_t *p;
    json_array_foreach((json_t *)points, i, p) {
        double m, lo, hi;
        if (json_is_true(json_object_get(p, "noisy")) || !figure(p, &m, &lo, &hi))
            continue;
        if (prev) {
            double ratio = m / pm, rlo = lo / phi, rhi = hi / plo;
            const char *change = NULL;
            if (rlo > 1.0 && ratio > 1.0 + min_effect)
                change = "slower";
            else if (rhi < 1.0 && ratio < 1.0 / (1.0 + min_effect))
                change = "faster";
            if (change)
                json_array_append_new(out, json_pack("{s:O, s:O, s:f, s:[f, f], s:s}", "from",
                                                     json_object_get(prev, "id"), "to",
                                                     json_object_get(p, "id"), "ratio", ratio,
                                                     "ratio_ci", rlo, rhi, "change", change));
        }
        prev = p, pm = m, plo = lo, phi = hi;
    }
    return out;
}
