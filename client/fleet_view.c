/* Comparing devices: a gathered fleet sweep read per point and per device
 * class, which technique wins where on each device, and each device's
 * crossovers (sweep_verdict_json on the class's own table, so the fleet says
 * what the daemon's report would say on each device). Pure: JSON in, JSON or
 * text out; unit-tested in tests/unit/test_fleet.c. Single-threaded. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/fleet.h"
#include "common/result_keys.h"
#include "daemon/reports/charts.h"
#include "daemon/reports/sweep_verdict.h"

/* "technique|{values}": a point's identity across devices. */
static char *point_key(const json_t *row, bool with_technique)
{
    json_t *values = json_deep_copy(json_object_get(row, "values"));
    if (!values)
        values = json_object();
    if (!with_technique)
        json_object_del(values, "technique");
    char *text = json_dumps(values, JSON_SORT_KEYS | JSON_COMPACT);
    json_decref(values);
    const char *tech = json_string_value(json_object_get(row, "technique"));
    size_t need = (text ? strlen(text) : 0) + (tech ? strlen(tech) : 0) + 2;
    char *key = malloc(need);
    if (key)
        snprintf(key, need, "%s|%s", with_technique && tech ? tech : "", text ? text : "{}");
    free(text);
    return key;
}

/* "lights=16 d=5": the values but the technique, for people. */
static void where_text(const json_t *values, char *out, size_t cap)
{
    out[0] = '\0';
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)values, k, v) {
        if (!strcmp(k, "technique"))
            continue;
        const char *dot = strrchr(k, '.');
        char *t = json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT);
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s=%s", used ? " " : "", dot ? dot + 1 : k,
                 t ? t : "?");
        free(t);
    }
    if (!out[0])
        snprintf(out, cap, "(all)");
}

static json_t *cell(const json_t *row, const char *series)
{
    json_t *s = json_object_get(row, series);
    json_t *c = json_pack("{s:O, s:s}", "status", json_object_get(row, "status"), "series", series);
    if (json_is_number(json_object_get(s, RK_MEDIAN))) {
        json_object_set(c, "ms", json_object_get(s, RK_MEDIAN));
        json_object_set(c, RK_CI95, json_object_get(s, RK_CI95));
    }
    static const char *const q[] = {RK_WORST_SSIM, RK_WORST_FLIP, RK_PDIFF_FAILED_CAPTURES};
    for (int i = 0; i < 3; i++)
        if (json_object_get(row, q[i]))
            json_object_set(c, q[i], json_object_get(row, q[i]));
    return c;
}

static double ci_edge(const json_t *c, int side)
{
    json_t *ci = json_object_get(c, RK_CI95);
    json_t *v = json_array_get(ci, (size_t)side);
    return json_is_number(v) ? json_number_value(v)
                             : json_number_value(json_object_get(c, "ms"));
}

