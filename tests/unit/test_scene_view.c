/* Scenes stated as users state them (GL-free): scene.camera as a pose
 * (perspective and orthographic, the up vector, derived planes), points
 * projected to hand-computed pixels, scene.light_rig parsed and built in
 * glTF's units, and the tone curves srgb and pbr_neutral against the
 * Khronos specification's equations. */
#define _GNU_SOURCE /* M_PI */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lighting/tone_curves.h"
#include "daemon/scene/scene.h"
#include "daemon/scene/scene_build.h" /* scene_mat4_* */
#include "tests/unit/check.h"

static bool parse(const char *json, struct scene_spec *spec, struct job_error *err)
{
    scene_spec_defaults(spec);
    memset(err, 0, sizeof(*err));
    json_error_t jerr;
    json_t *j = json_loads(json, 0, &jerr);
    CHECK(j != NULL);
    bool ok = j && scene_spec_parse(j, spec, err);
    json_decref(j);
    return ok;
}

static void rejects(const char *json, const char *field)
{
    struct scene_spec spec;
    struct job_error err;
    bool ok = parse(json, &spec, &err);
    CHECK(!ok);
    if (strcmp(err.field, field) != 0)
        fprintf(stderr, "  %s: field %s (%s), expected %s\n", json, err.field, err.message,
                field);
    CHECK(strcmp(err.field, field) == 0);
}

/* Window pixel (x from the left, y from the bottom) of world point p. */
static void project(const struct scene_camera *c, int w, int h, const float p[3], double px[2])
{
    float clip[4];
    scene_mat4_transform(c->view_proj, p, 1.0f, clip);
    px[0] = (clip[0] / clip[3] * 0.5 + 0.5) * w;
    px[1] = (clip[1] / clip[3] * 0.5 + 0.5) * h;
}

static void build(const char *json, struct scene *s)
{
    struct scene_spec spec;
    struct job_error err;
    CHECK(parse(json, &spec, &err));
    if (err.field[0])
        fprintf(stderr, "  %s: %s %s\n", json, err.field, err.message);
    CHECK(scene_init(s, &spec));
}

static void test_pose_parse(void)
{
    rejects("{\"camera\": {\"eye\": [0, 1, 2]}}", "scene.camera.target");
    rejects("{\"camera\": {\"target\": [0, 1, 2]}}", "scene.camera.eye");
    rejects("{\"camera\": {\"eye\": [1, 1, 1], \"target\": [1, 1, 1]}}", "scene.camera.target");
    rejects("{\"camera\": {\"eye\": [0, 5, 0], \"target\": [0, 0, 0]}}", "scene.camera.up");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, 0]}}",
            "scene.camera.up");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"yfov_deg\": 40, "
            "\"orthographic\": {\"ymag\": 1}}}", "scene.camera.orthographic");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"orthographic\": "
            "{\"xmag\": 1}}}", "scene.camera.orthographic.ymag");
    rejects("{\"camera\": {\"path\": \"orbit\", \"eye\": [0, 0, 5], \"target\": [0, 0, 0], "
            "\"orthographic\": {\"ymag\": 1}}}", "scene.camera.orthographic");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"near\": 1}}",
            "scene.camera.far");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"near\": 2, \"far\": 1}}",
            "scene.camera.far");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"yfov_deg\": 180}}",
            "scene.camera.yfov_deg");
    rejects("{\"camera\": {\"eye\": [0, \"a\", 5], \"target\": [0, 0, 0]}}", "scene.camera.eye");
    rejects("{\"camera\": {\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"fov\": 3}}",
            "scene.camera.fov");

    /* Round trip: what is written back parses to the same pose. */
    struct scene_spec a, b;
    struct job_error err;
    CHECK(parse("{\"camera\": {\"eye\": [1, 2, 3], \"target\": [0, 0, 0], \"up\": [0, 0, 2], "
                "\"orthographic\": {\"ymag\": 1.5}, \"near\": 0.5, \"far\": 9}}",
                &a, &err));
    CHECK(a.view.given && a.view.orthographic && a.view.ymag == 1.5 && a.view.xmag == 0);
    CHECK(a.view.up[2] == 1.0); /* normalised */
    json_t *j = scene_spec_to_json(&a);
    scene_spec_defaults(&b);
    CHECK(scene_spec_parse(j, &b, &err));
    CHECK(memcmp(&a.view, &b.view, sizeof(a.view)) == 0);
    json_decref(j);
    /* A path string clears a pose given before. */
    CHECK(parse("{\"camera\": \"orbit\"}", &b, &err) && !b.view.given);
}

