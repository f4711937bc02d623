/* The frame contract's GL-free half (common/frame_needs.h) and what rests
 * on it: TAA's jitter sequence (Halton 2, 3, centred, repeating, negative
 * frames included) and its needs; the job rules that keep frame k a pure
 * function of k (captures further apart than the history, enough warm-up
 * before the first), the reference that leaves TAA out, TAA's bad options
 * named; scene.mover (parse, path, pure in the frame); and the visibility
 * buffer's id packing. */
#include <math.h>
#include <string.h>

#include "common/frame_needs.h"
#include "daemon/effects/taa/taa_info.h"
#include "daemon/spec/job_spec.h"
#include "daemon/scene/scene.h"
#include "daemon/techniques/visibility_buffer/visibility_buffer_info.h"
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
    CHECK(ok || strcmp(err.field, field) == 0);
    if (ok || strcmp(err.field, field) != 0)
        fprintf(stderr, "  for %s: got field '%s' (%s)\n", text, ok ? "" : err.field,
                ok ? "accepted" : err.message);
}

static void test_jitter(void)
{
    /* The radical inverses themselves. */
    CHECK(frame_halton(1, 2) == 0.5 && frame_halton(2, 2) == 0.25 && frame_halton(3, 2) == 0.75);
    CHECK(fabs(frame_halton(1, 3) - 1.0 / 3) < 1e-15 && fabs(frame_halton(2, 3) - 2.0 / 3) < 1e-15 &&
          fabs(frame_halton(3, 3) - 1.0 / 9) < 1e-15);
    CHECK(frame_halton(0, 2) == 0.0);
    /* Frame k takes index 1 + (k mod N), centred: the first eight of TAA's
     * default sequence, as published (Karis 2014's Halton 2, 3). */
    static const double expect[8][2] = {
        {1.0 / 2, 1.0 / 3}, {1.0 / 4, 2.0 / 3}, {3.0 / 4, 1.0 / 9},  {1.0 / 8, 4.0 / 9},
        {5.0 / 8, 7.0 / 9}, {3.0 / 8, 2.0 / 9}, {7.0 / 8, 5.0 / 9}, {1.0 / 16, 8.0 / 9},
    };
    for (int k = 0; k < 8; k++) {
        float j[2];
        frame_jitter(8, k, j);
        CHECK(fabsf(j[0] - (float)(expect[k][0] - 0.5)) < 1e-7f);
        CHECK(fabsf(j[1] - (float)(expect[k][1] - 0.5)) < 1e-7f);
        CHECK(j[0] > -0.5f && j[0] < 0.5f && j[1] > -0.5f && j[1] < 0.5f);
    }
    /* It repeats every N frames, warm-up frames (negative) included, and
     * length 0 is no jitter. */
    for (int64_t k = -20; k < 20; k++) {
        float a[2], b[2];
        frame_jitter(8, k, a);
        frame_jitter(8, k + 8, b);
        CHECK(a[0] == b[0] && a[1] == b[1]);
        frame_jitter(0, k, a);
        CHECK(a[0] == 0.0f && a[1] == 0.0f);
    }
    /* The sequence covers the pixel: its mean over a period is near the
     * centre. */
    double mx = 0, my = 0;
    for (int k = 0; k < 16; k++) {
        float j[2];
        frame_jitter(16, k, j);
        mx += j[0] / 16.0, my += j[1] / 16.0;
    }
    CHECK(fabs(mx) < 0.05 && fabs(my) < 0.05);
}

static void test_needs(void)
{
    struct job_spec spec;
    struct job_error err;
    struct frame_needs n;
    /* No TAA: nothing. */
    CHECK(parse("{\"frames\": 4}", &spec, &err));
    job_spec_needs(&spec, false, &n);
    CHECK(n.history_frames == 0 && n.jitter_length == 0 && !n.motion_vectors);
    /* TAA's defaults and options. */
    CHECK(parse("{\"frames\": 40, \"warmup_frames\": 16, \"look\": {\"post\": [\"taa\"]}}", &spec,
                &err));
    job_spec_needs(&spec, false, &n);
    CHECK(n.history_frames == 16 && n.jitter_length == 8 && n.motion_vectors);
    CHECK(parse("{\"frames\": 40, \"look\": {\"post\": [{\"taa\": {\"history\": 4, "
                "\"jitter_length\": 0, \"clamp\": \"aabb\", \"blend\": 0.2}}]}}",
                &spec, &err));
    job_spec_needs(&spec, false, &n);
    CHECK(n.history_frames == 4 && n.jitter_length == 0 && n.motion_vectors);
    const struct taa_options *o = post_effect_options(&spec.look.post, 0);
    CHECK(o->clamp == TAA_CLAMP_AABB && o->blend == 0.2 && o->filter == TAA_FILTER_CATMULL_ROM);
    /* Merging takes the larger of each. */
    struct frame_needs a = {.history_frames = 3, .jitter_length = 16};
    struct frame_needs b = {.history_frames = 8, .jitter_length = 4, .motion_vectors = true};
    frame_needs_merge(&a, &b);
    CHECK(a.history_frames == 8 && a.jitter_length == 16 && a.motion_vectors);
}

