/* The GL-free halves of the harness's look features: cube faces (the
 * matrices the probes and the shadow maps render with agree with the face
 * table the shaders sample), the shadow plan (importance, sizes, packing,
 * overflow dropped least important first or failing with the lights
 * named, the cubes layout), probe placement and selection, and the
 * look.ibl / look.shadows options (field-naming errors, round trips). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lighting/cube_faces.h"
#include "daemon/lighting/ibl_plan.h"
#include "daemon/lighting/look_lighting.h"
#include "daemon/lighting/shadow_plan.h"
#include "daemon/scene/scene.h"
#include "tests/unit/check.h"

static void transform(const float m[16], const float p[3], float out[4])
{
    for (int r = 0; r < 4; r++)
        out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
}

/* A direction rendered by a face's matrix lands at the (s, t) the face
 * table gives it, at the depth cube_face_depth predicts. */
static void test_cube_faces(void)
{
    const float eye[3] = {1.0f, 2.0f, -3.0f};
    for (int f = 0; f < 6; f++) {
        float fw[3], sa[3], ta[3], m[16];
        cube_face_axes(f, fw, sa, ta);
        cube_face_view_proj(f, eye, 1.25f, 0.1f, 20.0f, m);
        static const float st[][2] = {{0, 0}, {0.5f, -0.25f}, {-0.9f, 0.7f}};
        for (int k = 0; k < 3; k++) {
            float dist = 3.0f, p[3], c[4];
            for (int a = 0; a < 3; a++)
                p[a] = eye[a] + dist * (fw[a] + st[k][0] * sa[a] + st[k][1] * ta[a]);
            transform(m, p, c);
            CHECK_NEAR(c[0] / c[3], st[k][0] / 1.25f, 1e-5);
            CHECK_NEAR(c[1] / c[3], st[k][1] / 1.25f, 1e-5);
            CHECK_NEAR(0.5f * c[2] / c[3] + 0.5f, cube_face_depth(dist, 0.1f, 20.0f), 1e-5);
            float d[3] = {p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
            CHECK(cube_face_of(d) == f);
        }
        /* s x t = -forward... each face's view is a rotation (det +1). */
        float cx[3] = {sa[1] * ta[2] - sa[2] * ta[1], sa[2] * ta[0] - sa[0] * ta[2],
                       sa[0] * ta[1] - sa[1] * ta[0]};
        CHECK_NEAR(cx[0] * fw[0] + cx[1] * fw[1] + cx[2] * fw[2], -1.0, 1e-6);
    }
    CHECK_NEAR(cube_face_depth(0.1f, 0.1f, 20.0f), 0.0, 1e-6);
    CHECK_NEAR(cube_face_depth(20.0f, 0.1f, 20.0f), 1.0, 1e-5);
    CHECK_NEAR(shadow_face_widen(64, 2), 64.0 / 60.0, 1e-6);
}

static void teapots(struct scene *s, int lights, int width)
{
    struct scene_spec spec;
    scene_spec_defaults(&spec);
    scene_spec_preset_defaults(&spec, SCENE_PRESET_TEAPOTS);
    spec.lights = lights;
    spec.width = width;
    spec.height = width * 3 / 4;
    spec.teapot_segments = 2;
    CHECK(scene_init(s, &spec));
}

static bool overlaps(const struct shadow_plan *p)
{
    for (int a = 0; a < p->lights; a++)
        for (int fa = 0; fa < 6 && p->light[a].status == SHADOW_MAPPED; fa++)
            for (int b = a; b < p->lights; b++)
                for (int fb = 0; fb < 6 && p->light[b].status == SHADOW_MAPPED; fb++) {
                    if (a == b && fa >= fb)
                        continue;
                    const struct shadow_light_plan *x = &p->light[a], *y = &p->light[b];
                    if (x->x[fa] < y->x[fb] + y->size && y->x[fb] < x->x[fa] + x->size &&
                        x->y[fa] < y->y[fb] + y->size && y->y[fb] < x->y[fa] + x->size)
                        return true;
                }
    return false;
}

static void test_shadow_plan(void)
{
    struct scene s;
    teapots(&s, 80, 320);
    struct shadow_spec spec;
    shadow_spec_defaults(&spec);
    spec.enabled = true;
    struct shadow_plan p;
    char err[512];
    CHECK(shadow_plan_init(&p, s.light_count, &spec));
    CHECK(shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)));
    CHECK(p.mapped + p.culled + p.no_casters + p.dropped == 80);
    CHECK(p.mapped > 40 && p.dropped == 0);
    printf("teapots, 80 lights, 320x240: %d mapped, %d culled, %d without casters, %.0f texels\n",
           p.mapped, p.culled, p.no_casters, p.texels);
    /* Sizes follow importance; every face inside the atlas, none overlapping. */
    for (int i = 0; i < 80; i++) {
        const struct shadow_light_plan *l = &p.light[i];
        if (l->status != SHADOW_MAPPED)
            continue;
        CHECK(l->size >= spec.min_tile && l->size <= spec.max_tile);
        CHECK(l->size * 1.42 >= l->importance || l->size == spec.max_tile);
        for (int f = 0; f < 6; f++)
            CHECK(l->x[f] >= 0 && l->y[f] >= 0 && l->x[f] + l->size <= spec.atlas &&
                  l->y[f] + l->size <= spec.atlas);
        for (int j = 0; j < 80; j++)
            if (p.light[j].status == SHADOW_MAPPED && p.light[j].importance > l->importance)
                CHECK(p.light[j].size >= l->size);
    }
    CHECK(!overlaps(&p));
    /* Frame k is a pure function of k. */
    struct shadow_light_plan first = p.light[3];
    CHECK(shadow_plan_frame(&p, &s, &spec, 7, err, sizeof(err)));
    CHECK(shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)));
    CHECK(memcmp(&first, &p.light[3], sizeof(first)) == 0);

    /* Overflow: a 256 atlas holds 256^2 / (6 16^2) = 42 lights at 16. The
     * least important lose their shadows, the rest are all at min_tile
     * or more, and fail mode names the lights. */
    int needed = p.mapped;
    spec.atlas = 256;
    CHECK(shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)));
    CHECK(p.mapped == 42 && p.dropped == needed - 42 && p.texels <= 256.0 * 256.0);
    CHECK(!overlaps(&p));
    float weakest_kept = 1e30f, strongest_dropped = 0;
    for (int i = 0; i < 80; i++) {
        if (p.light[i].status == SHADOW_MAPPED)
            weakest_kept = fminf(weakest_kept, p.light[i].importance);
        if (p.light[i].status == SHADOW_DROPPED)
            strongest_dropped = fmaxf(strongest_dropped, p.light[i].importance);
    }
    CHECK(strongest_dropped <= weakest_kept);
    spec.overflow = SHADOW_OVERFLOW_FAIL;
    err[0] = '\0';
    CHECK(!shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)));
    CHECK(strstr(err, "lights without shadows") && strstr(err, "look.shadows.atlas"));
    /* A roomier atlas shrinks nothing and drops nothing. */
    spec.atlas = 16384;
    CHECK(shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)) && p.dropped == 0);
    shadow_plan_finish(&p);

    /* The cubes layout: layers from the memory bound, most important first. */
    shadow_spec_defaults(&spec);
    spec.layout = SHADOW_LAYOUT_CUBES;
    spec.tile = 128;
    spec.atlas = 1024; /* 1024^2 / (6 128^2) = 10 layers */
    CHECK(shadow_cube_layers(&spec, 80) == 10);
    CHECK(shadow_plan_init(&p, s.light_count, &spec) && p.layers == 10);
    CHECK(shadow_plan_frame(&p, &s, &spec, 1, err, sizeof(err)));
    CHECK(p.mapped == 10 && p.dropped == needed - 10);
    int seen = 0;
    for (int i = 0; i < 80; i++)
        if (p.light[i].status == SHADOW_MAPPED)
            seen |= 1 << p.light[i].x[0];
    CHECK(seen == (1 << 10) - 1);
    shadow_plan_finish(&p);
    scene_finish(&s);

    /* A light far outside the view is culled; one with no object in reach
     * needs no map. */
    teapots(&s, 4, 320);
    s.lights[0].centre[0] = 500.0f;
    s.lights[1].centre[1] = 60.0f, s.lights[1].centre[2] = 0.0f;
    s.lights[1].radius = 2.0f;
    shadow_spec_defaults(&spec);
    CHECK(shadow_plan_init(&p, 4, &spec));
    CHECK(shadow_plan_frame(&p, &s, &spec, 0, err, sizeof(err)));
    CHECK(p.light[0].status == SHADOW_CULLED);
    CHECK(p.light[1].status == SHADOW_NO_CASTERS || p.light[1].status == SHADOW_CULLED);
    shadow_plan_finish(&p);
    scene_finish(&s);
}