static void test_perspective_pose(void)
{
    /* Looking down -z from (0, 0, 10) at 90 degrees on a 200 x 100 image:
     * (1, 0.5, 0) is 10 away, at x = 1 / (10 tan 45 x aspect 2) = 0.05 and
     * y = 0.5 / 10 = 0.05 in NDC: pixel (105, 52.5). */
    struct scene s;
    build("{\"preset\": \"sphere\", \"width\": 200, \"height\": 100, \"camera\": {\"eye\": "
          "[0, 0, 10], \"target\": [0, 0, 0], \"yfov_deg\": 90, \"near\": 1, \"far\": 100}}", &s);
    struct scene_camera c;
    scene_camera_at(&s, 0, &c);
    CHECK(!c.orthographic && c.fovy_deg == 90.0f && c.near_z == 1.0f && c.far_z == 100.0f);
    double px[2];
    project(&c, 200, 100, (const float[3]){1.0f, 0.5f, 0.0f}, px);
    CHECK_NEAR(px[0], 105.0, 1e-3);
    CHECK_NEAR(px[1], 52.5, 1e-3);
    scene_finish(&s);

    /* The up vector turns the image: with up +x, +x is the top of the
     * image and +y its left (right = forward x up = -z x +x = -y). */
    build("{\"preset\": \"sphere\", \"width\": 100, \"height\": 100, \"camera\": {\"eye\": "
          "[0, 0, 10], \"target\": [0, 0, 0], \"up\": [1, 0, 0], \"yfov_deg\": 90}}", &s);
    scene_camera_at(&s, 0, &c);
    project(&c, 100, 100, (const float[3]){1.0f, 0.0f, 0.0f}, px);
    CHECK_NEAR(px[0], 50.0, 1e-3);
    CHECK_NEAR(px[1], 55.0, 1e-3);
    project(&c, 100, 100, (const float[3]){0.0f, 1.0f, 0.0f}, px);
    CHECK_NEAR(px[0], 45.0, 1e-3);
    /* Derived planes hold the bounds: every corner between them. */
    CHECK(c.near_z > 0 && c.far_z > c.near_z);
    for (int corner = 0; corner < 8; corner++) {
        float p[3], v[4];
        for (int k = 0; k < 3; k++)
            p[k] = corner >> k & 1 ? s.bounds.max[k] : s.bounds.min[k];
        scene_mat4_transform(c.view, p, 1.0f, v);
        CHECK(-v[2] > c.near_z && -v[2] < c.far_z);
    }
    json_t *d = scene_describe(&s);
    json_t *cam = json_object_get(d, "camera");
    CHECK(strcmp(json_string_value(json_object_get(cam, "source")), "scene.camera") == 0);
    CHECK(json_array_size(json_object_get(cam, "view_matrix")) == 16);
    CHECK(json_real_value(json_array_get(json_object_get(cam, "up_at_frame_0"), 0)) == 1.0);
    json_decref(d);
    scene_finish(&s);
}

static void test_orthographic_pose(void)
{
    /* xmag 2, ymag 1 on 160 x 120: (1, 0.5, 0) at NDC (0.5, 0.5), pixel
     * (120, 90), whatever its distance; the image is stretched to the
     * extents as glTF's projection does. */
    struct scene s;
    build("{\"preset\": \"sphere\", \"width\": 160, \"height\": 120, \"camera\": {\"eye\": "
          "[0, 0, 10], \"target\": [0, 0, 0], \"orthographic\": {\"xmag\": 2, \"ymag\": 1}, "
          "\"near\": 1, \"far\": 30}}", &s);
    struct scene_camera c;
    scene_camera_at(&s, 0, &c);
    CHECK(c.orthographic && c.xmag == 2.0f && c.ymag == 1.0f);
    double px[2];
    project(&c, 160, 120, (const float[3]){1.0f, 0.5f, 0.0f}, px);
    CHECK_NEAR(px[0], 120.0, 1e-3);
    CHECK_NEAR(px[1], 90.0, 1e-3);
    project(&c, 160, 120, (const float[3]){1.0f, 0.5f, -15.0f}, px);
    CHECK_NEAR(px[0], 120.0, 1e-3);
    /* Depth: the near plane at NDC -1, the far at +1, the inverse exact. */
    float clip[4], back[4];
    scene_mat4_transform(c.view_proj, (const float[3]){0, 0, 9}, 1.0f, clip);
    CHECK_NEAR(clip[2] / clip[3], -1.0, 1e-5);
    scene_mat4_transform(c.view_proj, (const float[3]){0, 0, -20}, 1.0f, clip);
    CHECK_NEAR(clip[2] / clip[3], 1.0, 1e-5);
    float m[16];
    scene_mat4_mul(m, c.inv_proj, c.proj);
    scene_mat4_transform(m, (const float[3]){0.3f, -0.7f, 4.0f}, 1.0f, back);
    CHECK_NEAR(back[0], 0.3, 1e-5);
    CHECK_NEAR(back[2], 4.0, 1e-4);
    CHECK(!scene_camera_moves(&s));
    scene_finish(&s);

    /* xmag left out: ymag times the image's aspect (no stretch). */
    build("{\"preset\": \"sphere\", \"width\": 160, \"height\": 120, \"camera\": {\"eye\": "
          "[0, 0, 10], \"target\": [0, 0, 0], \"orthographic\": {\"ymag\": 3}}}", &s);
    scene_camera_at(&s, 0, &c);
    CHECK_NEAR(c.xmag, 4.0f, 1e-6f);
    scene_finish(&s);
}

