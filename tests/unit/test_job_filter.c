/* The job list's filters: arguments parsed with rejections naming them,
 * repeated filters as alternatives, labels, since, and headline figures. */
#include <string.h>

#include "daemon/api/job_filter.h"
#include "tests/unit/check.h"

static json_t *entry(const char *tech, const char *status, const char *created,
                     const char *branch)
{
    json_t *e = json_pack("{s:s, s:s, s:s, s:{}}", "technique", tech, "status", status,
                          "created", created, "labels");
    if (branch)
        json_object_set_new(json_object_get(e, "labels"), "branch", json_string(branch));
    return e;
}

static void rejects(const char *key, const char *value, const char *field)
{
    struct job_filter f;
    struct job_error err;
    job_filter_init(&f);
    bool ok = job_filter_add(&f, key, value, &err);
    CHECK(!ok && strcmp(err.field, field) == 0 && strlen(err.message) > 10);
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  %s=%s: got '%s' (%s)\n", key, value, err.field, err.message);
}

int main(void)
{
    char t[32];
    CHECK(job_filter_parse_time("2026-11-21", t) && !strcmp(t, "2026-11-21T00:00:00.000Z"));
    CHECK(job_filter_parse_time("2026-11-21T10:05", t) && !strcmp(t, "2026-11-21T10:05:00.000Z"));
    CHECK(job_filter_parse_time("2026-11-21T10:05:07.5Z", t) &&
          !strcmp(t, "2026-11-21T10:05:07.500Z"));
    CHECK(job_filter_parse_time("0", t) && !strcmp(t, "1970-01-01T00:00:00.000Z"));
    CHECK(job_filter_parse_time("1700000000", t) && !strcmp(t, "2023-11-14T22:13:20.000Z"));
    CHECK(!job_filter_parse_time("yesterday", t) && !job_filter_parse_time("2026-13-01", t) &&
          !job_filter_parse_time("2026-11-21T10", t) && !job_filter_parse_time("-5", t));

    rejects("techniqe", "forward", "techniqe");
    rejects("status", "finished", "status");
    rejects("since", "last week", "since");
    rejects("label.bad name", "x", "label.bad name");
    rejects("label.", "x", "label.");

    json_t *a = entry("forward", "done", "2026-11-21T10:00:00.000Z", "main");
    json_t *b = entry("osl", "done", "2026-11-22T10:00:00.000Z", "main");
    json_t *c = entry("osl", "failed", "2026-11-23T10:00:00.000Z", "topic");
    json_t *d = entry("unlit", "done", "2026-11-24T10:00:00.000Z", NULL);
    struct job_filter f;
    struct job_error err;

    job_filter_init(&f);
    CHECK(job_filter_match(&f, a) && job_filter_match(&f, d)); /* no filter: everything */

    CHECK(job_filter_add(&f, "technique", "osl", &err));
    CHECK(!job_filter_match(&f, a) && job_filter_match(&f, b) && job_filter_match(&f, c));
    CHECK(job_filter_add(&f, "technique", "forward", &err)); /* alternatives */
    CHECK(job_filter_match(&f, a) && job_filter_match(&f, b) && !job_filter_match(&f, d));
    CHECK(job_filter_add(&f, "status", "done", &err)); /* and */
    CHECK(job_filter_match(&f, a) && job_filter_match(&f, b) && !job_filter_match(&f, c));

    job_filter_init(&f);
    CHECK(job_filter_add(&f, "label.branch", "main", &err));
    CHECK(job_filter_match(&f, a) && job_filter_match(&f, b) && !job_filter_match(&f, c) &&
          !job_filter_match(&f, d));
    CHECK(job_filter_add(&f, "since", "2026-11-22", &err));
    CHECK(!job_filter_match(&f, a) && job_filter_match(&f, b));
    CHECK(job_filter_add(&f, "label.branch", "topic", &err));
    CHECK(job_filter_match(&f, b) && job_filter_match(&f, c) && !job_filter_match(&f, d));

    /* Figures: a single run over frames, a repeated job over runs. */
    json_t *single = json_loads("{\"frame_ms\":{\"median\":12.5,\"median_ci95\":[12,13]},"
                                "\"gpu_ms\":{\"median\":2.0,\"median_ci95\":[1.9,2.1]},"
                                "\"quality\":{\"worst_ssim\":{\"value\":0.99,\"frame\":10}},"
                                "\"device\":{\"gl_renderer\":\"llvmpipe\",\"gl_version\":\"4.5\"}}",
                                0, NULL);
    json_t *fig = job_filter_figures(single);
    CHECK(json_real_value(json_object_get(json_object_get(fig, "frame_ms"), "median")) == 12.5);
    CHECK(!strcmp(json_string_value(json_object_get(json_object_get(fig, "frame_ms"), "over")),
                  "frames"));
    CHECK(json_real_value(json_object_get(fig, "worst_ssim")) == 0.99 &&
          !strcmp(json_string_value(json_object_get(fig, "gl_renderer")), "llvmpipe") &&
          json_integer_value(json_object_get(fig, "runs")) == 1);
    CHECK(!json_object_get(fig, "cpu_ms"));
    json_decref(fig);
    json_t *repeated = json_loads("{\"frame_ms\":{\"median\":12.5},\"repeat\":{\"runs\":3,"
                                  "\"frame_ms\":{\"median\":13.0,\"ci95\":[12.0,14.0]}}}", 0, NULL);
    fig = job_filter_figures(repeated);
    CHECK(json_real_value(json_object_get(json_object_get(fig, "frame_ms"), "median")) == 13.0 &&
          json_integer_value(json_object_get(fig, "runs")) == 3);
    json_decref(fig);
    CHECK(job_filter_figures(NULL) == NULL);

    /* The visitor keeps matching entries, with figures, and frees others. */
    job_filter_init(&f);
    CHECK(job_filter_add(&f, "technique", "forward", &err));
    json_t *kept = job_filter_visit(json_incref(a), single, &f);
    CHECK(kept == a && json_object_get(a, "figures"));
    json_decref(kept);
    CHECK(job_filter_visit(json_incref(b), single, &f) == NULL);
    json_decref(single);
    json_decref(repeated);
    json_decref(a);
    json_decref(b);
    json_decref(c);
    json_decref(d);
    return check_finish("test_job_filter");
}
