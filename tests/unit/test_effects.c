/* The GL-free half of the post effects: look.post parsing through the
 * techniques' option parser (errors naming look.post[i].option), the look's
 * exposure and tone map, reference_look, pass names, the pass budget, blur
 * and SSAO kernels, tone curves, and the sweep side (post options as sweep
 * parameters, the finite criterion). */
#include <math.h>
#include <string.h>

#include "daemon/effects/bloom/bloom_info.h"
#include "daemon/effects/ssao/ssao_info.h"
#include "daemon/effects/toon/toon_info.h"
#include "daemon/spec/job_spec.h"
#include "daemon/lighting/tone_curves.h"
#include "daemon/spec/sweep_spec.h"
#include "tests/unit/catalog_fixture.h"
#include "tests/unit/check.h"

static bool parse(const char *text, struct job_spec *spec, struct job_error *err)
{
    return job_spec_parse_text(text, strlen(text), fixture_catalog(), spec, err);
}

static void rejects(const char *text, const char *field)
{
    struct job_spec spec;
    struct job_error err;
    bool ok = parse(text, &spec, &err);
    CHECK(!ok);
    CHECK(strcmp(err.field, field) == 0);
    CHECK(err.message[0] != '\0');
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  for %s: got field '%s' (%s)\n", text, err.field, err.message);
}

static void sweep_rejects(const char *text, const char *field)
{
    struct sweep_spec s;
    struct job_error err;
    json_t *body = json_loads(text, 0, NULL);
    CHECK(body != NULL);
    bool ok = body && sweep_spec_parse(body, fixture_catalog(), &s, &err);
    CHECK(!ok);
    CHECK(ok || strcmp(err.field, field) == 0);
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  for %s: got field '%s' (%s)\n", text, ok ? "" : err.field,
                ok ? "accepted" : err.message);
    if (ok)
        sweep_spec_finish(&s);
    json_decref(body);
}

