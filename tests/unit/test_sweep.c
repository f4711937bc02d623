#include <math.h>
#include <string.h>

#include "daemon/spec/sweep_spec.h"
#include "tests/unit/catalog_fixture.h"
#include "tests/unit/check.h"

#define techniques fixture_catalog()

static int calls;
static double boundary;

/* A synthetic monotone criterion: holds up to the boundary. */
static int below_boundary(double v, void *ctx)
{
    (void)ctx;
    calls++;
    return v <= boundary;
}

static int abort_third(double v, void *ctx)
{
    (void)v, (void)ctx;
    return ++calls >= 3 ? -1 : (calls == 1);
}

static bool parse(const char *text, struct sweep_spec *s, struct job_error *err)
{
    json_t *body = json_loads(text, 0, NULL);
    bool ok = body && sweep_spec_parse(body, techniques, s, err);
    json_decref(body);
    return ok;
}

static void rejects(const char *text, const char *field)
{
    struct sweep_spec s;
    struct job_error err;
    bool ok = parse(text, &s, &err);
    CHECK(!ok && strcmp(err.field, field) == 0);
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  for %s: got '%s' (%s)\n", text, err.field, err.message);
    sweep_spec_finish(&s);
}

/* The thesis preset as posted: its four points (forward and OSL, still and
 * moving lights) each a valid job with the thesis's settings at this size. */
static void thesis_points(const char *text, int width, int height, int resolution, int frames,
                          int warmup, int repeat)
{
    struct sweep_spec s;
    struct job_error err;
    bool ok = parse(text, &s, &err);
    CHECK(ok && s.thesis && s.kind == SWEEP_VARY && s.npoints == 4);
    if (!ok || s.npoints != 4) {
        fprintf(stderr, "  for %s: %s %s\n", text, err.field, err.message);
        sweep_spec_finish(&s);
        return;
    }
    int seen = 0;
    for (size_t i = 0; i < 4; i++) {
        json_t *values, *job = sweep_point_job(&s, i, &values);
        json_t *scene = json_object_get(job, "scene"), *osl = json_object_get(job, "osl");
        const char *technique = json_string_value(json_object_get(job, "technique"));
        bool moving = json_is_true(json_object_get(scene, "dynamic"));
        seen |= 1 << (2 * !strcmp(technique, "osl") + moving);
        CHECK(json_integer_value(json_object_get(scene, "width")) == width &&
              json_integer_value(json_object_get(scene, "height")) == height &&
              !strcmp(json_string_value(json_object_get(scene, "preset")), "grid") &&
              json_integer_value(json_object_get(scene, "lights")) == 10);
        CHECK(json_integer_value(json_object_get(osl, "resolution")) == resolution &&
              json_number_value(json_object_get(osl, "async_distance")) == 20 &&
              !strcmp(json_string_value(json_object_get(osl, "visibility")), "all"));
        CHECK(json_number_value(json_object_get(
                  json_object_get(json_object_get(job, "metrics"), "pdiff"), "fov")) == 22.6 &&
              !strcmp(json_string_value(json_object_get(job, "reference")), "forward"));
        CHECK(json_integer_value(json_object_get(job, "frames")) == frames &&
              json_integer_value(json_object_get(job, "warmup_frames")) == warmup &&
              json_integer_value(json_object_get(job, "repeat")) == repeat);
        struct job_spec spec;
        CHECK(job_spec_parse(job, techniques, &spec, &err));
        json_decref(job);
        json_decref(values);
    }
    CHECK(seen == 15); /* each technique with still and moving lights */
    sweep_spec_finish(&s);
}