static void test_light_rig(void)
{
    rejects("{\"light_rig\": [{\"position\": [0, 1, 0]}]}", "scene.light_rig[0].type");
    rejects("{\"light_rig\": [{\"type\": \"point\"}]}", "scene.light_rig[0].position");
    rejects("{\"light_rig\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"direction\": "
            "[0, -1, 0]}]}", "scene.light_rig[0].direction");
    rejects("{\"light_rig\": [{\"type\": \"directional\"}]}", "scene.light_rig[0].direction");
    rejects("{\"light_rig\": [{\"type\": \"directional\", \"direction\": [0, -1, 0], "
            "\"range\": 3}]}", "scene.light_rig[0].range");
    rejects("{\"light_rig\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": "
            "[0, -1, 0], \"inner_cone_deg\": 40, \"outer_cone_deg\": 30}]}",
            "scene.light_rig[0].inner_cone_deg");
    rejects("{\"light_rig\": [{\"type\": \"point\", \"position\": [0, 1, 0], "
            "\"outer_cone_deg\": 30}]}", "scene.light_rig[0].outer_cone_deg");
    rejects("{\"light_rig\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": "
            "-1}]}", "scene.light_rig[0].intensity");
    rejects("{\"light_rig\": [{\"type\": \"area\", \"position\": [0, 1, 0]}]}",
            "scene.light_rig[0].type");
    rejects("{\"light_rig\": {\"type\": \"point\"}}", "scene.light_rig");

    /* A rig replaces the generated lights unless scene.lights says; its
     * lights come last, in glTF's falloff, colour = colour x I / pi. */
    struct scene s;
    build("{\"preset\": \"plane\", \"light_rig\": [{\"type\": \"point\", \"position\": [0, 2, 0], "
          "\"color\": [1, 0.5, 0.25], \"intensity\": 8, \"range\": 6}, {\"type\": \"spot\", "
          "\"position\": [1, 3, 0], \"direction\": [0, -2, 0], \"intensity\": 100, "
          "\"inner_cone_deg\": 10, \"outer_cone_deg\": 20}, {\"type\": \"directional\", "
          "\"direction\": [0, -1, 0], \"intensity\": 3}]}", &s);
    CHECK(s.light_count == 3 && s.rig_light_count == 3);
    const struct scene_light *p = &s.lights[0], *sp = &s.lights[1], *dir = &s.lights[2];
    CHECK(p->falloff == SCENE_FALLOFF_GLTF && p->range == 6.0f && p->radius == 6.0f);
    CHECK_NEAR(p->color[1], 0.5 * 8 / M_PI, 1e-5);
    CHECK(sp->type == SCENE_LIGHT_SPOT && sp->direction[1] == -1.0f);
    CHECK_NEAR(sp->cos_inner, cos(10 * M_PI / 180), 1e-6);
    CHECK_NEAR(sp->cos_outer, cos(20 * M_PI / 180), 1e-6);
    CHECK_NEAR(sp->radius, sqrt(100 * 1024 / M_PI), 1e-2); /* no range: the cut-off */
    CHECK(dir->type == SCENE_LIGHT_DIRECTIONAL);
    CHECK_NEAR(dir->color[0], 3 / M_PI, 1e-6);
    json_t *d = scene_describe(&s);
    json_t *list = json_object_get(json_object_get(d, "gltf_lights"), "lights");
    CHECK(json_array_size(list) == 3);
    json_t *l0 = json_array_get(list, 0);
    CHECK(strcmp(json_string_value(json_object_get(l0, "source")), "light_rig") == 0);
    CHECK(json_real_value(json_object_get(l0, "intensity")) == 8.0);
    CHECK(json_real_value(json_object_get(l0, "range")) == 6.0);
    CHECK_NEAR(json_real_value(json_object_get(json_array_get(list, 1), "outer_cone_deg")), 20.0,
               1e-3);
    json_decref(d);
    scene_finish(&s);
    /* The sun is listed in glTF's terms too: pi lux of its colour. */
    build("{\"preset\": \"plane\", \"sun\": true, \"light_rig\": [{\"type\": \"point\", "
          "\"position\": [0, 2, 0]}]}", &s);
    d = scene_describe(&s);
    list = json_object_get(json_object_get(d, "gltf_lights"), "lights");
    CHECK(json_array_size(list) == 2);
    json_t *sun = json_array_get(list, 0);
    CHECK(strcmp(json_string_value(json_object_get(sun, "source")), "sun") == 0);
    CHECK_NEAR(json_real_value(json_object_get(sun, "intensity")), M_PI, 1e-5);
    CHECK_NEAR(json_real_value(json_array_get(json_object_get(sun, "color"), 0)),
               SCENE_SUN_COLOR[0], 1e-6);
    json_decref(d);
    scene_finish(&s);
    /* With lights given, the generated ones stay. */
    build("{\"preset\": \"plane\", \"lights\": 2, \"light_rig\": [{\"type\": \"point\", "
          "\"position\": [0, 2, 0]}]}", &s);
    CHECK(s.light_count == 3 && s.lights[0].falloff == SCENE_FALLOFF_WINDOW &&
          s.lights[2].falloff == SCENE_FALLOFF_GLTF);
    scene_finish(&s);
    /* Written back as given, with the defaults filled in. */
    struct scene_spec a, b;
    struct job_error err;
    CHECK(parse("{\"light_rig\": [{\"type\": \"spot\", \"position\": [0, 2, 0], \"direction\": "
                "[0, -1, 0]}]}", &a, &err));
    CHECK(a.lights == 0 && a.rig[0].outer_cone_deg == 45.0 && a.rig[0].intensity == 1.0);
    json_t *j = scene_spec_to_json(&a);
    scene_spec_defaults(&b);
    CHECK(scene_spec_parse(j, &b, &err) && b.rig_count == 1);
    CHECK(memcmp(&a.rig[0], &b.rig[0], sizeof(a.rig[0])) == 0);
    json_decref(j);
}

