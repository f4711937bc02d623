#include <stdlib.h>
#include <math.h>
#include <string.h>

#include "daemon/spec/job_cost.h"
#include "daemon/jobs/job_eta.h"
#include "daemon/spec/job_spec.h"
#include "tests/unit/catalog_fixture.h"
#include "tests/unit/check.h"

#define techniques fixture_catalog()

static bool parse(const char *text, struct job_spec *spec, struct job_error *err)
{
    return job_spec_parse_text(text, strlen(text), techniques, spec, err);
}

/* The request is rejected, and the error names field. */
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

/* The cost estimate (job_cost.h): each part grows with what drives it, the
 * largest names its field, and admission holds a job to the limit. */
static void test_cost(void)
{
    struct job_spec spec;
    struct job_error err;
    struct job_cost small, big, cost;
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":1,\"warmup_frames\":0,"
                "\"scene\":{\"width\":32,\"height\":32}}", &spec, &err));
    job_cost_estimate(&spec, &small);
    /* 24 bytes a pixel of the harness's (rgba32f); unlit declares no planes. */
    CHECK(small.targets_bytes == 32.0 * 32 * 24 && small.captures_bytes == 0 &&
          small.reference_bytes == 0 && small.metrics_bytes == 0 && small.look_bytes == 0);
    CHECK(small.memory_bytes > small.targets_bytes && strcmp(small.memory_field, "scene.width") == 0);
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":1,\"warmup_frames\":0,"
                "\"scene\":{\"width\":4096,\"height\":4096}}", &spec, &err));
    job_cost_estimate(&spec, &big);
    CHECK(big.targets_bytes == small.targets_bytes * 16384);
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":64,\"warmup_frames\":0,"
                "\"capture_interval\":1,\"reference\":\"forward\","
                "\"look\":{\"hdr\":\"rgba16f\",\"post\":[\"bloom\"]},"
                "\"scene\":{\"width\":256,\"height\":256}}", &spec, &err));
    job_cost_estimate(&spec, &cost);
    CHECK(cost.targets_bytes == 256.0 * 256 * (16 + 32) && cost.captures_bytes > 0 &&
          cost.reference_bytes > 0 && cost.metrics_bytes > 0);
    CHECK(strcmp(cost.memory_field, "capture_interval") == 0); /* 64 captures lead */
    json_t *j = job_cost_json(&cost);
    CHECK(json_real_value(json_object_get(j, "memory_bytes")) == cost.memory_bytes);
    json_decref(j);
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":1,\"warmup_frames\":0,"
                "\"look\":{\"lighting\":\"pbr\",\"ibl\":{\"probes\":32,\"resolution\":512}},"
                "\"scene\":{\"width\":64,\"height\":64}}", &spec, &err));
    job_cost_estimate(&spec, &cost);
    CHECK(cost.look_bytes > 5e8 && strcmp(cost.memory_field, "look.ibl.resolution") == 0);
    /* Work: 33 cubes (32 probes and the environment) of 512x512 faces. */
    CHECK(cost.frames_total == 1 && cost.pixel_frames == 64.0 * 64 &&
          cost.ibl_samples == 33 * 6.0 * 512 * 512 * spec.look.ibl.samples &&
          cost.shadow_texels == 0 && cost.metric_pixels == 0);
    CHECK(parse("{\"technique\":\"clustered_deferred\",\"frames\":10,\"warmup_frames\":2,"
                "\"capture_interval\":5,\"reference\":\"forward\","
                "\"scene\":{\"width\":100,\"height\":50,\"lights\":1000}}", &spec, &err));
    job_cost_estimate(&spec, &cost);
    CHECK(cost.frames_total == 12 && cost.pixel_light_evaluations == 12 * 5000.0 * 1000 &&
          cost.metric_pixels == 2 * 5000.0);
    j = job_cost_json(&cost);
    CHECK(json_real_value(json_object_get(json_object_get(j, "work"), "pixel_frames")) ==
          12 * 5000.0);
    json_decref(j);

    /* Admission: no limit by default; over the limit, refused naming the
     * field, and job_spec_parse does it for every caller. */
    CHECK(job_cost_memory_limit() == 0 && job_cost_admit(&big, &err));
    job_cost_set_memory_limit(64.0 * 1048576);
    CHECK(job_cost_admit(&small, &err) && !job_cost_admit(&big, &err) &&
          strcmp(err.field, "scene.width") == 0 && strstr(err.message, "MiB"));
    rejects("{\"technique\":\"unlit\",\"scene\":{\"width\":4096,\"height\":4096}}",
            "scene.width");
    rejects("{\"look\":{\"lighting\":\"pbr\",\"ibl\":{\"probes\":32,\"resolution\":512}},"
            "\"scene\":{\"width\":64,\"height\":64}}", "look.ibl.resolution");
    CHECK(parse("{\"scene\":{\"width\":64,\"height\":64}}", &spec, &err));
    job_cost_set_memory_limit(0);
}