static void test_job_rules(void)
{
    struct job_spec spec;
    struct job_error err;
    /* The reference leaves TAA out (it is the truth TAA approximates) and
     * keeps the rest of the chain; a reference_look given is kept whole. */
    CHECK(parse("{\"frames\": 40, \"warmup_frames\": 16, \"reference\": \"forward\", "
                "\"look\": {\"post\": [\"taa\", \"bloom\"]}}", &spec, &err));
    CHECK(spec.look.post.count == 2 && spec.reference_look.post.count == 1);
    CHECK(strcmp(effect_infos[spec.reference_look.post.effects[0].effect]->name, "bloom") == 0);
    struct frame_needs n;
    job_spec_needs(&spec, true, &n);
    CHECK(n.history_frames == 0 && !n.motion_vectors);
    CHECK(parse("{\"frames\": 40, \"warmup_frames\": 16, \"reference\": \"forward\", "
                "\"look\": {\"post\": [\"taa\"]}, \"reference_look\": {\"post\": [\"taa\"]}}",
                &spec, &err));
    CHECK(spec.reference_look.post.count == 1);
    /* Captures closer than the history would cut it short: refused naming
     * capture_interval; one capture, or captures further apart, pass. */
    rejects("{\"frames\": 40, \"warmup_frames\": 16, \"capture_interval\": 10, "
            "\"look\": {\"post\": [\"taa\"]}}", "capture_interval");
    rejects("{\"frames\": 40, \"warmup_frames\": 16, \"capture_interval\": 16, "
            "\"look\": {\"post\": [\"taa\"]}}", "capture_interval");
    CHECK(parse("{\"frames\": 40, \"warmup_frames\": 16, \"capture_interval\": 17, "
                "\"look\": {\"post\": [\"taa\"]}}", &spec, &err));
    CHECK(parse("{\"frames\": 10, \"warmup_frames\": 16, \"capture_interval\": 10, "
                "\"look\": {\"post\": [\"taa\"]}}", &spec, &err));
    CHECK(parse("{\"frames\": 40, \"capture_interval\": 5, \"warmup_frames\": 4, "
                "\"look\": {\"post\": [{\"taa\": {\"history\": 4}}]}}", &spec, &err));
    /* The first capture's history must fit in the frames before it. */
    rejects("{\"frames\": 10, \"warmup_frames\": 2, \"capture_interval\": 10, "
            "\"look\": {\"post\": [\"taa\"]}}", "warmup_frames");
    CHECK(parse("{\"frames\": 10, \"warmup_frames\": 7, \"capture_interval\": 10, "
                "\"look\": {\"post\": [\"taa\"]}}", &spec, &err));
    /* No captures, no rule. */
    CHECK(parse("{\"frames\": 10, \"warmup_frames\": 0, \"look\": {\"post\": [\"taa\"]}}", &spec,
                &err));
    /* TAA's bad options are named. */
    rejects("{\"look\": {\"post\": [{\"taa\": {\"blend\": 0}}]}}", "look.post[0].blend");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"blend\": 1.5}}]}}", "look.post[0].blend");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"clamp\": \"box\"}}]}}", "look.post[0].clamp");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"jitter_length\": -1}}]}}",
            "look.post[0].jitter_length");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"jitter_length\": 300}}]}}",
            "look.post[0].jitter_length");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"history\": 0}}]}}", "look.post[0].history");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"history\": 65}}]}}", "look.post[0].history");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"filter\": \"lanczos\"}}]}}",
            "look.post[0].filter");
    rejects("{\"look\": {\"post\": [{\"taa\": {\"gamma\": 10}}]}}", "look.post[0].gamma");
    /* The visibility buffer's. */
    rejects("{\"technique\": \"visibility_buffer\", \"visibility_buffer\": {\"lights\": \"tiled\"}}",
            "visibility_buffer.lights");
    rejects("{\"technique\": \"visibility_buffer\", \"visibility_buffer\": {\"ids\": 32}}",
            "visibility_buffer.ids");
    rejects("{\"technique\": \"visibility_buffer\", \"visibility_buffer\": {\"grid\": [2048, 1024, 64]}}",
            "visibility_buffer.grid");
}