/* Khronos PBR Neutral as its specification writes it (ToneMapping/
 * PBR_Neutral/README.md): f, p, p_n, g. */
static void pbr_neutral_spec(const double in[3], double out[3])
{
    const double F90 = 0.04, Ks = 0.8 - F90, Kd = 0.15;
    double x = fmin(in[0], fmin(in[1], in[2]));
    double f = x <= 2 * F90 ? x - x * x / (4 * F90) : F90;
    double p = fmax(in[0] - f, fmax(in[1] - f, in[2] - f));
    double pn = 1 - (1 - Ks) * (1 - Ks) / (p + 1 - 2 * Ks);
    double g = 1 / (Kd * (p - pn) + 1);
    for (int k = 0; k < 3; k++)
        out[k] = p <= Ks ? in[k] - f : (in[k] - f) * pn / p * g + pn * (1 - g);
}

static void test_tone_curves(void)
{
    /* Base colours 0.08..0.8 come out less F90, exactly. */
    double c[3] = {0.5, 0.3, 0.1};
    tonemap_pbr_neutral(c);
    CHECK_NEAR(c[0], 0.46, 1e-12);
    CHECK_NEAR(c[2], 0.06, 1e-12);
    const double cases[][3] = {{0, 0, 0},       {0.02, 0.05, 0.07}, {0.9, 0.2, 0.1},
                               {4.0, 2.0, 1.0}, {100, 100, 100},    {0.76, 0.05, 0.8}};
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        double got[3] = {cases[i][0], cases[i][1], cases[i][2]}, want[3];
        tonemap_pbr_neutral(got);
        pbr_neutral_spec(cases[i], want);
        for (int k = 0; k < 3; k++) {
            CHECK_NEAR(got[k], want[k], 1e-12);
            CHECK(got[k] >= 0 && got[k] <= 1);
        }
    }
    /* No hue shift: the output stays in the plane of the input and white. */
    double h[3] = {3.0, 1.5, 0.75};
    tonemap_pbr_neutral(h);
    CHECK(h[0] > h[1] && h[1] > h[2]);
    CHECK_NEAR((h[0] - h[1]) / (h[1] - h[2]), 2.0, 1e-9);
    /* srgb is the curve-less encode. */
    CHECK_NEAR(srgb_encode(0.2140), 0.5, 1e-3);
    /* The viewer's gamma 2.2 against sRGB: equal at the ends, apart in the
     * shadows (linear 0.01: 25.5 and 31.4 of 255). */
    CHECK(gamma22_encode(0) == 0 && gamma22_encode(1) == 1 && gamma22_encode(2) == 1);
    CHECK_NEAR(255 * srgb_encode(0.01), 25.46, 0.01);
    CHECK_NEAR(255 * gamma22_encode(0.01), 31.44, 0.01);
}

int main(void)
{
    test_pose_parse();
    test_perspective_pose();
    test_orthographic_pose();
    test_light_rig();
    test_tone_curves();
    return check_finish("test_scene_view");
}
