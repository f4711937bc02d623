/* The fleet's device view (client/fleet_view.c) on hand-made tables: each
 * point's time and quality per device, the fastest technique where the
 * other values are equal (distinguishable only when its interval ends below
 * every other's), crossovers per device, missing points kept apart, and no
 * winners when only one technique ran. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/fleet.h"
#include "tests/unit/check.h"

static json_t *row(const char *tech, int lights, double ms, double lo, double hi, const char *status)
{
    json_t *r = json_pack("{s:{s:s, s:i}, s:s, s:s, s:s, s:f}", "values", "technique", tech,
                          "scene.lights", lights, "technique", tech, "status", status, "job", "x",
                          "worst_ssim", 0.9995);
    if (!strcmp(status, "done"))
        json_object_set_new(r, "frame_ms",
                            json_pack("{s:f, s:[f, f], s:s}", "median", ms, "ci95", lo, hi, "over",
                                      "frames"));
    return r;
}

static json_t *group(const char *cls, json_t *points)
{
    return json_pack("{s:s, s:{s:s}, s:{s:s, s:s, s:{s:i, s:i}, s:o}}", "class", cls, "device",
                     "gl_renderer", "llvmpipe (LLVM 15)", "sweep", "kind", "vary", "status",
                     "done", "progress", "points_done", 4, "points_total", 4, "points", points);
}

static json_t *winner(const json_t *view, int lights, const char *cls)
{
    size_t i;
    json_t *w;
    json_array_foreach(json_object_get(view, "winners"), i, w)
        if (json_integer_value(json_object_get(json_object_get(w, "where"), "scene.lights")) == lights)
            return json_object_get(json_object_get(w, "by_device"), cls);
    return NULL;
}

int main(void)
{
    /* Device a: clustered wins from 64 lights, clearly. Device b: forward
     * is faster at 8 lights but tied with clustered; clustered wins at 64. */
    json_t *groups = json_array();
    json_array_append_new(groups, group("a", json_pack("[o, o, o, o]",
        row("forward", 8, 1.0, 0.9, 1.1, "done"), row("forward", 64, 4.0, 3.9, 4.1, "done"),
        row("clustered", 8, 1.5, 1.4, 1.6, "done"), row("clustered", 64, 2.0, 1.9, 2.1, "done"))));
    json_array_append_new(groups, group("b", json_pack("[o, o, o, o]",
        row("forward", 8, 1.0, 0.8, 1.3, "done"), row("forward", 64, 3.0, 2.9, 3.1, "done"),
        row("clustered", 8, 1.1, 1.0, 1.2, "done"), row("clustered", 64, 1.0, 0.9, 1.1, "missing"))));
    json_t *view = fleet_device_view(groups, NULL);
    CHECK(json_array_size(json_object_get(view, "devices")) == 2);
    CHECK(json_array_size(json_object_get(view, "points")) == 4);
    json_t *p0 = json_array_get(json_object_get(view, "points"), 0);
    CHECK(json_number_value(json_object_get(json_object_get(json_object_get(p0, "by_device"), "b"),
                                            "ms")) == 1.0);
    json_t *dev0 = json_array_get(json_object_get(view, "devices"), 0);
    CHECK(!strcmp(json_string_value(json_object_get(dev0, "series")), "frame_ms"));
    json_t *a8 = winner(view, 8, "a"), *a64 = winner(view, 64, "a");
    json_t *b8 = winner(view, 8, "b"), *b64 = winner(view, 64, "b");
    CHECK(a8 && !strcmp(json_string_value(json_object_get(json_object_get(a8, "fastest"), "technique")), "forward"));
    CHECK(a8 && json_is_true(json_object_get(a8, "distinguishable")));
    CHECK(a64 && !strcmp(json_string_value(json_object_get(json_object_get(a64, "fastest"), "technique")), "clustered"));
    CHECK(b8 && !strcmp(json_string_value(json_object_get(json_object_get(b8, "fastest"), "technique")), "forward"));
    CHECK(b8 && json_is_false(json_object_get(b8, "distinguishable")) &&
          json_array_size(json_object_get(b8, "tied_with")) == 1);
    /* A missing point never wins: on b at 64 lights forward is the only one that ran. */
    CHECK(b64 && !strcmp(json_string_value(json_object_get(json_object_get(b64, "fastest"), "technique")), "forward"));
    /* Device a's crossover between 8 and 64 lights, distinguishable, named by device. */
    size_t i;
    json_t *x;
    int on_a = 0;
    json_array_foreach(json_object_get(view, "crossovers"), i, x)
        if (!strcmp(json_string_value(json_object_get(x, "device")), "a")) {
            on_a++;
            /* forward is the sweep's reference here, and named so. */
            CHECK(!strncmp(json_string_value(json_object_get(x, "faster_below")), "forward", 7));
            CHECK(!strcmp(json_string_value(json_object_get(x, "faster_above")), "clustered"));
            CHECK(json_is_true(json_object_get(x, "distinguishable")));
        }
    CHECK(on_a == 1);
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    fleet_view_print(f, view);
    fclose(f);
    CHECK(text && strstr(text, "Fastest technique") && strstr(text, "a: forward (reference) is faster below"));
    CHECK(text && strstr(text, "forward 1.0000 (tied)"));
    free(text);
    json_decref(view);
    json_decref(groups);

    /* One technique: nothing to win between. */
    groups = json_array();
    json_array_append_new(groups, group("a", json_pack("[o, o]", row("osl", 8, 1.0, 0.9, 1.1, "done"),
                                                       row("osl", 64, 2.0, 1.9, 2.1, "done"))));
    view = fleet_device_view(groups, "frame_ms");
    CHECK(json_array_size(json_object_get(view, "winners")) == 0);
    json_decref(view);
    json_decref(groups);
    return check_finish("test_fleet");
}