/* Each technique is charged the planes its info declares (planes_bpp), not
 * the 32 bytes a pixel every technique was charged when the estimate could
 * not tell them apart: none for forward, the heat map for forward_plus,
 * the g-buffer by its layout, the look and MSAA for the deferred family. */
static void test_cost_planes(void)
{
    struct job_spec spec;
    struct job_error err;
    struct job_cost c;
    const char *const techs[] = {"forward", "forward_plus", "deferred", "clustered_deferred"};
    double bytes[4];
    for (int i = 0; i < 4; i++) {
        char text[256];
        snprintf(text, sizeof(text), "{\"technique\":\"%s\",\"scene\":{\"width\":100,"
                 "\"height\":100}}", techs[i]);
        CHECK(parse(text, &spec, &err));
        job_cost_estimate(&spec, &c);
        bytes[i] = c.targets_bytes / 1e4;
    }
    /* The harness's 24 (rgba32f); the heat map 4; the g-buffer under Phong
     * with octahedral normals: albedo 4, normal 8, material 8. */
    CHECK(bytes[0] == 24 && bytes[1] == 28 && bytes[2] == 24 + 20 + 4 && bytes[3] == bytes[2]);
    CHECK(parse("{\"technique\":\"deferred\",\"look\":{\"lighting\":\"pbr\"},"
                "\"deferred\":{\"gbuffer\":{\"normal\":\"float3\"}},"
                "\"scene\":{\"width\":100,\"height\":100}}", &spec, &err));
    job_cost_estimate(&spec, &c);
    CHECK(c.targets_bytes / 1e4 == 24 + (4 + 16 + 16) + 4);
    CHECK(parse("{\"technique\":\"deferred\",\"msaa\":4,"
                "\"scene\":{\"width\":100,\"height\":100}}", &spec, &err));
    job_cost_estimate(&spec, &c);
    /* Multisampled output (16 + 8) x 4, the g-buffer and its edge stencil x 4. */
    CHECK(c.targets_bytes / 1e4 == 24 + 24 * 4 + (20 + 4) * 4 + 4);
}

/* The duration estimate (job_eta.h): none before a job of the technique
 * ran; then scaled from it by pixels and frames; a projection far past the
 * timeout_s or a frame far past the frame bound refused naming the field. */
static void test_eta(void)
{
    struct job_spec spec;
    struct job_error err;
    struct job_eta e;
    job_eta_reset();
    CHECK(parse("{\"technique\":\"forward\",\"frames\":100,\"warmup_frames\":0,"
                "\"timeout_s\":600,\"scene\":{\"width\":100,\"height\":100,\"lights\":10}}",
                &spec, &err));
    job_eta_estimate(&spec, &e);
    CHECK(!e.known && json_is_null(job_eta_json(&e)) && job_eta_admit(&spec, &e, &err));
    /* 10,000 pixels and 10 lights at 10 ms a frame: 100 timed frames and, with
     * no warm-up, 2 of the harness's own, the measured one counted twice:
     * 103 frames in 1.5 s. */
    job_eta_observe("forward", 1e4, 10, 0.010, 1.0, 103, 1.5);
    job_eta_observe("deferred", 1e4, 10, 0.5, 1.0, 103, 60);
    job_eta_estimate(&spec, &e);
    CHECK(e.known && fabs(e.frame_s - 0.010) < 1e-12);
    /* 100 frames and 3 measuring ones, and the 0.47 s beyond them. */
    CHECK(fabs(e.duration_s - (103 * 0.010 + 0.47)) < 1e-9);
    CHECK(job_eta_admit(&spec, &e, &err));
    /* Four times the pixels, frames past what the timeout allows. */
    CHECK(parse("{\"technique\":\"forward\",\"frames\":100000,\"warmup_frames\":0,"
                "\"timeout_s\":600,\"scene\":{\"width\":200,\"height\":200,\"lights\":10}}",
                &spec, &err));
    job_eta_estimate(&spec, &e);
    CHECK(fabs(e.frame_s - 0.040) < 1e-12);
    CHECK(!job_eta_admit(&spec, &e, &err) && strcmp(err.field, "timeout_s") == 0 &&
          strstr(err.message, "projected to take"));
    /* 8000x8000: a frame far past the bound, unless sliced timing is accepted. */
    CHECK(parse("{\"technique\":\"forward\",\"timeout_s\":0,"
                "\"scene\":{\"width\":8000,\"height\":8000,\"lights\":10}}", &spec, &err));
    job_eta_estimate(&spec, &e);
    CHECK(!job_eta_admit(&spec, &e, &err) && strcmp(err.field, "scene.width") == 0 &&
          strstr(err.message, "64.0 s"));
    spec.accept_sliced_timing = true;
    CHECK(job_eta_admit(&spec, &e, &err));
    /* The nearest in lights; the light ratio's square root. */
    CHECK(parse("{\"technique\":\"forward\",\"scene\":{\"width\":100,\"height\":100,"
                "\"lights\":43}}", &spec, &err));
    job_eta_estimate(&spec, &e);
    CHECK(fabs(e.frame_s - 0.010 * 2.0) < 1e-12);
    /* A frame half of whose cost no pixel pays: that half stays. */
    job_eta_reset();
    job_eta_observe("forward", 1e4, 10, 0.010, 0.5, 103, 1.5);
    CHECK(parse("{\"technique\":\"forward\",\"scene\":{\"width\":200,\"height\":200,"
                "\"lights\":10}}", &spec, &err));
    job_eta_estimate(&spec, &e);
    CHECK(fabs(e.frame_s - (0.005 + 0.005 * 4)) < 1e-12);
    /* Seconds left by the frames drawn. */
    CHECK(job_eta_left(0, 10, 5) < 0 && fabs(job_eta_left(4, 10, 2.0) - 3.0) < 1e-12);
    job_eta_reset();
}