static void test_probes(void)
{
    struct scene s;
    teapots(&s, 8, 320);
    struct ibl_spec spec;
    ibl_spec_defaults(&spec);
    spec.probes = 3;
    struct ibl_probe probes[IBL_MAX_PROBES];
    ibl_place_probes(&s, &spec, probes);
    for (int i = 0; i < 3; i++) {
        /* Above every object, inside its footprint. */
        CHECK(probes[i].pos[1] > s.objects.max[1]);
        CHECK(probes[i].pos[0] > s.objects.min[0] && probes[i].pos[0] < s.objects.max[0]);
        CHECK(probes[i].radius > 0);
        for (int j = 0; j < i; j++)
            CHECK(probes[i].pos[0] != probes[j].pos[0] || probes[i].pos[2] != probes[j].pos[2]);
    }
    /* Selection: radius over distance, the nearest first. */
    float eye[3] = {probes[2].pos[0], probes[2].pos[1] + 1.0f, probes[2].pos[2]};
    int pick[IBL_MAX_BLEND];
    CHECK(ibl_select(probes, 3, eye, 4, pick) == 3 && pick[0] == 2);
    CHECK(ibl_select(probes, 3, eye, 1, pick) == 1 && pick[0] == 2);
    CHECK(ibl_select(probes, 0, eye, 4, pick) == 0);
    /* Weights: 1 at the centre, 0 at the radius and beyond, falling. */
    CHECK_NEAR(ibl_probe_weight(&probes[0], probes[0].pos), 1.0, 1e-6);
    float edge[3] = {probes[0].pos[0] + probes[0].radius, probes[0].pos[1], probes[0].pos[2]};
    CHECK(ibl_probe_weight(&probes[0], edge) == 0.0f);
    float mid[3] = {probes[0].pos[0] + 0.5f * probes[0].radius, probes[0].pos[1], probes[0].pos[2]};
    CHECK_NEAR(ibl_probe_weight(&probes[0], mid), 0.5, 1e-6);
    /* None placed: nothing written. */
    spec.probes = 0;
    ibl_place_probes(&s, &spec, probes);
    /* A placed list is taken as given. */
    spec.placed = true;
    spec.probes = 1;
    spec.probe[0].pos[0] = 1, spec.probe[0].pos[1] = 2, spec.probe[0].pos[2] = 3;
    spec.probe[0].radius = 4;
    ibl_place_probes(&s, &spec, probes);
    CHECK(probes[0].pos[1] == 2.0f && probes[0].radius == 4.0f);
    scene_finish(&s);
}

