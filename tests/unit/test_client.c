/* The client's JUnit: names from a job's content (the same for the same
 * job, whatever its id or labels; different when what is measured
 * differs), durations and properties in the XML; and the hand-written trend
 * chart (points, intervals never below zero, a log axis across decades). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/junit.h"
#include "client/trend.h"
#include "common/fsutil.h"
#include "tests/unit/check.h"

static size_t count(const char *hay, const char *needle)
{
    size_t n = 0;
    for (const char *p = hay; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

int main(void)
{
    json_t *osl = json_loads(
        "{\"technique\":\"osl\",\"frames\":20,\"warmup_frames\":5,\"capture_interval\":10,"
        "\"async_distance\":20,\"scene\":{\"preset\":\"grid\",\"lights\":10,\"dynamic\":true,"
        "\"width\":160,\"height\":120,\"sphere_segments\":32,\"light_speed\":1.0},"
        "\"osl\":{\"resolution\":\"auto\",\"texel_density\":1.0,\"reshade\":\"touched\"},"
        "\"repeat\":1,\"reference\":\"forward\",\"labels\":{\"commit\":\"abc\"}}", 0, NULL);
    char name[320], other[320];
    junit_job_name(osl, name, sizeof(name));
    static const char osl_prefix[] = "osl async_distance=20 osl(reshade=touched resolution=auto "
                                     "texel_density=1) grid 160x120 10 lights moving #";
    CHECK(strncmp(name, osl_prefix, strlen(osl_prefix)) == 0 &&
          strlen(name) == strlen(osl_prefix) + 8 + strlen(", 20 frames") &&
          strstr(name, ", 20 frames"));
    printf("name: %s\n", name);
    /* The daemon states async_distance in OSL's options too: named once. */
    json_object_set_new(json_object_get(osl, "osl"), "async_distance", json_integer(20));
    junit_job_name(osl, other, sizeof(other));
    CHECK(strcmp(name, other) == 0);
    /* Labels, repeat, captures and the reference leave the name alone. */
    json_object_set_new(osl, "labels", json_pack("{s:s}", "commit", "def"));
    json_object_set_new(osl, "repeat", json_integer(5));
    json_object_set_new(osl, "capture_interval", json_integer(0));
    junit_job_name(osl, other, sizeof(other));
    CHECK(strcmp(name, other) == 0);
    /* What is measured changes it. */
    json_object_set_new(json_object_get(osl, "scene"), "lights", json_integer(80));
    junit_job_name(osl, other, sizeof(other));
    CHECK(strcmp(name, other) != 0 && strstr(other, "80 lights"));
    /* So does a scene field that is not spelled out (it is in the hash), and the look. */
    junit_job_name(osl, name, sizeof(name));
    json_object_set_new(json_object_get(osl, "scene"), "light_speed", json_real(2.0));
    junit_job_name(osl, other, sizeof(other));
    CHECK(strcmp(name, other) != 0);
    json_object_set_new(osl, "look", json_pack("{s:s}", "lighting", "blinn_phong"));
    junit_job_name(osl, name, sizeof(name));
    CHECK(strcmp(name, other) != 0);
    /* However long the options, the name stays within 240 characters. */
    json_t *many = json_object();
    for (int i = 0; i < 40; i++) {
        char k[16];
        snprintf(k, sizeof(k), "option%02d", i);
        json_object_set_new(many, k, json_integer(i + 1000));
    }
    json_object_set_new(osl, "osl", many);
    junit_job_name(osl, other, sizeof(other));
    CHECK(strlen(other) <= 240);
    json_decref(osl);
    /* Forward leaves OSL's options and a zero async distance out. */
    json_t *fwd = json_loads("{\"technique\":\"forward\",\"frames\":40,\"async_distance\":0,"
                             "\"scene\":{\"preset\":\"grid\",\"lights\":10,\"dynamic\":false,"
                             "\"width\":160,\"height\":120},\"osl\":{\"resolution\":256},"
                             "\"forward\":{}}", 0,
                             NULL);
    junit_job_name(fwd, name, sizeof(name));
    CHECK(strncmp(name, "forward grid 160x120 10 lights still #", 38) == 0 &&
          strcmp(name + 38 + 8, ", 40 frames") == 0);
    json_decref(fwd);

    /* The XML: durations, properties, failures, escaping. */
    struct junit j;
    junit_init(&j);
    struct junit_case *a = junit_add(&j, "shadebench.forward", "forward <grid>: job");
    a->time_s = 1.25;
    junit_prop_num(a, "frame_ms_median", 12.5);
    junit_prop_str(a, "gl_renderer", "llvmpipe \"x\"");
    struct junit_case *b = junit_add(&j, "shadebench.forward", "forward: median frame_ms");
    junit_fail(b, "slower by %.1f%%", 12.0);
    junit_fail(b, "second reason");
    CHECK(junit_failures(&j) == 1 && strcmp(b->failure, "slower by 12.0%; second reason") == 0);
    const char *path = "test_client_junit.xml";
    CHECK(junit_write(&j, path, "suite & co", 3.5));
    size_t len;
    char *xml = fs_read_file(path, 1 << 20, &len);
    CHECK(xml && strstr(xml, "time=\"1.250\"") && strstr(xml, "name=\"forward &lt;grid&gt;: job\""));
    CHECK(xml && strstr(xml, "<property name=\"frame_ms_median\" value=\"12.5\"/>"));
    CHECK(xml && strstr(xml, "value=\"llvmpipe &quot;x&quot;\""));
    CHECK(xml && strstr(xml, "failures=\"1\"") && strstr(xml, "name=\"suite &amp; co\""));
    free(xml);
    remove(path);
    junit_finish(&j);
    junit_finish(NULL);

    /* The trend chart. */
    struct trend_point pts[4] = {
        {.t = 1700000000, .y = 10, .lo = -2, .hi = 22, .series = "forward", .label = "j1"},
        {.t = 1700003600, .y = 11, .lo = 9, .hi = 13, .series = "forward", .label = "j2"},
        {.t = 1700001800, .y = 3, .lo = NAN, .hi = NAN, .series = "unlit", .label = "j3"},
        {.t = 1700007200, .y = 10.5, .lo = 10, .hi = 11, .series = "forward", .label = "j<4>"},
    };
    char *svg = trend_svg(pts, 4, "frame_ms over time", "median frame_ms");
    CHECK(svg && count(svg, "<circle class=\"point\"") == 4);
    CHECK(svg && count(svg, "class=\"interval\"") == 3);
    CHECK(svg && strstr(svg, "data-low=\"0\"") && !strstr(svg, "data-low=\"-")); /* clamped */
    CHECK(svg && strstr(svg, "j&lt;4&gt;") && !strstr(svg, "(log scale)"));
    CHECK(svg && strstr(svg, "data-series=\"unlit\""));
    free(svg);
    CHECK(trend_log_axis(0.5, 80) && !trend_log_axis(5, 40) && !trend_log_axis(0, 100));
    struct trend_point wide[2] = {
        {.t = 1, .y = 0.5, .lo = NAN, .hi = NAN, .series = "unlit"},
        {.t = 2, .y = 900, .lo = NAN, .hi = NAN, .series = "osl"},
    };
    svg = trend_svg(wide, 2, "t", "ms");
    CHECK(svg && strstr(svg, "(log scale)"));
    free(svg);
    svg = trend_svg(NULL, 0, "t", "ms");
    CHECK(svg && strstr(svg, "no matching jobs"));
    free(svg);
    return check_finish("test_client");
}
