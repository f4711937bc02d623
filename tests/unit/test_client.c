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
#include "client/suggest.h"
#include "client/trend.h"
#include "client/workload.h"
#include "common/fsutil.h"
#include "tests/unit/check.h"

static size_t count(const char *hay, const char *needle)
{
    size_t n = 0;
    for (const char *p = hay; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

/* An undecided check is never a plain pass: <skipped> with its reason, or
 * a failure of type "inconclusive" when asked to fail; counted apart from
 * real failures (which decide the exit status first). */
static void test_inconclusive_junit(void)
{
    struct junit j;
    junit_init(&j);
    struct junit_case *job = junit_add(&j, "shadebench.forward", "forward: job");
    struct junit_case *gate = junit_add(&j, "shadebench.forward", "forward: median frame_ms");
    junit_inconclusive(gate, false, "inconclusive: interval reaches +30%%; 3 of 8 runs noisy");
    CHECK(junit_failures(&j) == 0 && junit_real_failures(&j) == 0 && junit_undecided(&j) == 1);
    const char *path = "test_client_inconclusive.xml";
    CHECK(junit_write(&j, path, "s", 1.0));
    size_t len;
    char *xml = fs_read_file(path, 1 << 20, &len);
    CHECK(xml && strstr(xml, "<skipped message=\"inconclusive: interval reaches +30%; 3 of 8 runs "
                             "noisy\"/>") && strstr(xml, "skipped=\"1\"") &&
          !strstr(xml, "<failure"));
    free(xml);
    /* Asked to fail: a failure of its own type, still not a real failure. */
    struct junit_case *gate2 = junit_add(&j, "shadebench.forward", "again");
    junit_inconclusive(gate2, true, "inconclusive (--fail-inconclusive): too noisy");
    CHECK(junit_failures(&j) == 1 && junit_real_failures(&j) == 0 && junit_undecided(&j) == 2);
    CHECK(junit_write(&j, path, "s", 1.0));
    xml = fs_read_file(path, 1 << 20, &len);
    CHECK(xml && strstr(xml, "<failure type=\"inconclusive\" message=\"inconclusive "
                             "(--fail-inconclusive): too noisy\"/>"));
    free(xml);
    junit_fail(job, JUNIT_JOB_FAILED, "job failed");
    CHECK(junit_real_failures(&j) == 1);
    /* A check that judged nothing: skipped, never a pass, and not an
     * undecided timing check either (no exit status of its own). */
    struct junit_case *q = junit_add(&j, "shadebench.forward", "forward: frame 10 quality");
    junit_skip(q, "SKIP", "no reference technique: nothing judged");
    CHECK(junit_judged_nothing(&j) == 1 && junit_undecided(&j) == 2 && junit_real_failures(&j) == 1);
    CHECK(junit_write(&j, path, "s", 1.0));
    xml = fs_read_file(path, 1 << 20, &len);
    CHECK(xml && strstr(xml, "<skipped message=\"no reference technique: nothing judged\"/>") &&
          strstr(xml, "<failure type=\"job_failed\" message=\"job failed\"/>") &&
          strstr(xml, "skipped=\"2\""));
    free(xml);
    /* The log names the outcome, in colour only when asked. */
    FILE *f = fopen(path, "w+");
    junit_print(&j, f, false);
    rewind(f);
    char buf[4096];
    size_t got = fread(buf, 1, sizeof(buf) - 1, f);
    buf[got] = '\0';
    fclose(f);
    CHECK(strstr(buf, "INCONCLUSIVE forward: median frame_ms") && strstr(buf, "not decided: ") &&
          strstr(buf, "FAIL forward: job") && strstr(buf, "failure (job_failed): job failed") &&
          strstr(buf, "\nSKIP forward: frame 10 quality") && strstr(buf, "not judged: no reference") &&
          !strstr(buf, "\033["));
    f = fopen(path, "w+");
    junit_print(&j, f, true);
    rewind(f);
    got = fread(buf, 1, sizeof(buf) - 1, f);
    buf[got] = '\0';
    fclose(f);
    CHECK(strstr(buf, "\033[1;31mFAIL\033[0m forward: job") &&
          strstr(buf, "\033[1;33mINCONCLUSIVE\033[0m forward: median") &&
          strstr(buf, "\033[1;33mSKIP\033[0m forward: frame 10"));
    remove(path);
    /* Names are unique within a file: a second case of the same name is
     * numbered, not merged with the first by a CI system. */
    struct junit_case *dup = junit_add(&j, "shadebench.forward", "forward: job");
    CHECK(dup && !strcmp(dup->name, "forward: job (2)"));
    junit_finish(&j);
}

/* Names from the spec as the user wrote it: fields the file does not name
 * are left out (no "0x0 0 lights"), so a default the daemon adds later
 * renames nothing. */
static void test_names_as_written(void)
{
    json_t *spec = json_loads("{\"technique\":\"forward\",\"frames\":20,"
                              "\"scene\":{\"width\":160,\"height\":120}}", 0, NULL);
    char name[320], again[320];
    junit_job_name(spec, name, sizeof(name));
    CHECK(strncmp(name, "forward 160x120 #", 17) == 0 && strstr(name, ", 20 frames") &&
          !strstr(name, "lights") && !strstr(name, "0x0"));
    /* The daemon's filled-in spec names more; the file's name is the one CI
     * keeps, whatever the daemon adds. */
    json_t *filled = json_deep_copy(spec);
    json_object_set_new(json_object_get(filled, "scene"), "lights", json_integer(10));
    junit_job_name(filled, again, sizeof(again));
    CHECK(strcmp(name, again) != 0);
    junit_job_name(spec, again, sizeof(again));
    CHECK(strcmp(name, again) == 0);
    json_decref(filled);
    json_decref(spec);
    spec = json_loads("{\"technique\":\"unlit\"}", 0, NULL);
    junit_job_name(spec, name, sizeof(name));
    CHECK(strncmp(name, "unlit #", 7) == 0 && !strstr(name, "frames"));
    json_decref(spec);
}

/* Workload identity: labels, repeat, captures, the reference and other
 * techniques' options leave it alone; size, lights, frames, warm-up, look
 * and the technique's own options change it; 20 and 20.0 are one value. */
static void test_workload_identity(void)
{
    json_t *a = json_loads("{\"technique\":\"osl\",\"frames\":20,\"warmup_frames\":5,"
                           "\"scene\":{\"width\":160,\"height\":120,\"lights\":10},"
                           "\"osl\":{\"resolution\":256},\"labels\":{\"commit\":\"a\"},"
                           "\"repeat\":1,\"reference\":\"forward\",\"forward\":{},"
                           "\"capture_interval\":10}", 0, NULL);
    json_t *b = json_deep_copy(a);
    char ka[96], kb[96], da[240], db[240];
    json_object_set_new(b, "labels", json_pack("{s:s}", "commit", "b"));
    json_object_set_new(b, "repeat", json_integer(5));
    json_object_set_new(b, "capture_interval", json_integer(0));
    json_object_del(b, "reference");
    json_object_del(b, "forward");
    json_object_set_new(json_object_get(b, "scene"), "lights", json_real(10.0));
    workload_key(a, ka, sizeof(ka));
    workload_key(b, kb, sizeof(kb));
    CHECK(strcmp(ka, kb) == 0 && strncmp(ka, "osl#", 4) == 0 && strlen(ka) == 4 + 16);
    static const char *const changes[] = {
        "{\"scene\":{\"width\":320}}", "{\"scene\":{\"lights\":14}}", "{\"frames\":40}",
        "{\"warmup_frames\":0}", "{\"look\":{\"hdr\":\"rgba16f\"}}",
        "{\"osl\":{\"resolution\":128}}"};
    for (size_t i = 0; i < sizeof(changes) / sizeof(changes[0]); i++) {
        json_t *c = json_deep_copy(a), *patch = json_loads(changes[i], 0, NULL);
        const char *k;
        json_t *v;
        json_object_foreach(patch, k, v) {
            if (json_is_object(v) && json_is_object(json_object_get(c, k)))
                json_object_update(json_object_get(c, k), v);
            else
                json_object_set(c, k, v);
        }
        workload_key(c, kb, sizeof(kb));
        CHECK(strcmp(ka, kb) != 0);
        /* The description differs too, even where the name does not spell
         * the field out (warm-up frames). */
        workload_describe(a, da, sizeof(da));
        workload_describe(c, db, sizeof(db));
        CHECK(strcmp(da, db) != 0);
        json_decref(patch);
        json_decref(c);
    }
    /* One hash for the file as written and the spec the daemon echoes: a
     * field at its default (stated, or filled in by the daemon's parser)
     * is the same workload as one left out, and the daemon's whole spec
     * (every default filled in, numbers as reals) hashes as the file does. */
    json_t *stated = json_deep_copy(a);
    json_object_set_new(json_object_get(stated, "scene"), "sphere_segments", json_integer(32));
    json_object_set_new(stated, "msaa", json_integer(1));
    json_object_set_new(stated, "look", json_pack("{s:s}", "tonemap", "none"));
    workload_key(stated, kb, sizeof(kb));
    CHECK(strcmp(ka, kb) == 0);
    json_decref(stated);
    json_t *daemon_spec = json_loads(
        "{\"technique\":\"osl\",\"frames\":20,\"warmup_frames\":5,\"capture_interval\":10,"
        "\"async_distance\":0.0,\"scene\":{\"preset\":\"grid\",\"lights\":10,\"dynamic\":false,"
        "\"width\":160,\"height\":120,\"sphere_segments\":32,\"light_speed\":1.0},"
        "\"look\":{\"lighting\":\"phong\",\"exposure\":1.0,\"post\":[]},"
        "\"osl\":{\"resolution\":256},\"forward\":{},\"repeat\":1,\"reference\":null,"
        "\"timeout_s\":86400.0,\"msaa\":1,\"labels\":{}}", 0, NULL);
    workload_key(daemon_spec, kb, sizeof(kb));
    CHECK(strcmp(ka, kb) == 0);
    json_decref(daemon_spec);
    workload_describe(a, da, sizeof(da));
    static const char prefix[] = "osl osl(resolution=256) grid 160x120 10 lights still #";
    CHECK(strncmp(da, prefix, strlen(prefix)) == 0 &&
          strncmp(da + strlen(prefix), ka + 4, 8) == 0 && strstr(da, ", 20 frames"));
    json_decref(a);
    json_decref(b);
}

static void test_suggest(void)
{
    static const char *const opts[] = {"runs", "max-reruns", "fail-inconclusive", "baseline",
                                       "junit", "max-slowdown", "server", "server-b"};
    size_t n = sizeof(opts) / sizeof(opts[0]);
    CHECK(suggest_nearest("rnus", opts, n) && !strcmp(suggest_nearest("rnus", opts, n), "runs"));
    CHECK(!strcmp(suggest_nearest("run", opts, n), "runs"));
    CHECK(!strcmp(suggest_nearest("max-rerun", opts, n), "max-reruns"));
    CHECK(!strcmp(suggest_nearest("fail-inconclusiv", opts, n), "fail-inconclusive"));
    CHECK(!strcmp(suggest_nearest("basline", opts, n), "baseline"));
    CHECK(suggest_nearest("colour", opts, n) == NULL);
    CHECK(suggest_nearest("max", opts, n) == NULL); /* ambiguous and far */
    CHECK(suggest_distance("ab", "ba") == 1 && suggest_distance("", "abc") == 3 &&
          suggest_distance("kitten", "sitting") == 3);
}

/* Time ticks on round times, labelled exactly: the job at 03:26:06 lies
 * right of the tick labelled 03:26, which is at 03:26:00. */
static void test_time_ticks(void)
{
    double ticks[16], step;
    char labels[16][24];
    /* 2026-11-25 03:25:00 to 03:28:30 UTC */
    double t0 = 1795564800.0 + 3 * 3600 + 25 * 60, t1 = t0 + 210;
    int n = trend_time_ticks(t0, t1, ticks, labels, 16, &step);
    CHECK(n >= 3 && n <= 8 && step == 30);
    for (int i = 0; i < n; i++)
        CHECK(fmod(ticks[i], step) == 0 && ticks[i] >= t0 && ticks[i] <= t1);
    CHECK(!strcmp(labels[0], "03:25:00") && !strcmp(labels[2], "03:26:00"));
    /* Over hours: labels in minutes, each at a whole minute. */
    n = trend_time_ticks(t0, t0 + 5 * 3600, ticks, labels, 16, &step);
    CHECK(n >= 3 && n <= 8 && step == 3600);
    for (int i = 0; i < n; i++)
        CHECK(fmod(ticks[i], 60) == 0 && strlen(labels[i]) == 5 && !strcmp(labels[i] + 2, ":00"));
    /* Over days: dates, at midnight. */
    n = trend_time_ticks(t0, t0 + 20 * 86400, ticks, labels, 16, &step);
    CHECK(n >= 2 && n <= 8 && fmod(step, 86400) == 0);
    for (int i = 0; i < n; i++)
        CHECK(fmod(ticks[i], 86400) == 0 && strlen(labels[i]) == 10);
    /* An odd span (100 s: the old step) gets a round step, not 100 s. */
    n = trend_time_ticks(t0 + 6, t0 + 106, ticks, labels, 16, &step);
    CHECK(step == 15 || step == 30);
}

/* The trend chart: one series per workload with its full name in the
 * legend, noisy runs hollow with the CPU others took, series beyond the
 * eighth counted rather than silently dropped. */
static void test_trend_workloads(void)
{
    struct trend_point pts[12];
    memset(pts, 0, sizeof(pts));
    for (int i = 0; i < 12; i++) {
        pts[i].t = 1795576800.0 + 60 * i;
        pts[i].y = 10 + i;
        pts[i].lo = pts[i].hi = NAN;
        pts[i].other_share = NAN;
        snprintf(pts[i].series, sizeof(pts[i].series), "forward#%016d", i < 4 ? i % 2 : i);
        snprintf(pts[i].name, sizeof(pts[i].name), "forward 320x240 workload %d", i < 4 ? i % 2 : i);
        snprintf(pts[i].label, sizeof(pts[i].label), "job%d", i);
    }
    pts[1].noisy = true;
    pts[1].other_share = 0.79;
    /* Jobs within two seconds still get an axis with ticks. */
    struct trend_point close[2] = {pts[0], pts[1]};
    close[1].t = close[0].t + 1.5;
    char *svg = trend_svg(close, 2, "t", "ms");
    CHECK(svg && count(svg, "class=\"tick\"") >= 3);
    free(svg);
    svg = trend_svg(pts, 4, "t", "ms");
    CHECK(svg && count(svg, "class=\"series\"") == 2 && strstr(svg, "forward 320x240 workload 0") &&
          strstr(svg, "forward 320x240 workload 1"));
    CHECK(svg && count(svg, "data-noisy=\"true\"") == 1 && strstr(svg, "took 79% of the CPU"));
    free(svg);
    svg = trend_svg(pts, 12, "t", "ms");
    /* 2 + 8 workloads: 8 drawn, 2 said to be left out. */
    CHECK(svg && count(svg, "class=\"series\"") == 8 && strstr(svg, "2 more workloads not drawn"));
    free(svg);
}

int main(void)
{
    test_inconclusive_junit();
    test_names_as_written();
    test_workload_identity();
    test_suggest();
    test_time_ticks();
    test_trend_workloads();

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
    junit_fail(b, JUNIT_REGRESSION, "slower by %.1f%%", 12.0);
    junit_fail(b, JUNIT_QUALITY, "second reason");
    CHECK(junit_failures(&j) == 1 && strcmp(b->failure, "slower by 12.0%; second reason") == 0);
    const char *path = "test_client_junit.xml";
    CHECK(junit_write(&j, path, "suite & co", 3.5));
    size_t len;
    char *xml = fs_read_file(path, 1 << 20, &len);
    CHECK(xml && strstr(xml, "time=\"1.250\"") && strstr(xml, "name=\"forward &lt;grid&gt;: job\""));
    CHECK(xml && strstr(xml, "<property name=\"frame_ms_median\" value=\"12.5\"/>"));
    CHECK(xml && strstr(xml, "value=\"llvmpipe &quot;x&quot;\""));
    CHECK(xml && strstr(xml, "failures=\"1\"") && strstr(xml, "name=\"suite &amp; co\""));
    /* The failure's type is its first cause, not the class name. */
    CHECK(xml && strstr(xml, "<failure type=\"regression\" message=\"slower by 12.0%; second reason\"/>"));
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