static bool rejects(bool shadows, const char *json, const char *field)
{
    struct ibl_spec ibl;
    struct shadow_spec sh;
    struct job_error err;
    memset(&err, 0, sizeof(err));
    ibl_spec_defaults(&ibl);
    shadow_spec_defaults(&sh);
    json_t *v = json_loads(json, JSON_DECODE_ANY, NULL);
    bool ok = shadows ? shadow_spec_parse(v, "look.shadows", &sh, &err)
                      : ibl_spec_parse(v, "look.ibl", &ibl, &err);
    json_decref(v);
    if (!ok && strcmp(err.field, field) != 0)
        fprintf(stderr, "%s: named %s (%s)\n", json, err.field, err.message);
    return !ok && strcmp(err.field, field) == 0 && strlen(err.message) > 5;
}

static void test_options(void)
{
    CHECK(rejects(false, "{\"probes\": 33}", "look.ibl.probes"));
    CHECK(rejects(false, "{\"probes\": \"many\"}", "look.ibl.probes"));
    CHECK(rejects(false, "{\"probes\": [{\"position\": [0, 1]}]}", "look.ibl.probes[0].position"));
    CHECK(rejects(false, "{\"probes\": [{\"position\": [0, 1, 2]}]}", "look.ibl.probes[0].radius"));
    CHECK(rejects(false, "{\"probes\": [{\"position\": [0, 1, 2], \"radius\": 1, \"r\": 2}]}",
                  "look.ibl.probes[0].r"));
    CHECK(rejects(false, "{\"resolution\": 48}", "look.ibl.resolution"));
    CHECK(rejects(false, "{\"blend\": 9}", "look.ibl.blend"));
    CHECK(rejects(false, "{\"environment\": \"studio\"}", "look.ibl.environment"));
    CHECK(rejects(false, "{\"probez\": 2}", "look.ibl.probez"));
    CHECK(rejects(false, "3", "look.ibl"));
    CHECK(rejects(true, "{\"atlas\": 3000}", "look.shadows.atlas"));
    CHECK(rejects(true, "{\"atlas\": 32768}", "look.shadows.atlas"));
    CHECK(rejects(true, "{\"tile\": 24}", "look.shadows.tile"));
    CHECK(rejects(true, "{\"atlas\": 256, \"tile\": 128}", "look.shadows.tile"));
    CHECK(rejects(true, "{\"min_tile\": 64, \"max_tile\": 32}", "look.shadows.min_tile"));
    CHECK(rejects(true, "{\"bias\": -1}", "look.shadows.bias"));
    CHECK(rejects(true, "{\"pcf\": 4}", "look.shadows.pcf"));
    CHECK(rejects(true, "{\"overflow\": \"ignore\"}", "look.shadows.overflow"));
    CHECK(rejects(true, "{\"layout\": \"dual_paraboloid\"}", "look.shadows.layout"));

    /* Round trips; true switches on with defaults. */
    struct ibl_spec a, b;
    struct job_error err;
    ibl_spec_defaults(&a);
    json_t *v = json_loads("{\"probes\": [{\"position\": [0, 1, 2], \"radius\": 3}], \"blend\": 2}",
                           0, NULL);
    CHECK(ibl_spec_parse(v, "look.ibl", &a, &err) && a.enabled && a.placed && a.probes == 1);
    json_decref(v);
    v = ibl_spec_to_json(&a);
    ibl_spec_defaults(&b);
    CHECK(ibl_spec_parse(v, "look.ibl", &b, &err) && memcmp(&a, &b, sizeof(a)) == 0);
    json_decref(v);
    struct shadow_spec s, t;
    shadow_spec_defaults(&s);
    CHECK(shadow_spec_parse(json_true(), "look.shadows", &s, &err) && s.enabled);
    v = shadow_spec_to_json(&s);
    shadow_spec_defaults(&t);
    CHECK(shadow_spec_parse(v, "look.shadows", &t, &err) && memcmp(&s, &t, sizeof(s)) == 0);
    json_decref(v);
    shadow_spec_defaults(&s);
    v = shadow_spec_to_json(&s);
    CHECK(json_is_false(v));
    json_decref(v);
}

int main(void)
{
    test_cube_faces();
    test_shadow_plan();
    test_probes();
    test_options();
    return check_finish("test_lighting");
}