json_t *fleet_device_view(const json_t *groups, const char *series)
{
    json_t *view = json_pack("{s:[], s:[], s:[], s:[]}", "devices", "points", "winners",
                             "crossovers");
    json_t *points = json_object_get(view, "points"), *winners = json_object_get(view, "winners");
    json_t *index = json_object(), *windex = json_object(); /* key -> position */
    json_t *techniques = json_object();
    size_t g, i;
    json_t *grp, *row;
    json_array_foreach(groups, g, grp) {
        const char *cls = json_string_value(json_object_get(grp, "class"));
        const json_t *sweep = json_object_get(grp, "sweep");
        const char *s = series ? series : charts_default_series(json_object_get(grp, "device"));
        json_t *verdict = sweep_verdict_json(sweep, s);
        json_array_append_new(json_object_get(view, "devices"),
                              json_pack("{s:s, s:s, s:O, s:O}", "class", cls, "series", s,
                                        "partial", json_object_get(verdict, "partial"),
                                        "against_reference",
                                        json_object_get(verdict, "against_reference")));
        json_t *x;
        json_array_foreach(json_object_get(verdict, "crossovers"), i, x) {
            json_t *cx = json_deep_copy(x);
            json_object_set_new(cx, "device", json_string(cls));
            json_array_append_new(json_object_get(view, "crossovers"), cx);
        }
        json_decref(verdict);
        json_array_foreach(json_object_get(sweep, "points"), i, row) {
            char *key = point_key(row, true), *wkey = point_key(row, false);
            if (!key || !wkey) {
                free(key);
                free(wkey);
                continue;
            }
            json_object_set_new(techniques, json_string_value(json_object_get(row, "technique"))
                                                ? json_string_value(json_object_get(row, "technique"))
                                                : "?",
                                json_true());
            json_t *pos = json_object_get(index, key);
            if (!pos) {
                pos = json_integer((json_int_t)json_array_size(points));
                json_object_set_new(index, key, pos);
                json_array_append_new(points, json_pack("{s:O, s:O, s:{}}", "technique",
                                                        json_object_get(row, "technique"), "values",
                                                        json_object_get(row, "values"),
                                                        "by_device"));
            }
            json_t *pt = json_array_get(points, (size_t)json_integer_value(pos));
            json_object_set_new(json_object_get(pt, "by_device"), cls, cell(row, s));
            /* The fastest technique where the other values are the same. */
            json_t *wpos = json_object_get(windex, wkey);
            if (!wpos) {
                wpos = json_integer((json_int_t)json_array_size(winners));
                json_object_set_new(windex, wkey, wpos);
                json_t *values = json_deep_copy(json_object_get(row, "values"));
                json_object_del(values, "technique");
                json_array_append_new(winners, json_pack("{s:o, s:{}}", "where", values,
                                                         "by_device"));
            }
            json_t *w = json_object_get(json_array_get(winners, (size_t)json_integer_value(wpos)),
                                        "by_device");
            json_t *c = cell(row, s), *best = json_object_get(w, cls);
            json_object_set(c, "technique", json_object_get(row, "technique"));
            if (!json_object_get(c, "ms") || strcmp(json_string_value(json_object_get(row, "status")), "done")) {
                json_decref(c);
            } else if (!best) {
                json_object_set_new(w, cls, json_pack("{s:o, s:[]}", "fastest", c, "others"));
            } else {
                json_t *f = json_object_get(best, "fastest");
                if (json_number_value(json_object_get(c, "ms")) <
                    json_number_value(json_object_get(f, "ms"))) {
                    json_array_append(json_object_get(best, "others"), f);
                    json_object_set_new(best, "fastest", c);
                } else {
                    json_array_append_new(json_object_get(best, "others"), c);
                }
            }
            free(key);
            free(wkey);
        }
    }
    /* A win is distinguishable when the fastest's interval ends below every
     * other's; otherwise it names those it is tied with. */
    json_t *w;
    json_array_foreach(winners, i, w) {
        const char *cls;
        json_t *b;
        json_object_foreach(json_object_get(w, "by_device"), cls, b) {
            json_t *f = json_object_get(b, "fastest"), *o, *tied = json_array();
            size_t k;
            json_array_foreach(json_object_get(b, "others"), k, o)
                if (!(ci_edge(f, 1) < ci_edge(o, 0)))
                    json_array_append(tied, json_object_get(o, "technique"));
            json_object_set_new(b, "distinguishable", json_boolean(json_array_size(tied) == 0 &&
                                                                   json_array_size(json_object_get(b, "others"))));
            json_object_set_new(b, "tied_with", tied);
            json_object_del(b, "others");
        }
    }
    /* Winners mean something only between techniques. */
    if (json_object_size(techniques) < 2)
        json_array_clear(winners);
    json_decref(index);
    json_decref(windex);
    json_decref(techniques);
    return view;
}

