/* A workload's history: which specs are one measurement, and the changes
 * between points that the gate's rule flags (daemon/reports/history.h). */
#include <string.h>

#include "daemon/reports/history.h"
#include "tests/unit/check.h"

static bool is_technique(void *ctx, const char *key)
{
    (void)ctx;
    return !strcmp(key, "forward") || !strcmp(key, "osl");
}

static bool same(const char *a, const char *b)
{
    json_t *ja = json_loads(a, 0, NULL), *jb = json_loads(b, 0, NULL);
    bool r = history_same_workload(ja, jb, is_technique, NULL);
    json_decref(ja);
    json_decref(jb);
    return r;
}

static json_t *changes(const char *points)
{
    json_t *p = json_loads(points, 0, NULL);
    json_t *c = history_changes(p, HISTORY_MIN_EFFECT);
    json_decref(p);
    return c;
}

int main(void)
{
    const char *base = "{\"technique\":\"osl\",\"frames\":300,\"osl\":{\"async_distance\":20},"
                       "\"scene\":{\"width\":1080,\"lights\":10},\"labels\":{\"commit\":\"a\"}}";
    /* What is not timed does not part workloads: labels, the reference and
     * its options, metrics, captures; numbers compare by value. */
    CHECK(same(base, "{\"technique\":\"osl\",\"frames\":300.0,\"osl\":{\"async_distance\":20},"
                     "\"scene\":{\"lights\":10,\"width\":1080},\"labels\":{\"commit\":\"b\"},"
                     "\"reference\":\"forward\",\"forward\":{\"x\":1},\"capture_interval\":100,"
                     "\"metrics\":{\"ssim\":true}}"));
    /* What is timed does. */
    CHECK(!same(base, "{\"technique\":\"osl\",\"frames\":301,\"osl\":{\"async_distance\":20},"
                      "\"scene\":{\"width\":1080,\"lights\":10}}"));
    CHECK(!same(base, "{\"technique\":\"osl\",\"frames\":300,\"osl\":{\"async_distance\":5},"
                      "\"scene\":{\"width\":1080,\"lights\":10}}"));
    CHECK(!same(base, "{\"technique\":\"osl\",\"frames\":300,\"osl\":{\"async_distance\":20},"
                      "\"scene\":{\"width\":1080,\"lights\":10,\"dynamic\":true}}"));
    CHECK(!same(base, "{\"technique\":\"forward\",\"frames\":300,\"scene\":{\"width\":1080,\"lights\":10}}"));
    CHECK(history_ignored_field("labels", false) && !history_ignored_field("scene", false) &&
          history_ignored_field("forward", true));

    /* A slowdown of 20% whose intervals separate: flagged as the gate's
     * regression; a 3% one is under the minimum effect; overlapping
     * intervals are not a change; a noisy point is left out, and the next
     * is compared with the last quiet one. */
    json_t *c = changes("[{\"id\":\"1\",\"median\":10,\"ci95\":[9.8,10.2]},"
                        "{\"id\":\"2\",\"median\":12,\"ci95\":[11.8,12.2]},"
                        "{\"id\":\"3\",\"median\":12.36,\"ci95\":[12.3,12.4]},"
                        "{\"id\":\"4\",\"median\":20,\"ci95\":[19,21],\"noisy\":true},"
                        "{\"id\":\"5\",\"median\":12.5,\"ci95\":[11,14]},"
                        "{\"id\":\"6\",\"median\":9,\"ci95\":[8.9,9.1]}]");
    CHECK(json_array_size(c) == 2);
    json_t *first = json_array_get(c, 0), *second = json_array_get(c, 1);
    CHECK(!strcmp(json_string_value(json_object_get(first, "from")), "1") &&
          !strcmp(json_string_value(json_object_get(first, "to")), "2") &&
          !strcmp(json_string_value(json_object_get(first, "change")), "slower"));
    CHECK_NEAR(json_real_value(json_object_get(first, "ratio")), 1.2, 1e-9);
    CHECK_NEAR(json_real_value(json_array_get(json_object_get(first, "ratio_ci"), 0)), 11.8 / 10.2, 1e-9);
    CHECK(!strcmp(json_string_value(json_object_get(second, "from")), "5") &&
          !strcmp(json_string_value(json_object_get(second, "to")), "6") &&
          !strcmp(json_string_value(json_object_get(second, "change")), "faster"));
    json_decref(c);
    /* Points without an interval are skipped, never divided by zero. */
    c = changes("[{\"id\":\"1\",\"median\":10},{\"id\":\"2\",\"median\":20,\"ci95\":[0,21]}]");
    CHECK(json_array_size(c) == 0);
    json_decref(c);
    return check_finish("test_history");
}