static void test_mover(void)
{
    struct job_spec spec;
    struct job_error err;
    CHECK(parse("{\"scene\": {\"preset\": \"grid\", \"mover\": true}}", &spec, &err));
    CHECK(spec.scene.mover && spec.scene.mover_period == 120);
    CHECK(parse("{\"scene\": {\"preset\": \"lights\", \"mover\": {\"period\": 40}}}", &spec, &err));
    CHECK(spec.scene.mover && spec.scene.mover_period == 40);
    rejects("{\"scene\": {\"mover\": {\"period\": 1}}}", "scene.mover.period");
    rejects("{\"scene\": {\"mover\": {\"speed\": 1}}}", "scene.mover.speed");
    rejects("{\"scene\": {\"mover\": 3}}", "scene.mover");
    rejects("{\"scene\": {\"preset\": \"textured\", \"mover\": true}}", "scene.mover");
    /* Written back only when on, and read back the same. */
    json_t *js = scene_spec_to_json(&spec.scene);
    CHECK(json_integer_value(json_object_get(json_object_get(js, "mover"), "period")) == 40);
    json_decref(js);
    CHECK(parse("{\"scene\": {\"preset\": \"lights\"}}", &spec, &err));
    js = scene_spec_to_json(&spec.scene);
    CHECK(json_object_get(js, "mover") == NULL);
    json_decref(js);

    /* The mover: one sphere more, after the last sphere, sliding along x at
     * a constant speed, there and back every period; the others stand. */
    struct scene plain, moving;
    struct scene_spec sp;
    scene_spec_defaults(&sp);
    sp.width = 64, sp.height = 48;
    CHECK(scene_init(&plain, &sp));
    sp.mover = true;
    sp.mover_period = 40;
    CHECK(scene_init(&moving, &sp));
    CHECK(plain.mover == -1 && moving.mover >= 0);
    CHECK(moving.instance_count == plain.instance_count + 1);
    CHECK(moving.mesh_instance_count[SCENE_MESH_SPHERE] ==
          plain.mesh_instance_count[SCENE_MESH_SPHERE] + 1);
    CHECK(moving.instances[moving.mover].mesh == SCENE_MESH_SPHERE);
    CHECK(moving.mover + 1 == moving.instance_count ||
          moving.instances[moving.mover + 1].mesh != SCENE_MESH_SPHERE);
    float a[4], b[4], c[4], d[4];
    scene_instance_at(&moving, moving.mover, 0, a);
    scene_instance_at(&moving, moving.mover, 20, b);
    scene_instance_at(&moving, moving.mover, 40, c);
    scene_instance_at(&moving, moving.mover, -40, d);
    CHECK(a[0] == moving.mover_from[0] && b[0] == moving.mover_to[0] && b[0] > a[0]);
    CHECK(memcmp(a, c, sizeof(a)) == 0 && memcmp(a, d, sizeof(a)) == 0);
    float s1[4], s2[4], s3[4];
    scene_instance_at(&moving, moving.mover, 5, s1);
    scene_instance_at(&moving, moving.mover, 6, s2);
    scene_instance_at(&moving, moving.mover, 7, s3);
    CHECK(fabsf((s2[0] - s1[0]) - (s3[0] - s2[0])) < 1e-4f && s2[0] > s1[0]);
    CHECK(s1[1] == s2[1] && s1[2] == s2[2] && s1[3] == a[3]);
    scene_instance_at(&moving, moving.mover, 25, s1);
    CHECK(s1[0] < b[0]); /* on its way back */
    float still[4];
    int other = moving.mover == 0 ? 1 : 0;
    scene_instance_at(&moving, other, 17, still);
    CHECK(memcmp(still, moving.instances[other].pos, 3 * sizeof(float)) == 0);
    /* Above the objects the camera frames, whose bounds it leaves alone. */
    CHECK(a[1] > plain.objects.max[1]);
    CHECK(memcmp(&moving.objects, &plain.objects, sizeof(plain.objects)) == 0);
    scene_finish(&plain);
    scene_finish(&moving);
}

static void test_vis_ids(void)
{
    /* 512 instances and 8192 triangles: 13 bits of triangle, 10 of
     * instance; one more instance bit than there is room for: wide. */
    CHECK(vis_triangle_bits(512, 8192) == 13);
    CHECK(vis_triangle_bits(1, 1) == 0);
    CHECK(vis_triangle_bits(1, 2) == 1);
    CHECK(vis_triangle_bits(1023, 1 << 22) == 22);
    CHECK(vis_triangle_bits(1024, 1 << 22) == -1);
    CHECK(vis_triangle_bits(1, 1LL << 31) == 31);
    CHECK(vis_triangle_bits(2, 1LL << 31) == -1);
    int bits = vis_triangle_bits(512, 8192), inst;
    uint32_t tri;
    CHECK(!vis_unpack(0, bits, &inst, &tri));
    for (int i = 0; i < 512; i += 37)
        for (uint32_t t = 0; t < 8192; t += 911) {
            uint32_t id = vis_pack(i, t, bits);
            CHECK(id != 0 && vis_unpack(id, bits, &inst, &tri) && inst == i && tri == t);
        }
}

int main(void)
{
    test_jitter();
    test_needs();
    test_job_rules();
    test_mover();
    test_vis_ids();
    return check_finish("test_temporal");
}
