/* The GL-free parts of the Khronos reference (daemon/reference/): a job's
 * "fidelity" and its checks, POST /v1/assets/NAME/fidelity's body as a job,
 * the page's request (the tone curve and the exposure as the viewer takes
 * them), the cache key, the gamma-2.2 to sRGB re-encoding, and the viewer
 * module's IBL sampler patch. */
#include <math.h>
#include <string.h>

#include "daemon/spec/job_spec.h"
#include "daemon/jobs/fidelity.h"
#include "daemon/spec/fidelity_spec.h"
#include "daemon/reference/reference_files.h"
#include "daemon/techniques/catalog.h"
#include "tests/unit/catalog_fixture.h"
#include "tests/unit/check.h"

static bool parse(const char *text, struct job_spec *spec, struct job_error *err)
{
    return job_spec_parse_text(text, strlen(text), fixture_catalog(), spec, err);
}

static void test_spec(void)
{
    struct job_spec spec;
    struct job_error err;
    /* A fidelity job: the captured frame defaults to the last. */
    CHECK(parse("{\"technique\":\"forward\",\"frames\":2,\"scene\":{\"asset\":\"a.glb\"},"
                "\"look\":{\"lighting\":\"pbr\"},\"fidelity\":{\"channels\":[\"base_color\"]}}",
                &spec, &err));
    CHECK(spec.fidelity.enabled && spec.capture_interval == 2);
    CHECK(spec.fidelity.channels == ((1u << FIDELITY_LIT) | (1u << FIDELITY_BASE_COLOR)));
    json_t *back = job_spec_to_json(&spec);
    CHECK(json_array_size(json_object_get(json_object_get(back, "fidelity"), "channels")) == 2);
    json_decref(back);
    /* Each rule names its field. */
    static const struct {
        const char *body, *field;
    } bad[] = {
        {"{\"fidelity\":true}", "fidelity"}, /* no scene.asset */
        {"{\"scene\":{\"asset\":\"a.glb\"},\"fidelity\":true}", "look.lighting"},
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\",\"tonemap\":\"reinhard\"},"
         "\"fidelity\":true}", "look.tonemap"},
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\"},\"msaa\":4,"
         "\"fidelity\":true}", "msaa"},
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\",\"ibl\":true},"
         "\"fidelity\":true}", "look.ibl.environment"}, /* the default sky */
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\"},"
         "\"fidelity\":{\"channels\":[\"albedo\"]}}", "fidelity.channels[0]"},
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\"},"
         "\"fidelity\":{\"ibl_sampler\":{\"texture_size\":100}}}", "fidelity.ibl_sampler.texture_size"},
        {"{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\"},\"reference\":\"forward\","
         "\"fidelity\":true}", "reference"},
        {"{\"scene\":{\"asset\":\"a.glb\",\"sun\":true},\"look\":{\"lighting\":\"pbr\"},"
         "\"fidelity\":true}", "scene.sun"},
    };
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
        memset(&err, 0, sizeof(err));
        CHECK(!parse(bad[i].body, &spec, &err));
        CHECK(strcmp(err.field, bad[i].field) == 0);
        if (strcmp(err.field, bad[i].field) != 0)
            fprintf(stderr, "  %s: %s %s\n", bad[i].body, err.field, err.message);
    }
}

static void test_body(void)
{
    struct job_error err = {0};
    json_t *b = json_loads("{\"width\":64,\"lights\":[{\"type\":\"directional\",\"direction\":"
                           "[0,-1,0],\"intensity\":3}],\"channels\":[\"occlusion\"]}", 0, NULL);
    json_t *job = fidelity_job_body("x.glb", b, &err);
    CHECK(job != NULL);
    json_t *scene = json_object_get(job, "scene");
    CHECK(strcmp(json_string_value(json_object_get(scene, "asset")), "x.glb") == 0);
    CHECK(json_integer_value(json_object_get(scene, "width")) == 64);
    CHECK(json_integer_value(json_object_get(scene, "height")) == FIDELITY_DEFAULT_HEIGHT);
    CHECK(json_array_size(json_object_get(scene, "light_rig")) == 1);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(job, "look"), "lighting")),
                 "pbr") == 0);
    CHECK(strcmp(json_string_value(json_object_get(job, "technique")), "forward") == 0);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(job, "look"), "transfer")),
                 "gamma_2.2") == 0);
    struct job_spec spec;
    CHECK(job_spec_parse(job, fixture_catalog(), &spec, &err));
    CHECK(spec.frames == 1 && spec.warmup_frames == 0 && spec.capture_interval == 1);
    json_decref(job);
    json_decref(b);
    b = json_loads("{\"size\":64}", 0, NULL);
    CHECK(!fidelity_job_body("x.glb", b, &err) && strcmp(err.field, "size") == 0);
    json_decref(b);
    b = json_loads("{\"scene\":{\"asset\":\"y.glb\"}}", 0, NULL);
    CHECK(!fidelity_job_body("x.glb", b, &err) && strcmp(err.field, "scene.asset") == 0);
    json_decref(b);
}