/* --max-job-seconds: a job's own timeout_s above it (or 0, no limit) is
 * refused naming timeout_s; one that names none gets the default capped. */
static void test_max_seconds(void)
{
    struct job_spec spec;
    struct job_error err;
    double saved = job_spec_default_timeout();
    CHECK(job_spec_max_seconds() == 0);
    CHECK(parse("{\"timeout_s\":0}", &spec, &err) && spec.timeout_s == 0);
    job_spec_set_max_seconds(600);
    CHECK(parse("{}", &spec, &err) && spec.timeout_s == 600);
    CHECK(parse("{\"timeout_s\":30}", &spec, &err) && spec.timeout_s == 30);
    CHECK(parse("{\"timeout_s\":600}", &spec, &err) && spec.timeout_s == 600);
    rejects("{\"timeout_s\":601}", "timeout_s");
    rejects("{\"timeout_s\":0}", "timeout_s");
    job_spec_set_default_timeout(60);
    CHECK(parse("{}", &spec, &err) && spec.timeout_s == 60);
    job_spec_set_default_timeout(0);
    CHECK(parse("{}", &spec, &err) && spec.timeout_s == 600);
    job_spec_set_max_seconds(0);
    job_spec_set_default_timeout(saved);
    CHECK(parse("{\"timeout_s\":601}", &spec, &err) && spec.timeout_s == 601);
}

/* reference as {"technique", "supersample"} beside the shorthand, and
 * temporal.frames: parsed strictly, written back, costed. */