static void test_look(void)
{
    struct job_spec spec;
    struct job_error err;
    CHECK(parse("{}", &spec, &err));
    CHECK(spec.look.exposure == 1.0 && spec.look.tonemap == LOOK_TONEMAP_NONE);
    CHECK(spec.look.post.count == 0 && !spec.reference_look_given);
    CHECK(memcmp(&spec.reference_look, &spec.look, sizeof(spec.look)) == 0);

    CHECK(parse("{\"look\": {\"exposure\": 2.5, \"tonemap\": \"aces\", \"post\": [\"bloom\", "
                "{\"toon\": {\"edges\": \"depth_diff\", \"levels\": 3}}, {\"ssao\": {\"samples\": 8}}]}}",
                &spec, &err));
    CHECK(spec.look.exposure == 2.5 && spec.look.tonemap == LOOK_TONEMAP_ACES);
    CHECK(spec.look.post.count == 3);
    const struct bloom_options *b = post_effect_options(&spec.look.post, 0);
    CHECK(spec.look.post.effects[0].effect == effect_find("bloom"));
    CHECK(b->radius == 4 && b->kernel == BLOOM_SEPARABLE && b->threshold == 1.0 &&
          b->intensity == 1.0 && b->downsample == 0);
    const struct toon_options *t = post_effect_options(&spec.look.post, 1);
    CHECK(t->edges == TOON_EDGES_DEPTH_DIFF && t->levels == 3 && t->thickness == 1);
    const struct ssao_options *s = post_effect_options(&spec.look.post, 2);
    CHECK(s->samples == 8 && s->blur && s->bias == 0.025);
    /* The reference renders with the same look unless told otherwise. */
    CHECK(memcmp(&spec.reference_look, &spec.look, sizeof(spec.look)) == 0);

    /* The spec as understood round-trips, effect options included. */
    json_t *j = job_spec_to_json(&spec);
    char *text = json_dumps(j, 0);
    struct job_spec again;
    CHECK(parse(text, &again, &err));
    CHECK(memcmp(&again.look, &spec.look, sizeof(spec.look)) == 0);
    free(text);
    json_decref(j);

    /* reference_look is a whole look read over the defaults. */
    CHECK(parse("{\"look\": {\"post\": [\"bloom\"], \"lighting\": \"blinn_phong\"}, "
                "\"reference\": \"forward\", \"capture_interval\": 60, \"reference_look\": {}}",
                &spec, &err));
    CHECK(spec.reference_look_given && spec.reference_look.post.count == 0);
    CHECK(spec.reference_look.lighting == LOOK_PHONG && spec.look.lighting == LOOK_BLINN_PHONG);
    j = job_spec_to_json(&spec);
    text = json_dumps(j, 0);
    CHECK(parse(text, &again, &err));
    CHECK(again.reference_look_given &&
          memcmp(&again.reference_look, &spec.reference_look, sizeof(spec.look)) == 0);
    free(text);
    json_decref(j);

    /* Bad input names the field. */
    rejects("{\"look\": {\"post\": [\"bloom\", {\"bloom\": {\"radius\": 99}}]}}", "look.post[1].radius");
    rejects("{\"look\": {\"post\": [{\"bloom\": {\"radius\": 1}}]}}", "look.post[0].radius");
    rejects("{\"look\": {\"post\": [{\"bloom\": {\"kernel\": \"3d\"}}]}}", "look.post[0].kernel");
    rejects("{\"look\": {\"post\": [{\"bloom\": {\"radiuss\": 3}}]}}", "look.post[0].radiuss");
    rejects("{\"look\": {\"post\": [\"ssao\", {\"ssao\": {\"samples\": 65}}]}}", "look.post[1].samples");
    rejects("{\"look\": {\"post\": [{\"ssao\": {\"samples\": 3}}]}}", "look.post[0].samples");
    rejects("{\"look\": {\"post\": [{\"ssao\": {\"blur\": 1}}]}}", "look.post[0].blur");
    rejects("{\"look\": {\"post\": [{\"toon\": {\"edges\": \"canny\"}}]}}", "look.post[0].edges");
    rejects("{\"look\": {\"post\": [{\"toon\": {\"thickness\": 0}}]}}", "look.post[0].thickness");
    rejects("{\"look\": {\"post\": [\"blur\"]}}", "look.post[0]");
    rejects("{\"look\": {\"post\": [\"bloom\", 3]}}", "look.post[1]");
    rejects("{\"look\": {\"post\": [{\"bloom\": {}, \"toon\": {}}]}}", "look.post[0]");
    rejects("{\"look\": {\"post\": [{\"blom\": {}}]}}", "look.post[0].blom");
    rejects("{\"look\": {\"post\": [{\"bloom\": 4}]}}", "look.post[0]");
    rejects("{\"look\": {\"post\": \"bloom\"}}", "look.post");
    rejects("{\"look\": {\"post\": [\"toon\",\"toon\",\"toon\",\"toon\",\"toon\",\"toon\",\"toon\","
            "\"toon\",\"toon\"]}}", "look.post");
    /* Three blooms with mip chains need 3 x 6 passes: over the budget of 15. */
    rejects("{\"look\": {\"post\": [{\"bloom\": {\"downsample\": 3}}, {\"bloom\": {\"downsample\": 3}}, "
            "{\"bloom\": {\"downsample\": 3}}]}}", "look.post");
    rejects("{\"look\": {\"exposure\": 0}}", "look.exposure");
    rejects("{\"look\": {\"exposure\": \"bright\"}}", "look.exposure");
    rejects("{\"look\": {\"tonemap\": \"filmic\"}}", "look.tonemap");
    rejects("{\"reference_look\": {}}", "reference_look");
    rejects("{\"reference\": \"forward\", \"capture_interval\": 300, "
            "\"reference_look\": {\"post\": [{\"bloom\": {\"radius\": 40}}]}}",
            "reference_look.post[0].radius");
    rejects("{\"reference\": \"forward\", \"capture_interval\": 300, \"reference_look\": {\"hdr\": 1}}",
            "reference_look.hdr");
}