void fleet_view_print(FILE *f, const json_t *view)
{
    json_t *devices = json_object_get(view, "devices"), *d;
    size_t i, k;
    fprintf(f, "%-44s", "point");
    json_array_foreach(devices, k, d) {
        char head[64];
        snprintf(head, sizeof(head), "%s %s", json_string_value(json_object_get(d, "class")),
                 json_string_value(json_object_get(d, "series")));
        fprintf(f, "  %-30s", head);
    }
    fputc('\n', f);
    json_t *p;
    json_array_foreach(json_object_get(view, "points"), i, p) {
        char where[200], name[260];
        where_text(json_object_get(p, "values"), where, sizeof(where));
        snprintf(name, sizeof(name), "%s %s", json_string_value(json_object_get(p, "technique")),
                 where);
        fprintf(f, "%-44s", name);
        json_array_foreach(devices, k, d) {
            json_t *c = json_object_get(json_object_get(p, "by_device"),
                                        json_string_value(json_object_get(d, "class")));
            char text[64];
            if (!c)
                snprintf(text, sizeof(text), "-");
            else if (!json_object_get(c, "ms"))
                snprintf(text, sizeof(text), "%s", json_string_value(json_object_get(c, "status")));
            else if (json_is_number(json_object_get(c, RK_WORST_SSIM)))
                snprintf(text, sizeof(text), "%.4f ms  SSIM %.6f%s",
                         json_number_value(json_object_get(c, "ms")),
                         json_number_value(json_object_get(c, RK_WORST_SSIM)),
                         json_integer_value(json_object_get(c, RK_PDIFF_FAILED_CAPTURES)) ? " pd!" : "");
            else
                snprintf(text, sizeof(text), "%.4f ms", json_number_value(json_object_get(c, "ms")));
            fprintf(f, "  %-30s", text);
        }
        fputc('\n', f);
    }
    json_t *winners = json_object_get(view, "winners"), *w;
    if (json_array_size(winners)) {
        fprintf(f, "\nFastest technique where the other values are equal\n%-44s", "where");
        json_array_foreach(devices, k, d)
            fprintf(f, "  %-30s", json_string_value(json_object_get(d, "class")));
        fputc('\n', f);
        json_array_foreach(winners, i, w) {
            char where[200];
            where_text(json_object_get(w, "where"), where, sizeof(where));
            fprintf(f, "%-44s", where);
            json_array_foreach(devices, k, d) {
                json_t *b = json_object_get(json_object_get(w, "by_device"),
                                            json_string_value(json_object_get(d, "class")));
                json_t *fa = json_object_get(b, "fastest");
                char text[96];
                if (!fa)
                    snprintf(text, sizeof(text), "-");
                else
                    snprintf(text, sizeof(text), "%s %.4f%s",
                             json_string_value(json_object_get(fa, "technique")),
                             json_number_value(json_object_get(fa, "ms")),
                             json_is_true(json_object_get(b, "distinguishable")) ? ""
                             : json_array_size(json_object_get(b, "tied_with")) ? " (tied)" : "");
                fprintf(f, "  %-30s", text);
            }
            fputc('\n', f);
        }
    }
    json_t *xs = json_object_get(view, "crossovers"), *x;
    if (json_array_size(xs)) {
        fputs("\nCrossovers\n", f);
        json_array_foreach(xs, i, x) {
            json_t *bt = json_object_get(x, "between");
            fprintf(f, "%s: %s is faster below %s = %.4g, %s above it (between %.4g and %.4g%s)\n",
                    json_string_value(json_object_get(x, "device")),
                    json_string_value(json_object_get(x, "faster_below")),
                    json_string_value(json_object_get(x, "param")),
                    json_number_value(json_object_get(x, "at")),
                    json_string_value(json_object_get(x, "faster_above")),
                    json_number_value(json_array_get(bt, 0)), json_number_value(json_array_get(bt, 1)),
                    json_is_true(json_object_get(x, "distinguishable"))
                        ? "" : "; not distinguishable at this noise");
        }
    } else if (json_array_size(winners)) {
        fputs("\nCrossovers: none on any device along the first numeric swept field.\n", f);
    }
    json_array_foreach(devices, k, d)
        if (json_is_true(json_object_get(d, "partial")))
            fprintf(f, "\n%s: partial, the figures cover the points that ran.\n",
                    json_string_value(json_object_get(d, "class")));
}