static void test_reference_temporal(void)
{
    struct job_spec spec;
    struct job_error err;
    /* A reference with no word on captures scores the last frame; an
     * explicit 0 is refused. */
    CHECK(parse("{\"frames\":8,\"reference\":\"forward\"}", &spec, &err) &&
          spec.capture_interval == 8);
    rejects("{\"frames\":8,\"capture_interval\":0,\"reference\":\"forward\"}", "reference");
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":4,\"capture_interval\":2,"
                "\"reference\":\"forward\",\"scene\":{\"width\":64,\"height\":48}}", &spec, &err));
    CHECK(spec.reference_supersample == 1 && spec.temporal_frames == 0);
    json_t *j = job_spec_to_json(&spec);
    CHECK(json_is_string(json_object_get(j, "reference")) && !json_object_get(j, "temporal"));
    json_decref(j);
    struct job_cost plain, ss;
    job_cost_estimate(&spec, &plain);
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":4,\"capture_interval\":2,"
                "\"reference\":{\"technique\":\"forward\",\"supersample\":4},"
                "\"temporal\":{\"frames\":3},\"scene\":{\"width\":64,\"height\":48}}", &spec, &err));
    CHECK(spec.reference_supersample == 4 && !strcmp(spec.reference, "forward") &&
          spec.temporal_frames == 3 && spec.reference_index >= 0);
    job_cost_estimate(&spec, &ss);
    CHECK(ss.reference_bytes > plain.reference_bytes + 64.0 * 48 * 16 * 4 &&
          ss.temporal_bytes == 64.0 * 48 * 4 * 5);
    j = job_spec_to_json(&spec);
    json_t *r = json_object_get(j, "reference");
    CHECK(json_is_object(r) && json_integer_value(json_object_get(r, "supersample")) == 4 &&
          !strcmp(json_string_value(json_object_get(r, "technique")), "forward"));
    CHECK(json_integer_value(json_object_get(json_object_get(j, "temporal"), "frames")) == 3);
    /* The spec as answered parses to the same job. */
    struct job_spec again;
    CHECK(job_spec_parse(j, techniques, &again, &err) && again.reference_supersample == 4 &&
          again.temporal_frames == 3);
    json_decref(j);
    /* The object without a technique is the baseline's; supersample 1 is
     * written back as the shorthand. */
    CHECK(parse("{\"technique\":\"unlit\",\"frames\":4,\"capture_interval\":2,"
                "\"reference\":{\"supersample\":1}}", &spec, &err));
    CHECK(!strcmp(spec.reference, "forward") && spec.reference_supersample == 1);
    j = job_spec_to_json(&spec);
    CHECK(json_is_string(json_object_get(j, "reference")));
    json_decref(j);
    const char *base = "{\"technique\":\"unlit\",\"frames\":4,\"capture_interval\":2,";
    char text[300];
    static const struct {
        const char *rest, *field;
    } bad[] = {
        {"\"reference\":{\"technique\":\"forward\",\"supersample\":5}}", "reference.supersample"},
        {"\"reference\":{\"technique\":\"forward\",\"supersample\":0}}", "reference.supersample"},
        {"\"reference\":{\"technique\":\"forward\",\"supersample\":2.5}}", "reference.supersample"},
        {"\"reference\":{\"technique\":\"forward\",\"supersample\":\"4\"}}", "reference.supersample"},
        {"\"reference\":{\"technique\":\"nope\"}}", "reference.technique"},
        {"\"reference\":{\"technique\":null}}", "reference.technique"},
        {"\"reference\":{\"technique\":\"forward\",\"samples\":4}}", "reference.samples"},
        {"\"reference\":4}", "reference"},
        {"\"reference\":\"forward\",\"temporal\":{\"frames\":1}}", "temporal.frames"},
        {"\"reference\":\"forward\",\"temporal\":{\"frames\":17}}", "temporal.frames"},
        {"\"reference\":\"forward\",\"temporal\":{}}", "temporal.frames"},
        {"\"reference\":\"forward\",\"temporal\":{\"frames\":4,\"x\":1}}", "temporal.x"},
        {"\"reference\":\"forward\",\"temporal\":4}", "temporal"},
        {"\"temporal\":{\"frames\":4}}", "temporal"},
    };
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
        snprintf(text, sizeof(text), "%s%s", base, bad[i].rest);
        rejects(text, bad[i].field);
    }
    /* Past GL 4.5's guaranteed 16384 a side. */
    rejects("{\"frames\":1,\"capture_interval\":1,\"reference\":{\"supersample\":4},"
            "\"scene\":{\"width\":4097,\"height\":64}}", "reference.supersample");
    CHECK(parse("{\"frames\":1,\"capture_interval\":1,\"reference\":{\"supersample\":4},"
                "\"scene\":{\"width\":4096,\"height\":64}}", &spec, &err));
    /* Over the memory a job may take, the supersampled reference is named. */
    job_cost_set_memory_limit(64.0 * 1048576);
    rejects("{\"technique\":\"unlit\",\"frames\":1,\"capture_interval\":1,\"reference\":"
            "{\"technique\":\"forward\",\"supersample\":4},\"scene\":{\"width\":512,\"height\":512}}",
            "reference.supersample");
    job_cost_set_memory_limit(0);
}

