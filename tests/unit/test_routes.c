/* The URL space: which resource a path names, its id and sub-resource, and
 * the methods each takes. */
#include <stdlib.h>
#include <string.h>

#include "daemon/api/routes.h"
#include "tests/unit/check.h"

static enum route_kind kind_of(const char *url, struct route *r)
{
    route_parse(url, r);
    return r->kind;
}

int main(void)
{
    struct route r;
    CHECK(kind_of("/healthz", &r) == ROUTE_HEALTHZ);
    CHECK(kind_of("/metrics", &r) == ROUTE_METRICS);
    CHECK(kind_of("/v1/info", &r) == ROUTE_INFO);
    CHECK(kind_of("/v1/jobs", &r) == ROUTE_JOBS && kind_of("/v1/jobs/", &r) == ROUTE_JOBS);
    CHECK(kind_of("/v1/jobs/20260101-000000-0001", &r) == ROUTE_JOB &&
          strcmp(r.id, "20260101-000000-0001") == 0);
    CHECK(kind_of("/v1/jobs/1/frames/100.png", &r) == ROUTE_JOB_IMAGE && r.frame == 100 &&
          r.image == JOB_IMAGE_FRAME && strcmp(job_image_kind(r.image)->prefix, "frame") == 0);
    CHECK(kind_of("/v1/jobs/1/flip/7.png", &r) == ROUTE_JOB_IMAGE && r.image == JOB_IMAGE_FLIP);
    CHECK(kind_of("/v1/jobs/1/heatmap/7.png", &r) == ROUTE_JOB_IMAGE && r.image == JOB_IMAGE_HEATMAP);
    CHECK(kind_of("/v1/jobs/1/timings.csv", &r) == ROUTE_JOB_TIMINGS);
    CHECK(kind_of("/v1/jobs/1/report.html", &r) == ROUTE_JOB_REPORT);
    CHECK(kind_of("/v1/jobs/1/charts/distribution.svg", &r) == ROUTE_JOB_CHART &&
          strcmp(r.chart, "distribution") == 0 && !r.chart_png);
    CHECK(kind_of("/v1/sweeps", &r) == ROUTE_SWEEPS && kind_of("/v1/sweeps/", &r) == ROUTE_SWEEPS);
    CHECK(kind_of("/v1/sweeps/5/charts/speed_accuracy.png", &r) == ROUTE_SWEEP_CHART && r.chart_png);
    CHECK(kind_of("/v1/sweeps/5/report.html", &r) == ROUTE_SWEEP_REPORT);
    CHECK(kind_of("/v1/jobs/1/pdiff/100.png", &r) == ROUTE_JOB_PDIFF && r.frame == 100);
    CHECK(kind_of("/v1/jobs/1/pdiff/x.png", &r) == ROUTE_NONE && strcmp(r.field, "frame") == 0);
    CHECK(kind_of("/v1/jobs/1/history", &r) == ROUTE_JOB_HISTORY && strcmp(r.id, "1") == 0);
    CHECK(kind_of("/v1/sweeps/5/verdict", &r) == ROUTE_SWEEP_VERDICT && strcmp(r.id, "5") == 0);
    /* The dashboard: / and /ui/ are its index; any other /ui/ path is looked up. */
    CHECK(kind_of("/", &r) == ROUTE_UI && strcmp(r.ui, "/ui/index.html") == 0);
    CHECK(kind_of("/ui/", &r) == ROUTE_UI && strcmp(r.ui, "/ui/index.html") == 0);
    CHECK(kind_of("/ui/app.js", &r) == ROUTE_UI && strcmp(r.ui, "/ui/app.js") == 0);
    CHECK(kind_of("/ui/0123456789012345678901234567890123456789012345678901234567890.js", &r) ==
          ROUTE_NONE);
    {
        const char *ui_allow, *ui_rule;
        CHECK(!route_method_ok(ROUTE_UI, "POST", &ui_allow, &ui_rule) &&
              strcmp(ui_allow, "GET, HEAD") == 0);
    }

    /* The raw target: an encoded NUL anywhere, or a query of more than
     * ROUTE_MAX_QUERY_ARGS arguments, is refused naming it. */
    size_t args;
    const char *field = NULL, *why = NULL;
    CHECK(route_check_target("/v1/jobs?a=1&b=2", &args, &field, &why) && args == 2);
    CHECK(route_check_target("/v1/jobs?", &args, &field, &why) && args == 0);
    CHECK(route_check_target("/v1/jobs/1/frames/1.png%2500", &args, &field, &why));
    CHECK(!route_check_target("/v1/jobs/1/frames/1.png%00.txt", &args, &field, &why) &&
          strcmp(field, "url") == 0 && why);
    CHECK(!route_check_target("/v1/jobs?label.a=%00", &args, &field, &why) &&
          strcmp(field, "url") == 0);
    char many[1024] = "/v1/jobs?a";
    for (int i = 0; i < ROUTE_MAX_QUERY_ARGS; i++)
        strcat(many, "&a");
    CHECK(!route_check_target(many, &args, &field, &why) && strcmp(field, "query") == 0 &&
          args == ROUTE_MAX_QUERY_ARGS + 1);
    many[strlen(many) - 2] = '\0';
    CHECK(route_check_target(many, &args, &field, &why) && args == ROUTE_MAX_QUERY_ARGS);

    /* Refusals name what is wrong. */
    CHECK(kind_of("/v1/jobs/../../etc/passwd", &r) == ROUTE_NONE && strcmp(r.field, "id") == 0);
    CHECK(kind_of("/v1/jobs/1/frames/0.png", &r) == ROUTE_NONE && strcmp(r.field, "frame") == 0);
    CHECK(kind_of("/v1/jobs/1/frames/-1.png", &r) == ROUTE_NONE);
    CHECK(kind_of("/v1/jobs/1/frames/ 5.png", &r) == ROUTE_NONE);
    CHECK(kind_of("/v1/jobs/1/frames/1234567890.png", &r) == ROUTE_NONE);
    CHECK(kind_of("/v1/jobs/1/frames/5.png.png", &r) == ROUTE_NONE);
    CHECK(kind_of("/v1/jobs/1/charts/../x.svg", &r) == ROUTE_NONE && strcmp(r.field, "chart") == 0);
    CHECK(kind_of("/v1/jobs/1/unknown", &r) == ROUTE_NONE && strcmp(r.field, "url") == 0);
    CHECK(kind_of("/v1/jobs/123456789012345678901234", &r) == ROUTE_NONE);
    CHECK(kind_of("/v1/nothing", &r) == ROUTE_NONE && strcmp(r.message, "no such route") == 0);
    CHECK(kind_of("", &r) == ROUTE_NONE);

    const char *allow, *rule;
    CHECK(route_method_ok(ROUTE_JOBS, "POST", &allow, &rule));
    CHECK(route_method_ok(ROUTE_JOB, "HEAD", &allow, &rule));
    CHECK(!route_method_ok(ROUTE_JOBS, "PUT", &allow, &rule) && strstr(allow, "POST"));
    CHECK(!route_method_ok(ROUTE_INFO, "DELETE", &allow, &rule) && strcmp(allow, "GET, HEAD") == 0);
    CHECK(!route_method_ok(ROUTE_HEALTHZ, "POST", &allow, &rule));
    /* Assets: one path segment, its rules left to the handler (a 400). */
    CHECK(kind_of("/v1/assets", &r) == ROUTE_ASSETS && kind_of("/v1/assets/", &r) == ROUTE_ASSETS);
    CHECK(kind_of("/v1/assets/scene.glb", &r) == ROUTE_ASSET && strcmp(r.asset, "scene.glb") == 0 &&
          !r.asset_too_long);
    CHECK(kind_of("/v1/assets/..", &r) == ROUTE_ASSET && strcmp(r.asset, "..") == 0);
    CHECK(kind_of("/v1/assets/a/b.glb", &r) == ROUTE_NONE && strcmp(r.field, "url") == 0);
    char long_asset[200];
    snprintf(long_asset, sizeof(long_asset), "/v1/assets/%0150d", 0);
    CHECK(kind_of(long_asset, &r) == ROUTE_ASSET && r.asset_too_long &&
          strlen(r.asset) == ROUTE_ASSET_NAME_MAX);
    CHECK(route_method_ok(ROUTE_ASSET, "PUT", &allow, &rule) &&
          route_method_ok(ROUTE_ASSET, "DELETE", &allow, &rule));
    CHECK(!route_method_ok(ROUTE_ASSET, "POST", &allow, &rule) && strstr(allow, "PUT"));
    CHECK(!route_method_ok(ROUTE_ASSETS, "PUT", &allow, &rule));
    CHECK(!route_method_ok(ROUTE_JOB, "PUT", &allow, &rule));
    CHECK(strcmp(route_label(ROUTE_ASSET), "/v1/assets/{name}") == 0);
    CHECK(strcmp(route_label(ROUTE_JOB), "/v1/jobs/{id}") == 0);
    CHECK(strcmp(route_label((enum route_kind)99), "other") == 0);

    /* Every URL the API hands out routes back to what it names. */
    char url[ROUTE_URL_MAX];
    struct route back;
    route_job_url("20261122-091703-0001", url);
    CHECK(route_parse(url, &back) && back.kind == ROUTE_JOB &&
          strcmp(back.id, "20261122-091703-0001") == 0);
    route_sweep_url("20261122-091703-0002", url);
    CHECK(route_parse(url, &back) && back.kind == ROUTE_SWEEP &&
          strcmp(back.id, "20261122-091703-0002") == 0);
    route_timings_url("20261122-091703-0001", url);
    CHECK(route_parse(url, &back) && back.kind == ROUTE_JOB_TIMINGS &&
          strcmp(back.id, "20261122-091703-0001") == 0);
    for (int image = 0; image < JOB_IMAGE_COUNT; image++) {
        route_image_url("1-2", (enum job_image)image, 999999999, url);
        CHECK(route_parse(url, &back) && back.kind == ROUTE_JOB_IMAGE &&
              back.image == (enum job_image)image && back.frame == 999999999 &&
              strcmp(back.id, "1-2") == 0);
    }
    /* A list's next page: each key and value percent-encoded, in order. */
    const char *keys[] = {"label.branch", "since", "limit", "cursor"};
    const char *values[] = {"feature/a b&c=d", "2026-11-21T10:00:00.000Z", "100", "1-2"};
    char *next = route_list_url(ROUTE_JOBS, 4, keys, values);
    CHECK(next && !strcmp(next, "/v1/jobs?label.branch=feature%2Fa%20b%26c%3Dd&since=2026-11-21T10%3A"
                                "00%3A00.000Z&limit=100&cursor=1-2"));
    free(next);
    next = route_list_url(ROUTE_SWEEPS, 0, keys, values);
    CHECK(next && !strcmp(next, "/v1/sweeps"));
    free(next);
    const char *utf8[] = {"\xc3\xa9"};
    next = route_list_url(ROUTE_SWEEPS, 1, keys, utf8);
    CHECK(next && !strcmp(next, "/v1/sweeps?label.branch=%C3%A9"));
    free(next);
    return check_finish("test_routes");
}