int main(void)
{
    struct bisect_result r;
    /* Integer parameter: finds the boundary exactly, in about log2 probes. */
    boundary = 37;
    calls = 0;
    sweep_bisect(0, 100, true, 20, below_boundary, NULL, &r);
    CHECK(r.outcome == BISECT_BOUNDARY && r.value == 37 && r.first_failing == 38);
    CHECK(r.probes == calls && r.probes <= 2 + 7);
    /* Real-valued: within 1/1000 of the range. */
    boundary = 0.4242;
    sweep_bisect(0, 1, false, 40, below_boundary, NULL, &r);
    CHECK(r.outcome == BISECT_BOUNDARY && r.value <= 0.4242 && 0.4242 - r.value <= 0.001);
    /* Limited probes still give a value that holds. */
    boundary = 37;
    sweep_bisect(0, 100, true, 4, below_boundary, NULL, &r);
    CHECK(r.probes == 4 && r.value <= 37 && r.first_failing > 37);
    /* Holds everywhere, fails everywhere, aborted. */
    boundary = 1000;
    sweep_bisect(0, 100, true, 10, below_boundary, NULL, &r);
    CHECK(r.outcome == BISECT_HOLDS_EVERYWHERE && r.value == 100 && r.probes == 2);
    boundary = -1;
    sweep_bisect(0, 100, true, 10, below_boundary, NULL, &r);
    CHECK(r.outcome == BISECT_FAILS_EVERYWHERE && r.probes == 1);
    calls = 0;
    sweep_bisect(0, 100, true, 10, abort_third, NULL, &r);
    CHECK(r.outcome == BISECT_ABORTED);

    /* A two-parameter grid, row-major, with point defaults filled in. */
    struct sweep_spec s;
    struct job_error err;
    CHECK(parse("{\"base\":{\"technique\":\"osl\",\"frames\":20},"
                "\"vary\":{\"async_distance\":[0,5,10],\"scene.lights\":[4,8]}}", &s, &err));
    /* 6 grid points, then forward timed once per light count. */
    CHECK(s.kind == SWEEP_VARY && s.ngrid == 6 && s.npoints == 8 && s.nparams == 2);
    json_t *values, *job = sweep_point_job(&s, 3, &values);
    CHECK(json_integer_value(json_object_get(values, "async_distance")) == 5);
    CHECK(json_integer_value(json_object_get(values, "scene.lights")) == 8);
    /* values keep vary's order: the charts' x axis is the first. */
    {
        void *it = json_object_iter(values);
        CHECK(it && !strcmp(json_object_iter_key(it), "async_distance"));
    }
    CHECK(json_integer_value(json_object_get(json_object_get(job, "scene"), "lights")) == 8);
    CHECK(strcmp(json_string_value(json_object_get(job, "reference")), "forward") == 0);
    CHECK(json_integer_value(json_object_get(job, "capture_interval")) == 20);
    json_decref(values);
    json_decref(job);
    job = sweep_point_job(&s, 7, &values);
    CHECK(!strcmp(json_string_value(json_object_get(values, "technique")), "forward") &&
          json_integer_value(json_object_get(values, "scene.lights")) == 8 &&
          json_object_size(values) == 2);
    CHECK(!strcmp(json_string_value(json_object_get(job, "technique")), "forward") &&
          !json_object_get(job, "reference") &&
          json_integer_value(json_object_get(job, "capture_interval")) == 0 &&
          json_integer_value(json_object_get(json_object_get(job, "scene"), "lights")) == 8);
    json_decref(values);
    json_decref(job);
    sweep_spec_finish(&s);
    /* No workload varied: one reference point. The reference among the
     * techniques, or time_reference false: none. */
    CHECK(parse("{\"base\":{\"technique\":\"osl\"},\"vary\":{\"async_distance\":[0,5]}}",
                &s, &err) && s.npoints == 3);
    sweep_spec_finish(&s);
    CHECK(parse("{\"base\":{},\"vary\":{\"technique\":[\"osl\",\"forward\"],"
                "\"scene.lights\":[1,2]}}", &s, &err) && s.npoints == 4);
    sweep_spec_finish(&s);
    CHECK(parse("{\"base\":{\"technique\":\"osl\"},\"vary\":{\"async_distance\":[0,5]},"
                "\"time_reference\":false}", &s, &err) && s.npoints == 2);
    sweep_spec_finish(&s);
    CHECK(parse("{\"base\":{\"technique\":\"osl\",\"reference\":\"unlit\","
                "\"capture_interval\":5},\"vary\":{\"async_distance\":[0]}}", &s, &err) &&
          s.npoints == 2);
    job = sweep_point_job(&s, 1, &values);
    CHECK(!strcmp(json_string_value(json_object_get(job, "technique")), "unlit"));
    json_decref(values);
    json_decref(job);
    sweep_spec_finish(&s);
    rejects("{\"base\":{},\"vary\":{\"frames\":[1]},\"time_reference\":1}", "time_reference");

    /* async_distance is an alias of osl.async_distance: a sweep varies
     * either, whichever spelling its base uses, and a point never gives it
     * twice. */
    CHECK(parse("{\"base\":{\"technique\":\"osl\",\"osl\":{\"async_distance\":20}},"
                "\"vary\":{\"async_distance\":[0,5]}}", &s, &err));
    job = sweep_point_job(&s, 1, &values);
    CHECK(json_integer_value(json_object_get(job, "async_distance")) == 5 &&
          !json_object_get(json_object_get(job, "osl"), "async_distance"));
    json_decref(values);
    json_decref(job);
    sweep_spec_finish(&s);
    CHECK(parse("{\"base\":{\"technique\":\"osl\",\"async_distance\":20},"
                "\"vary\":{\"osl.async_distance\":[0,5]}}", &s, &err));
    job = sweep_point_job(&s, 1, &values);
    CHECK(json_integer_value(json_object_get(json_object_get(job, "osl"), "async_distance")) == 5 &&
          !json_object_get(job, "async_distance"));
    json_decref(values);
    json_decref(job);
    sweep_spec_finish(&s);
    {
        json_t *sweepable = sweep_params_json(techniques);
        CHECK(!strcmp(json_string_value(json_object_get(sweepable, "async_distance")), "number") &&
              !strcmp(json_string_value(json_object_get(sweepable, "osl.async_distance")),
                      "number"));
        json_decref(sweepable);
    }

    /* find: numeric parameter, criterion parsed, probes built. */
    CHECK(parse("{\"base\":{\"technique\":\"osl\"},\"find\":{\"param\":\"async_distance\","
                "\"from\":0,\"to\":100,\"while\":\"ssim_min >= 0.95\"}}", &s, &err));
    CHECK(s.kind == SWEEP_FIND && !s.integer && s.criterion == CRITERION_SSIM_MIN && s.threshold == 0.95);
    json_t *result = json_pack("{s:{s:{s:f}}}", "quality", "worst_ssim_min", "value", 0.97);
    CHECK(sweep_criterion_holds(&s, result));
    json_decref(result);
    result = json_pack("{s:{s:{s:f}}}", "quality", "worst_ssim_min", "value", 0.90);
    CHECK(!sweep_criterion_holds(&s, result));
    json_decref(result);
    sweep_spec_finish(&s);
    /* no_overflow: light lists and the shadow atlas; a result without
     * either record cannot be judged (it would hold everywhere). */
    CHECK(parse("{\"base\":{},\"find\":{\"param\":"
                "\"scene.lights\",\"from\":1,\"to\":4096,\"while\":\"no_overflow\"}}", &s, &err));
    CHECK(s.criterion == CRITERION_NO_OVERFLOW);
    {
        static const char *const cases[][2] = {
            {"{\"technique\":\"clustered_deferred\",\"clustered_deferred\":{\"overflow\":{\"frames\":0}}}", "1"},
            {"{\"technique\":\"clustered_deferred\",\"clustered_deferred\":{\"overflow\":{\"frames\":3}}}", "0"},
            {"{\"technique\":\"forward\",\"clustered_deferred\":{\"overflow\":{\"frames\":3}}}", "1"},
            {"{\"technique\":\"forward\",\"shadows\":{\"overflow\":{\"frames_with_drops\":1}}}", "0"},
            {"{\"technique\":\"forward\",\"shadows\":{\"overflow\":{\"frames_with_drops\":0}}}", "1"},
            {"{\"technique\":\"forward\"}", "1"},
        };
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
            json_t *r = json_loads(cases[i][0], 0, NULL);
            CHECK(r && sweep_criterion_holds(&s, r) == (cases[i][1][0] == '1'));
            json_decref(r);
        }
        for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
            json_t *r = json_loads(cases[i][0], 0, NULL);
            const char *why = sweep_criterion_unjudged(&s, r);
            CHECK(i == 2 || i == 5 ? why && strstr(why, "look.shadows") : !why);
            json_decref(r);
        }
        json_int_t lists, shadows;
        json_t *r = json_loads(cases[3][0], 0, NULL);
        sweep_overflow_frames(r, &lists, &shadows);
        CHECK(lists == -1 && shadows == 1);
        json_decref(r);
    }
    sweep_spec_finish(&s);
    CHECK(parse("{\"base\":{},\"find\":{\"param\":\"scene.lights\",\"from\":1,\"to\":64,"
                "\"while\":\"stable\"}}", &s, &err) && s.integer);
    job = sweep_probe_job(&s, 17);
    CHECK(json_object_get(job, "repeat") != NULL);
    json_decref(job);
    sweep_spec_finish(&s);

    /* Bad input names the field. */
    /* Values valid alone, refused together: 400 at submission, naming the
     * first bad combination (point 2 of 4: frames=2, capture_interval=5). */
    {
        struct sweep_spec c;
        struct job_error e;
        CHECK(!parse("{\"base\":{},\"vary\":{\"frames\":[2,10],\"capture_interval\":[1,5]}}",
                     &c, &e));
        CHECK(strcmp(e.field, "vary") == 0);
        CHECK(strstr(e.message, "point 2 (frames=2, capture_interval=5)") != NULL);
        CHECK(strstr(e.message, "capture_interval") != NULL);
        sweep_spec_finish(&c);
        /* A key cut at 40 bytes inside a character still names the field. */
        CHECK(!parse("{\"base\":{},\"vary\":{\"aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\u00e9\":[1]}}",
                     &c, &e));
        CHECK(strncmp(e.field, "vary.", 5) == 0 && strlen(e.field) == 5 + 39);
        sweep_spec_finish(&c);
    }
    rejects("[]", "body");
    rejects("{\"base\":{},\"vary\":{\"async_distance\":[1]},\"find\":{}}", "find");
    rejects("{\"base\":{}}", "vary");
    rejects("{\"base\":{\"frames\":0},\"vary\":{\"frames\":[1]}}", "base");
    rejects("{\"base\":{},\"vary\":{\"scene.lightz\":[1,2]}}", "vary.scene.lightz");
    rejects("{\"base\":{},\"vary\":{\"async_distance\":[]}}", "vary.async_distance");
    rejects("{\"base\":{},\"vary\":{\"async_distance\":[0,\"far\"]}}", "vary.async_distance[1]");
    rejects("{\"base\":{},\"vary\":{\"technique\":[\"forward\",\"sponza\"]}}", "vary.technique[1]");
    rejects("{\"base\":{},\"vary\":{\"scene.lights\":[1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17],"
            "\"async_distance\":[0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15]}}", "vary");
    rejects("{\"base\":{},\"vary\":{\"a\":[1],\"b\":[2],\"c\":[3]}}", "vary");
    rejects("{\"base\":{},\"find\":{\"param\":\"technique\",\"from\":0,\"to\":1,\"while\":\"pdiff_pass\"}}", "find.param");
    rejects("{\"base\":{},\"find\":{\"param\":\"async_distance\",\"from\":5,\"to\":1,\"while\":\"pdiff_pass\"}}", "find.to");
    rejects("{\"base\":{},\"find\":{\"param\":\"scene.lights\",\"from\":0.5,\"to\":9,\"while\":\"pdiff_pass\"}}", "find.from");
    rejects("{\"base\":{},\"find\":{\"param\":\"async_distance\",\"from\":0,\"to\":9,\"while\":\"pretty\"}}", "find.while");
    rejects("{\"base\":{},\"find\":{\"param\":\"scene.lights\",\"from\":0,\"to\":70000,\"while\":\"stable\"}}", "find.to");
    rejects("{\"base\":{},\"vary\":{\"frames\":[1]},\"extra\":1}", "extra");

    /* find.while's threshold: a plain decimal in the metric's range, and
     * the message names the rule broken (issue 26). */
    static const struct {
        const char *crit, *rule; /* rule: a word of the message; NULL: accepted */
        double x;
    } whiles[] = {
        {"ssim_min >= 0.95", NULL, 0.95}, {"ssim_min>=1", NULL, 1}, {"ssim_min >= -1", NULL, -1},
        {"flip_max <= 5e-2", NULL, 0.05}, {"flip_max <=0.1", NULL, 0.1},
        {"ssim_min >= 2", "from -1 to 1", 0}, {"flip_max <= -0.1", "from 0 to 1", 0},
        {"ssim_min >= 0x1p-1", "decimal", 0}, {"ssim_min >= inf", "decimal", 0},
        {"ssim_min >= nan", "decimal", 0}, {"ssim_min >= 1e-400", "closer to 0", 0},
        {"ssim_min >= 1e-310", "closer to 0", 0}, {"ssim_min >= 0.9x", "decimal", 0},
        {"ssim_min >= ", "decimal", 0}, {"ssim_min >= .", "decimal", 0},
        {"ssim_max >= 0.9", "one of", 0}, {"flip_max >= 0.1", "one of", 0},
        /* The mean SSIM (the thesis's figure) beside its smallest window. */
        {"ssim >= 0.99", NULL, 0.99}, {"ssim>=-0.5", NULL, -0.5}, {"ssim >= 1.5", "from -1 to 1", 0},
        {"ssim >= nan", "decimal", 0}, {"ssim >= 0x1p-1", "decimal", 0},
        {"ssim >= 1e-400", "closer to 0", 0}, {"ssim <= 0.9", "one of", 0},
        {"ssim > 0.9", "one of", 0}, {"ssim_mean >= 0.9", "one of", 0},
        /* flicker_max needs base.temporal, which this base lacks. */
        {"flicker_max <= 0.01", "base.temporal", 0},
    };
    for (size_t i = 0; i < sizeof(whiles) / sizeof(whiles[0]); i++) {
        char text[256];
        snprintf(text, sizeof(text), "{\"base\":{},\"find\":{\"param\":\"async_distance\","
                 "\"from\":0,\"to\":9,\"while\":\"%s\"}}", whiles[i].crit);
        struct sweep_spec s;
        struct job_error err;
        bool ok = parse(text, &s, &err);
        if (whiles[i].rule)
            CHECK(!ok && strcmp(err.field, "find.while") == 0 && strstr(err.message, whiles[i].rule));
        else
            CHECK(ok && s.threshold == whiles[i].x);
        if (ok != !whiles[i].rule || (!ok && !strstr(err.message, whiles[i].rule)))
            fprintf(stderr, "  for %s: %s\n", whiles[i].crit, ok ? "accepted" : err.message);
        sweep_spec_finish(&s);
    }
    /* flicker_max over a base with temporal frames: strict as the others. */
    static const struct {
        const char *crit, *rule;
        double x;
    } flickers[] = {
        {"flicker_max <= 0.01", NULL, 0.01}, {"flicker_max<=1", NULL, 1},
        {"flicker_max <= 0", NULL, 0}, {"flicker_max <= 1.5", "from 0 to 1", 0},
        {"flicker_max <= -0.1", "from 0 to 1", 0}, {"flicker_max <= inf", "decimal", 0},
        {"flicker_max >= 0.1", "one of", 0}, {"flicker <= 0.1", "one of", 0},
    };
    for (size_t i = 0; i < sizeof(flickers) / sizeof(flickers[0]); i++) {
        char text[300];
        snprintf(text, sizeof(text), "{\"base\":{\"technique\":\"osl\",\"temporal\":"
                 "{\"frames\":4}},\"find\":{\"param\":\"scene.light_speed\",\"from\":0,"
                 "\"to\":9,\"while\":\"%s\"}}", flickers[i].crit);
        struct sweep_spec s;
        struct job_error err;
        bool ok = parse(text, &s, &err);
        if (flickers[i].rule)
            CHECK(!ok && strcmp(err.field, "find.while") == 0 && strstr(err.message, flickers[i].rule));
        else
            CHECK(ok && s.criterion == CRITERION_FLICKER_MAX && s.threshold == flickers[i].x);
        if (ok != !flickers[i].rule || (!ok && !strstr(err.message, flickers[i].rule)))
            fprintf(stderr, "  for %s: %s\n", flickers[i].crit, ok ? "accepted" : err.message);
        sweep_spec_finish(&s);
    }
    /* The criteria read the worst capture's mean SSIM and flicker. */
    {
        struct sweep_spec s;
        struct job_error err;
        CHECK(parse("{\"base\":{},\"find\":{\"param\":\"scene.light_speed\",\"from\":0,"
                    "\"to\":9,\"while\":\"ssim >= 0.98\"}}", &s, &err));
        CHECK(s.criterion == CRITERION_SSIM_MEAN);
        json_t *r = json_pack("{s:{s:{s:f}, s:{s:f}}}", "quality", "worst_ssim", "value", 0.985,
                              "worst_ssim_min", "value", 0.5);
        CHECK(sweep_criterion_holds(&s, r)); /* the mean, not the smallest window */
        json_decref(r);
        r = json_pack("{s:{s:{s:f}, s:{s:f}}}", "quality", "worst_ssim", "value", 0.97,
                      "worst_ssim_min", "value", 0.99);
        CHECK(!sweep_criterion_holds(&s, r));
        json_decref(r);
        r = json_pack("{s:{}}", "quality");
        CHECK(!sweep_criterion_holds(&s, r));
        json_decref(r);
        sweep_spec_finish(&s);
        CHECK(parse("{\"base\":{\"temporal\":{\"frames\":3}},\"find\":{\"param\":"
                    "\"scene.light_speed\",\"from\":0,\"to\":9,\"while\":\"flicker_max <= 0.02\"}}",
                    &s, &err));
        r = json_pack("{s:{s:{s:f, s:i}}}", "quality", "worst_flicker", "value", 0.01, "frame", 5);
        CHECK(sweep_criterion_holds(&s, r));
        json_decref(r);
        r = json_pack("{s:{s:{s:f, s:i}}}", "quality", "worst_flicker", "value", 0.03, "frame", 5);
        CHECK(!sweep_criterion_holds(&s, r));
        json_decref(r);
        r = json_pack("{s:{}}", "quality"); /* no flicker measured: does not hold */
        CHECK(!sweep_criterion_holds(&s, r));
        json_decref(r);
        /* Probes carry the base's temporal frames. */
        json_t *probe = sweep_probe_job(&s, 4.5);
        CHECK(json_integer_value(json_object_get(json_object_get(probe, "temporal"), "frames")) == 3);
        json_decref(probe);
        sweep_spec_finish(&s);
    }
    /* reference.supersample and temporal.frames are sweep axes; over the
     * shorthand "reference": "forward" the name is kept. */
    {
        struct sweep_spec s;
        struct job_error err;
        CHECK(parse("{\"base\":{\"technique\":\"unlit\",\"reference\":\"forward\","
                    "\"frames\":4,\"capture_interval\":4},\"vary\":{\"reference.supersample\":[1,2,4]}}", &s, &err));
        CHECK(s.ngrid == 3);
        json_t *values, *job = sweep_point_job(&s, 2, &values);
        json_t *ref = json_object_get(job, "reference");
        CHECK(json_is_object(ref) &&
              !strcmp(json_string_value(json_object_get(ref, "technique")), "forward") &&
              json_integer_value(json_object_get(ref, "supersample")) == 4);
        struct job_spec spec;
        CHECK(job_spec_parse(job, techniques, &spec, &err) && spec.reference_supersample == 4 &&
              !strcmp(spec.reference, "forward"));
        json_decref(job);
        json_decref(values);
        sweep_spec_finish(&s);
        /* Over a base without a reference: the baseline's, supersampled. */
        CHECK(parse("{\"base\":{\"technique\":\"unlit\",\"frames\":4},"
                    "\"find\":{\"param\":\"reference.supersample\",\"from\":1,\"to\":4,"
                    "\"while\":\"ssim >= 0.9\"}}", &s, &err));
        job = sweep_probe_job(&s, 2);
        CHECK(job_spec_parse(job, techniques, &spec, &err) && spec.reference_supersample == 2 &&
              !strcmp(spec.reference, "forward"));
        json_decref(job);
        sweep_spec_finish(&s);
        json_t *sweepable = sweep_params_json(techniques);
        CHECK(json_object_get(sweepable, "reference.supersample") &&
              json_object_get(sweepable, "temporal.frames"));
        json_decref(sweepable);
    }
    rejects("{\"base\":{\"reference\":\"forward\",\"capture_interval\":5},\"vary\":{\"reference.supersample\":[2,5]}}",
            "vary.reference.supersample[1]");
    rejects("{\"base\":{},\"vary\":{\"temporal.frames\":[1]}}", "vary.temporal.frames[0]");
    /* A base is checked as its points run (the baseline as reference,
     * captures at the last frame), so temporal needs no more than that. */
    {
        struct sweep_spec s;
        struct job_error err;
        CHECK(parse("{\"base\":{\"technique\":\"osl\",\"frames\":6,\"temporal\":{\"frames\":3}},"
                    "\"vary\":{\"scene.lights\":[2,4]}}", &s, &err));
        json_t *values, *job = sweep_point_job(&s, 1, &values);
        struct job_spec spec;
        CHECK(job_spec_parse(job, techniques, &spec, &err) && spec.temporal_frames == 3 &&
              !strcmp(spec.reference, "forward") && spec.capture_interval == 6);
        json_decref(job);
        json_decref(values);
        sweep_spec_finish(&s);
    }
    /* The thesis preset: its own settings at 1080x720, or smaller at a
     * scale that shrinks the frame and OSL's tiles alike. */
    thesis_points("{\"preset\":\"thesis\"}", 1080, 720, 256, 300, 10, 5);
    thesis_points("{\"preset\":\"thesis\",\"scale\":1,\"frames\":60,\"repeat\":3}", 1080, 720,
                  256, 60, 10, 3);
    thesis_points("{\"preset\":\"thesis\",\"scale\":0.5}", 540, 360, 128, 300, 10, 5);
    thesis_points("{\"preset\":\"thesis\",\"scale\":0.25,\"frames\":1,\"warmup_frames\":0,"
                  "\"repeat\":2}", 270, 180, 64, 1, 0, 2);
    thesis_points("{\"preset\":\"thesis\",\"scale\":0.125}", 135, 90, 32, 300, 10, 5);
    rejects("{\"preset\":\"thesis\",\"scale\":0.3}", "scale");
    rejects("{\"preset\":\"thesis\",\"scale\":2}", "scale");
    rejects("{\"preset\":\"thesis\",\"scale\":0.0625}", "scale");
    rejects("{\"preset\":\"thesis\",\"scale\":\"0.5\"}", "scale");
    rejects("{\"preset\":\"thesis\",\"scale\":null}", "scale");
    rejects("{\"preset\":\"thesis\",\"width\":270}", "width");
    {
        struct thesis_size size;
        struct job_error err;
        json_t *body = json_pack("{s:s}", "preset", "thesis");
        CHECK(sweep_thesis_size(body, &size, &err) && size.scale == 1 && size.width == 1080 &&
              size.height == 720 && size.osl_resolution == 256);
        json_object_set_new(body, "scale", json_real(0.25));
        CHECK(sweep_thesis_size(body, &size, &err) && size.scale == 0.25 && size.width == 270 &&
              size.height == 180 && size.osl_resolution == 64);
        json_decref(body);
    }
    return check_finish("test_sweep");
}