static void test_passes(void)
{
    struct job_spec spec;
    struct job_error err;
    CHECK(parse("{\"look\": {\"post\": [\"bloom\", {\"bloom\": {\"kernel\": \"2d\", \"downsample\": 2}}, "
                "{\"toon\": {}}, {\"ssao\": {\"blur\": false}}]}}", &spec, &err));
    char names[POST_MAX_PASSES][POST_PASS_NAME_BYTES];
    int n = post_spec_pass_names(&spec.look.post, names, POST_MAX_PASSES);
    static const char *const want[] = {
        "bloom.bright", "bloom.blur_h", "bloom.blur_v", "bloom.composite", "bloom2.bright",
        "bloom2.down", "bloom2.blur", "bloom2.up", "bloom2.composite", "toon.shade", "ssao.ao",
        "ssao.apply"};
    CHECK(n == 12);
    for (int i = 0; i < n && i < 12; i++) {
        CHECK(strcmp(names[i], want[i]) == 0);
        if (strcmp(names[i], want[i]) != 0)
            fprintf(stderr, "  pass %d: %s, wanted %s\n", i, names[i], want[i]);
    }
    /* Counting needs no storage. */
    CHECK(post_spec_pass_names(&spec.look.post, NULL, 0) == 12);

    /* Every registered effect passes its registration checks. */
    char why[256];
    CHECK(effect_infos_check(why, sizeof(why)));

    json_t *info = effect_catalog_json();
    CHECK(json_array_size(info) == 4); /* bloom, toon, ssao, taa */
    json_t *bloom = json_array_get(info, 0);
    CHECK(strcmp(json_string_value(json_object_get(bloom, "name")), "bloom") == 0);
    json_t *radius = json_object_get(json_object_get(bloom, "options"), "radius");
    CHECK(strcmp(json_string_value(json_object_get(radius, "type")), "integer") == 0 &&
          json_number_value(json_object_get(radius, "max")) == 32);
    json_decref(info);
}

static void test_kernels(void)
{
    float w[BLOOM_MAX_RADIUS + 1];
    for (int r = 1; r <= BLOOM_MAX_RADIUS; r++) {
        CHECK(gauss_weights(r, w));
        double sum = w[0];
        for (int i = 1; i <= r; i++) {
            sum += 2.0 * w[i];
            CHECK(w[i] < w[i - 1] && w[i] > 0);
        }
        CHECK_NEAR(sum, 1.0, 1e-6);
    }
    CHECK(!gauss_weights(0, w) && !gauss_weights(33, w));

    float k[SSAO_MAX_SAMPLES][4], again[SSAO_MAX_SAMPLES][4];
    CHECK(ssao_kernel(64, SSAO_SEED, k));
    CHECK(ssao_kernel(64, SSAO_SEED, again));
    CHECK(memcmp(k, again, sizeof(k)) == 0); /* a fixed seed: the same kernel every run */
    double mean_len_first = 0, mean_len_last = 0;
    for (int i = 0; i < 64; i++) {
        double len = sqrt(k[i][0] * k[i][0] + k[i][1] * k[i][1] + k[i][2] * k[i][2]);
        CHECK(len <= 1.0 + 1e-6 && len > 0 && k[i][2] > 0 && k[i][3] == 0);
        if (i < 16)
            mean_len_first += len / 16;
        if (i >= 48)
            mean_len_last += len / 16;
    }
    CHECK(mean_len_first < mean_len_last); /* denser near the centre */
    CHECK(!ssao_kernel(0, SSAO_SEED, k) && !ssao_kernel(65, SSAO_SEED, k));

    float a[16], b[16];
    ssao_noise(SSAO_SEED, a);
    ssao_noise(SSAO_SEED, b);
    CHECK(memcmp(a, b, sizeof(a)) == 0);
    /* Every one of the 16 rotations once per tile. */
    int seen[16] = {0};
    for (int i = 0; i < 16; i++) {
        int slot = (int)floor(a[i] / (6.283185307179586 / 16));
        CHECK(slot >= 0 && slot < 16);
        if (slot >= 0 && slot < 16)
            seen[slot]++;
    }
    for (int i = 0; i < 16; i++)
        CHECK(seen[i] == 1);

    /* Tone curves: 0 at 0, rising, below 1; sRGB's ends and its linear toe. */
    double prev_r = 0, prev_a = 0;
    CHECK(tonemap_reinhard(0) == 0 && tonemap_aces(0) == 0);
    for (double x = 0.01; x < 100; x *= 1.5) {
        double r = tonemap_reinhard(x), ac = tonemap_aces(x);
        CHECK(r > prev_r && r < 1 && ac >= prev_a && ac <= 1);
        prev_r = r, prev_a = ac;
    }
    CHECK_NEAR(tonemap_reinhard(1.0), 0.5, 1e-12);
    CHECK(srgb_encode(0) == 0 && fabs(srgb_encode(1) - 1) < 1e-12);
    CHECK_NEAR(srgb_encode(0.002), 0.002 * 12.92, 1e-12);
    CHECK_NEAR(srgb_encode(0.5), 0.735357, 1e-5);
}