int main(void)
{
    test_reference_temporal();
    struct job_spec spec;
    struct job_error err;

    CHECK(parse("{}", &spec, &err));
    CHECK(strcmp(spec.technique, "forward") == 0);
    CHECK(spec.frames == 60 && spec.warmup_frames == 5 && spec.capture_interval == 0);
    CHECK(spec.scene.width == 1080 && spec.scene.height == 720 && spec.scene.lights == 10);
    CHECK(!spec.scene.dynamic);
    {
        /* OSL's defaults are the configuration that beats forward (issue 25):
         * auto tiles and visibility "seen", no budget, no change detection. */
        const struct osl_options *osl = (const struct osl_options *)spec.options[2].bytes;
        CHECK(osl->resolution == 0 && osl->visibility == OSL_VISIBILITY_SEEN);
        CHECK(osl->budget_texels == 0 && osl->change_threshold == 0);
    }

    CHECK(parse("{\"technique\":\"osl\",\"frames\":40,\"warmup_frames\":0,"
                "\"capture_interval\":20,\"async_distance\":20,"
                "\"scene\":{\"preset\":\"grid\",\"lights\":3,\"dynamic\":true,"
                "\"width\":320,\"height\":240,\"sphere_segments\":16},"
                "\"osl\":{\"resolution\":\"auto\",\"texel_density\":2,\"reshade\":\"all\"}}",
                &spec, &err));
    CHECK(strcmp(spec.technique, "osl") == 0 && spec.frames == 40 && spec.warmup_frames == 0);
    const struct osl_options *osl = job_spec_technique_options(&spec);
    CHECK(osl->async_distance == 20.0 && spec.scene.dynamic && spec.scene.lights == 3);
    CHECK(osl->resolution == 0 && osl->texel_density == 2.0);
    CHECK(osl->reshade == OSL_RESHADE_ALL && spec.scene.sphere_segments == 16);
    CHECK(job_spec_capture_count(&spec) == 2);
    CHECK(job_spec_is_capture_frame(&spec, 20) && job_spec_is_capture_frame(&spec, 40));
    CHECK(!job_spec_is_capture_frame(&spec, 10) && !job_spec_is_capture_frame(&spec, 0));

    /* The spec as understood round-trips through JSON. */
    json_t *j = job_spec_to_json(&spec);
    char *text = json_dumps(j, 0);
    struct job_spec again;
    CHECK(parse(text, &again, &err));
    CHECK(memcmp(&again, &spec, sizeof(spec)) == 0);
    free(text);
    json_decref(j);

    CHECK(parse("{\"frames\":300.0}", &spec, &err) && spec.frames == 300);
    CHECK(parse("{\"repeat\":5}", &spec, &err) && spec.repeat == 5 && !spec.repeat_auto);
    CHECK(parse("{\"repeat\":{\"auto\":true,\"max\":12}}", &spec, &err) && spec.repeat == 12 &&
          spec.repeat_auto && job_spec_runs(&spec) == 12);
    CHECK(parse("{\"repeat\":{\"auto\":true}}", &spec, &err) && spec.repeat == 30);
    rejects("{\"repeat\":0}", "repeat");
    rejects("{\"repeat\":\"many\"}", "repeat");
    rejects("{\"repeat\":{\"auto\":false}}", "repeat.auto");
    rejects("{\"repeat\":{\"auto\":true,\"max\":2}}", "repeat.max");
    rejects("{\"repeat\":{\"atuo\":true}}", "repeat.atuo");

    rejects("", "body");
    rejects("{", "body");
    rejects("[1,2]", "body");
    rejects("{\"frames\":1,\"frames\":2}", "body");
    rejects("{\"frame\":10}", "frame");
    rejects("{\"technique\":\"sponza\"}", "technique");
    rejects("{\"technique\":3}", "technique");
    rejects("{\"frames\":\"300\"}", "frames");
    rejects("{\"frames\":0}", "frames");
    rejects("{\"frames\":10.5}", "frames");
    rejects("{\"frames\":2000000}", "frames");
    rejects("{\"warmup_frames\":-1}", "warmup_frames");
    rejects("{\"capture_interval\":-5}", "capture_interval");
    rejects("{\"frames\":10,\"capture_interval\":11}", "capture_interval");
    rejects("{\"frames\":100000,\"capture_interval\":1}", "capture_interval");
    rejects("{\"async_distance\":-1}", "async_distance");
    rejects("{\"async_distance\":\"far\"}", "async_distance");
    rejects("{\"scene\":5}", "scene");
    rejects("{\"scene\":{\"width\":8}}", "scene.width");
    rejects("{\"scene\":{\"height\":9000}}", "scene.height");
    rejects("{\"scene\":{\"lights\":-1}}", "scene.lights");
    rejects("{\"scene\":{\"dynamic\":\"yes\"}}", "scene.dynamic");
    rejects("{\"scene\":{\"preset\":\"sponza\"}}", "scene.preset");
    rejects("{\"scene\":{\"sphere_segments\":15}}", "scene.sphere_segments");
    rejects("{\"scene\":{\"widht\":300}}", "scene.widht");
    rejects("{\"osl\":{\"resolution\":100}}", "osl.resolution");
    rejects("{\"osl\":{\"resolution\":2048}}", "osl.resolution");
    rejects("{\"osl\":{\"resolution\":\"high\"}}", "osl.resolution");
    rejects("{\"osl\":{\"texel_density\":0.03}}", "osl.texel_density"); /* 0 is auto */
    rejects("{\"osl\":{\"reshade\":\"some\"}}", "osl.reshade");
    rejects("{\"osl\":{\"resolutoin\":256}}", "osl.resolutoin");

    /* The generic option parser, on a technique with every kind of option. */
    CHECK(parse("{\"technique\":\"demo\"}", &spec, &err));
    const struct demo_options *demo = job_spec_technique_options(&spec);
    CHECK(demo->tile == 16 && demo->radius == 0.5 && demo->fallback && demo->normal == 0 &&
          demo->albedo == 1 && demo->size == 0 && demo->grid[0] == 16 && demo->grid[2] == 24);
    CHECK(parse("{\"technique\":\"demo\",\"demo\":{\"tile\":32,\"radius\":1.5,"
                "\"fallback\":false,\"gbuffer\":{\"normal\":\"xy_reconstruct_z\"},"
                "\"size\":64,\"grid\":[8,8,32]}}", &spec, &err));
    demo = job_spec_technique_options(&spec);
    CHECK(demo->tile == 32 && demo->radius == 1.5 && !demo->fallback && demo->normal == 2 &&
          demo->albedo == 1 && demo->size == 64 && demo->grid[0] == 8 && demo->grid[2] == 32);
    j = job_spec_to_json(&spec);
    CHECK(json_is_string(json_object_get(json_object_get(json_object_get(j, "demo"), "gbuffer"),
                                         "normal")));
    text = json_dumps(j, 0);
    CHECK(parse(text, &again, &err));
    CHECK(memcmp(&again, &spec, sizeof(spec)) == 0);
    free(text);
    json_decref(j);
    rejects("{\"demo\":{\"tile\":4}}", "demo.tile");
    rejects("{\"demo\":{\"radius\":\"big\"}}", "demo.radius");
    rejects("{\"demo\":{\"fallback\":1}}", "demo.fallback");
    rejects("{\"demo\":{\"gbuffer\":{\"normal\":\"packed\"}}}", "demo.gbuffer.normal");
    rejects("{\"demo\":{\"gbuffer\":{\"normals\":\"float3\"}}}", "demo.gbuffer.normals");
    rejects("{\"demo\":{\"gbuffer\":3}}", "demo.gbuffer");
    rejects("{\"demo\":{\"size\":48}}", "demo.size");
    rejects("{\"demo\":{\"grid\":[8,8]}}", "demo.grid");
    rejects("{\"demo\":{\"grid\":[8,8,0]}}", "demo.grid");
    rejects("{\"demo\":[]}", "demo");
    /* Dotted names, as /v1/info lists them, read as the nested form. */
    CHECK(parse("{\"technique\":\"demo\",\"demo\":{\"gbuffer\":{\"normal\":\"float3\"}}}",
                &spec, &err));
    CHECK(parse("{\"technique\":\"demo\",\"demo\":{\"gbuffer.normal\":\"float3\"}}", &again,
                &err));
    CHECK(memcmp(&again, &spec, sizeof(spec)) == 0 &&
          ((const struct demo_options *)job_spec_technique_options(&spec))->normal == 1);
    rejects("{\"demo\":{\"gbuffer\":{\"normal\":\"float3\"},\"gbuffer.normal\":\"float3\"}}",
            "demo.gbuffer.normal");
    rejects("{\"demo\":{\"gbuffer.normal\":\"packed\"}}", "demo.gbuffer.normal");
    rejects("{\"demo\":{\"gbuffer.normals\":\"float3\"}}", "demo.gbuffer.normals");
    rejects("{\"forward\":{\"x\":1}}", "forward.x");
    rejects("{\"forward\":5}", "forward");
    CHECK(parse("{\"forward\":{}}", &spec, &err));

    /* async_distance is OSL's option; the top-level field stays an alias,
     * and the spec as understood shows it in both places. */
    CHECK(parse("{\"async_distance\":20}", &spec, &err) &&
          ((const struct osl_options *)spec.options[2].bytes)->async_distance == 20.0);
    j = job_spec_to_json(&spec);
    CHECK(json_number_value(json_object_get(j, "async_distance")) == 20.0);
    json_decref(j);
    CHECK(parse("{\"technique\":\"osl\",\"osl\":{\"async_distance\":5}}", &spec, &err));
    j = job_spec_to_json(&spec);
    CHECK(json_number_value(json_object_get(json_object_get(j, "osl"), "async_distance")) == 5.0 &&
          json_number_value(json_object_get(j, "async_distance")) == 5.0);
    text = json_dumps(j, 0);
    CHECK(parse(text, &again, &err) && memcmp(&again, &spec, sizeof(spec)) == 0);
    free(text);
    json_decref(j);
    CHECK(parse("{\"technique\":\"osl\",\"async_distance\":5,\"osl\":{\"async_distance\":5.0}}",
                &spec, &err));
    rejects("{\"technique\":\"osl\",\"async_distance\":5,\"osl\":{\"async_distance\":0}}",
            "async_distance");
    rejects("{\"osl\":{\"async_distance\":-1}}", "osl.async_distance");
    CHECK(strcmp(job_spec_alias("async_distance"), "osl.async_distance") == 0 &&
          strcmp(job_spec_aliased("osl.async_distance"), "async_distance") == 0 &&
          !job_spec_alias("frames"));

    /* The catalogue a daemon builds, without GL: every registered technique
     * passes its checks, and the baseline is what a job runs by default. */
    {
        struct technique_catalog real;
        char why[256];
        CHECK(technique_catalog_init(&real, why, sizeof(why)) && real.count >= 8 &&
              real.baseline >= 0);
        CHECK(parse("{}", &spec, &err) &&
              strcmp(spec.technique, real.infos[real.baseline]->name) == 0);
        char list[400];
        technique_catalog_list(&real, TECHNIQUE_BOUNDED_LIGHT_LISTS, list, sizeof(list));
        CHECK(strstr(list, "\"clustered_deferred\"") && !strstr(list, "\"osl\""));
        CHECK(!technique_catalog_add(&real, real.infos[0], why, sizeof(why)) &&
              strstr(why, "registered twice"));
    }

    /* The look. */
    CHECK(parse("{}", &spec, &err) && spec.look.lighting == LOOK_PHONG &&
          spec.look.hdr == LOOK_HDR_RGBA32F);
    CHECK(parse("{\"look\":{\"lighting\":\"blinn_phong\",\"hdr\":\"rgba16f\"}}", &spec, &err) &&
          spec.look.lighting == LOOK_BLINN_PHONG && spec.look.hdr == LOOK_HDR_RGBA16F);
    rejects("{\"look\":{\"lighting\":\"pbr2\"}}", "look.lighting");
    rejects("{\"look\":{\"hdr\":\"rgb8\"}}", "look.hdr");
    rejects("{\"look\":{\"tonemap\":\"hable\"}}", "look.tonemap");

    /* Labels: sorted by key, kept in the spec as understood, and round-tripped. */
    CHECK(parse("{\"labels\":{\"commit\":\"abc123\",\"branch\":\"main\",\"ci.run\":\"\"}}",
                &spec, &err));
    CHECK(spec.nlabels == 3 && strcmp(spec.labels[0].key, "branch") == 0 &&
          strcmp(spec.labels[1].key, "ci.run") == 0 && strcmp(spec.labels[2].value, "abc123") == 0);
    j = job_spec_to_json(&spec);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(j, "labels"), "commit")),
                 "abc123") == 0);
    text = json_dumps(j, 0);
    CHECK(parse(text, &again, &err) && memcmp(&again, &spec, sizeof(spec)) == 0);
    free(text);
    json_decref(j);
    CHECK(parse("{}", &spec, &err) && spec.nlabels == 0);
    j = job_spec_to_json(&spec);
    CHECK(json_object_size(json_object_get(j, "labels")) == 0);
    json_decref(j);
    rejects("{\"labels\":[\"main\"]}", "labels");
    rejects("{\"labels\":{\"commit\":5}}", "labels.commit");
    rejects("{\"labels\":{\"bad key\":\"x\"}}", "labels.bad key");
    rejects("{\"labels\":{\"\":\"x\"}}", "labels.");
    rejects("{\"labels\":{\"k\":\"a\\nb\"}}", "labels.k");
    {
        char big[400];
        snprintf(big, sizeof(big), "{\"labels\":{\"v\":\"%0200d\"}}", 0);
        rejects(big, "labels.v");
        char many[600] = "{\"labels\":{";
        for (int i = 0; i < JOB_MAX_LABELS + 1; i++)
            snprintf(many + strlen(many), sizeof(many) - strlen(many), "%s\"k%d\":\"v\"",
                     i ? "," : "", i);
        strcat(many, "}}");
        rejects(many, "labels");
    }

    /* timeout_s: the daemon's default unless the job gives one; 0 is no limit. */
    job_spec_set_default_timeout(600);
    CHECK(parse("{}", &spec, &err) && spec.timeout_s == 600);
    CHECK(parse("{\"timeout_s\":2.5}", &spec, &err) && spec.timeout_s == 2.5);
    CHECK(parse("{\"timeout_s\":0}", &spec, &err) && spec.timeout_s == 0);
    rejects("{\"timeout_s\":-1}", "timeout_s");
    rejects("{\"timeout_s\":\"1h\"}", "timeout_s");
    job_spec_set_default_timeout(0);

    /* msaa: 1 unless given; 1, 2, 4 or 8, and at most the device's limit
     * once the daemon knows it; the framebuffers' estimate grows with it. */
    CHECK(parse("{}", &spec, &err) && spec.msaa == 1);
    CHECK(parse("{\"msaa\":8}", &spec, &err) && spec.msaa == 8);
    rejects("{\"msaa\":3}", "msaa");
    rejects("{\"msaa\":0}", "msaa");
    rejects("{\"msaa\":16}", "msaa");
    rejects("{\"msaa\":\"4x\"}", "msaa");
    job_spec_set_max_msaa(4);
    CHECK(parse("{\"msaa\":4}", &spec, &err) && spec.msaa == 4);
    rejects("{\"msaa\":8}", "msaa");
    {
        struct job_spec one, four;
        struct job_cost c1, c4;
        CHECK(parse("{}", &one, &err) && parse("{\"msaa\":4}", &four, &err));
        job_cost_estimate(&one, &c1);
        job_cost_estimate(&four, &c4);
        CHECK(c4.targets_bytes > 3.0 * c1.targets_bytes);
    }
    job_spec_set_max_msaa(0);

    /* At most 1000 captures a job, however small the frames. */
    rejects("{\"frames\":100000,\"capture_interval\":99,\"scene\":{\"width\":16,\"height\":16}}",
            "capture_interval");
    CHECK(parse("{\"frames\":100000,\"capture_interval\":100,\"scene\":{\"width\":16,"
                "\"height\":16}}", &spec, &err) && job_spec_capture_count(&spec) == 1000);

    /* A typo gets a suggestion. */
    parse("{\"frame\":10}", &spec, &err);
    CHECK(strstr(err.message, "'frames'") != NULL);
    parse("{\"scene\":{\"widht\":300}}", &spec, &err);
    CHECK(strstr(err.message, "'scene.width'") != NULL);
    /* Error texts are cut to their buffers at a UTF-8 boundary, and bytes
     * that are not UTF-8 are escaped: the error JSON is always built. */
    char key[128];
    for (int at = 36; at <= 42; at++) {
        /* "é" (2 bytes) straddling byte 40 of an unknown key. */
        memset(key, 'k', sizeof(key));
        memcpy(key + at, "\xc3\xa9", 2);
        key[60] = '\0';
        char text[256];
        snprintf(text, sizeof(text), "{\"%s\": 1}", key);
        CHECK(!parse(text, &spec, &err));
        json_t *e = job_error_to_json(&err);
        CHECK(e != NULL);
        CHECK(json_string_value(json_object_get(json_object_get(e, "error"), "field")) != NULL);
        json_decref(e);
    }
    /* A syntax error whose quoted token is cut inside a 3-byte character. */
    char bad[600] = "{\"frames\": ";
    for (int i = 0; i < 150; i++)
        strcat(bad, "\xe2\x82\xac");
    CHECK(!parse(bad, &spec, &err));
    json_t *e = job_error_to_json(&err);
    CHECK(e != NULL);
    char *dump = e ? json_dumps(e, 0) : NULL;
    CHECK(dump != NULL);
    free(dump);
    json_decref(e);
    /* Invalid bytes are escaped, a cut character is dropped. */
    char msg[32] = "a\xff b \xe2\x82";
    jf_utf8_sanitize(msg, sizeof(msg));
    CHECK(strcmp(msg, "a\\xff b ") == 0);
    char fits[8] = "abcdef";
    jf_utf8_sanitize(fits, 6); /* room for 5 bytes */
    CHECK(strcmp(fits, "abcde") == 0);
    CHECK(jf_utf8_prefix("ab\xc3\xa9", 3) == 2 && jf_utf8_prefix("ab\xc3\xa9", 4) == 4);
    struct job_error raw;
    snprintf(raw.field, sizeof(raw.field), "x\xc3");
    snprintf(raw.message, sizeof(raw.message), "\x80\x80");
    e = job_error_to_json(&raw);
    CHECK(e != NULL);
    json_decref(e);
    test_cost();
    test_cost_planes();
    test_eta();
    test_max_seconds();
    return check_finish("test_job");
}