static void test_page_request(void)
{
    struct job_spec spec;
    struct job_error err;
    CHECK(parse("{\"scene\":{\"asset\":\"a.glb\"},\"look\":{\"lighting\":\"pbr\",\"tonemap\":"
                "\"aces\",\"exposure\":2},\"fidelity\":true}", &spec, &err));
    json_t *view = json_pack("{s:[f,f,f,f,f,f,f,f,f,f,f,f,f,f,f,f], s:[f,f,f,f,f,f,f,f,f,f,f,f,f,f,f,f],"
                             " s:[f,f,f], s:[]}", "view", 1., 0., 0., 0., 0., 1., 0., 0., 0., 0.,
                             1., 0., 0., 0., -5., 1., "projection", 1., 0., 0., 0., 0., 1., 0.,
                             0., 0., 0., -1., -1., 0., 0., -0.2, 0., "eye", 0., 0., 5., "lights");
    const char *ch[] = {"lit", "base_color"};
    json_t *r = fidelity_page_request(&spec, view, ch, 2, err.message, sizeof(err.message));
    CHECK(r != NULL);
    /* shadebench's ACES is Narkowicz's after x 0.6: the viewer's exposure takes it. */
    CHECK(strcmp(json_string_value(json_object_get(r, "tonemap")), "aces") == 0);
    CHECK_NEAR(json_number_value(json_object_get(r, "exposure")), 1.2, 1e-9);
    /* No look.ibl: the uniform ambient of radiance 0.15. */
    CHECK_NEAR(json_number_value(json_object_get(r, "ibl_intensity")), 0.15, 1e-9);
    CHECK(json_array_size(json_object_get(r, "channels")) == 2);
    /* The key leaves the channels out and changes with the camera. */
    char k1[65], k2[65], k3[65];
    fidelity_cache_key(r, &spec, k1);
    json_array_remove(json_object_get(r, "channels"), 1);
    fidelity_cache_key(r, &spec, k2);
    CHECK(strcmp(k1, k2) == 0 && strlen(k1) == 64);
    json_array_set_new(json_object_get(r, "eye"), 0, json_real(0.5));
    fidelity_cache_key(r, &spec, k3);
    CHECK(strcmp(k1, k3) != 0);
    json_decref(r);
    json_decref(view);
}

static void test_reencode(void)
{
    /* Gamma 2.2 to sRGB: ends fixed, mid-tones within a level or two, dark
     * tones lifted less (sRGB's linear toe). */
    CHECK(fidelity_reencode(0, false) == 0 && fidelity_reencode(255, false) == 255);
    int d = (int)fidelity_reencode(128, false) - 128;
    CHECK(d >= -3 && d <= 3);
    CHECK(fidelity_reencode(10, false) < 10);
    /* To linear: (v / 255)^2.2. */
    CHECK(fidelity_reencode(128, true) == (uint8_t)lround(pow(128 / 255.0, 2.2) * 255));
}

static void test_patch(void)
{
    const char *src = "a;this.textureSize = 256;this.ggxSampleCount = 1024;"
                      "this.lambertianSampleCount = 2048;this.sheenSamplCount = 64;"
                      "this.lutResolution = 1024;b";
    struct reference_sampler given, s;
    reference_sampler_defaults(&given);
    reference_sampler_resolve(&given, true, &s);
    CHECK(s.texture_size == 32 && s.lut_resolution == 128);
    size_t n;
    char err[256];
    char *out = reference_patch_viewer(src, strlen(src), &s, &n, err, sizeof(err));
    CHECK(out && n == strlen(src) && strstr(out, "this.textureSize = 32;"));
    CHECK(out && strstr(out, "this.ggxSampleCount = 16;"));
    free(out);
    /* Another version's module is refused, not silently served. */
    CHECK(!reference_patch_viewer("this.textureSize = 512;", 23, &s, &n, err, sizeof(err)));
    CHECK(strstr(err, "textureSize") != NULL);
}

int main(void)
{
    test_spec();
    test_body();
    test_page_request();
    test_reencode();
    test_patch();
    return check_finish("test_fidelity");
}