static void test_sweeps(void)
{
    struct sweep_spec s;
    struct job_error err;
    json_t *body = json_loads(
        "{\"base\": {\"frames\": 4, \"look\": {\"hdr\": \"rgba16f\", \"post\": [\"toon\", \"bloom\"]}},"
        " \"find\": {\"param\": \"look.post.bloom.intensity\", \"from\": 1, \"to\": 1e8,"
        " \"while\": \"finite\"}}", 0, NULL);
    CHECK(sweep_spec_parse(body, fixture_catalog(), &s, &err));
    if (s.base) {
        CHECK(s.criterion == CRITERION_FINITE && !s.integer);
        json_t *probe = sweep_probe_job(&s, 5000);
        json_t *entry = json_array_get(json_object_get(json_object_get(probe, "look"), "post"), 1);
        CHECK(json_number_value(json_object_get(json_object_get(entry, "bloom"), "intensity")) == 5000);
        CHECK(json_is_string(json_array_get(json_object_get(json_object_get(probe, "look"), "post"), 0)));
        json_decref(probe);

        json_t *ok = json_loads("{\"nonfinite\": {\"finite\": true}}", 0, NULL);
        json_t *bad = json_loads("{\"nonfinite\": {\"finite\": false}}", 0, NULL);
        CHECK(sweep_criterion_holds(&s, ok) && !sweep_criterion_holds(&s, bad));
        CHECK(!sweep_criterion_holds(&s, json_object_get(ok, "nonfinite")));
        json_decref(ok);
        json_decref(bad);
        sweep_spec_finish(&s);
    }
    json_decref(body);

    body = json_loads("{\"base\": {\"frames\": 4, \"look\": {\"post\": [{\"bloom\": {\"radius\": 3}}]}},"
                      " \"vary\": {\"look.post.bloom.kernel\": [\"separable\", \"2d\"],"
                      " \"look.exposure\": [0.5, 2]}}", 0, NULL);
    CHECK(sweep_spec_parse(body, fixture_catalog(), &s, &err));
    if (s.base) {
        json_t *values, *job = sweep_point_job(&s, 3, &values);
        json_t *bloom = json_object_get(json_array_get(json_object_get(json_object_get(job, "look"), "post"), 0), "bloom");
        CHECK(strcmp(json_string_value(json_object_get(bloom, "kernel")), "2d") == 0);
        CHECK(json_integer_value(json_object_get(bloom, "radius")) == 3);
        CHECK(json_number_value(json_object_get(json_object_get(job, "look"), "exposure")) == 2);
        json_decref(job);
        json_decref(values);
        sweep_spec_finish(&s);
    }
    json_decref(body);

    sweep_rejects("{\"base\": {\"frames\": 4}, \"find\": {\"param\": \"look.post.bloom.intensity\","
                  " \"from\": 1, \"to\": 10, \"while\": \"finite\"}}", "find.param");
    sweep_rejects("{\"base\": {\"frames\": 4, \"look\": {\"post\": [\"bloom\"]}}, \"find\":"
                  " {\"param\": \"look.post.bloom.glow\", \"from\": 1, \"to\": 10, \"while\": \"finite\"}}",
                  "find.param");
    sweep_rejects("{\"base\": {\"frames\": 4, \"look\": {\"post\": [\"bloom\"]}}, \"vary\":"
                  " {\"look.post.bloom.radius\": [4, 64]}}", "vary.look.post.bloom.radius[1]");
    sweep_rejects("{\"base\": {\"frames\": 4}, \"find\": {\"param\": \"look.exposure\","
                  " \"from\": 1, \"to\": 10, \"while\": \"infinite\"}}", "find.while");
}

int main(void)
{
    test_look();
    test_passes();
    test_kernels();
    test_sweeps();
    return check_finish("test_effects");
}
