/* Spot and directional lights, GL-free: the cone's bounding sphere (it holds
 * the whole sector, and is the smallest that does), Wronski's cone-sphere
 * test (never culls a sphere the sector touches), glTF's cone falloff, the
 * scene options that generate them (parsing, errors naming the field, the
 * JSON written back, the lights built, scene_describe's counts), OSL's
 * "touched" rule and the shadow plan's treatment of them. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lighting/cube_faces.h"
#include "daemon/lighting/shadow_plan.h"
#include "daemon/scene/light_shape.h"
#include "daemon/scene/scene.h"
#include "daemon/techniques/osl/osl_schedule.h"
#include "tests/unit/check.h"

static const double PI = 3.14159265358979323846;

static double frand(void) { return rand() / (RAND_MAX + 1.0); }

static float dist3(const float a[3], const float b[3])
{
    float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* A unit vector at angle `angle` from the unit axis d, turned by phi about
 * it. */
static void around(const float d[3], double angle, double phi, float out[3])
{
    /* Two axes perpendicular to d. */
    float a[3] = {1, 0, 0};
    if (fabsf(d[0]) > 0.9f)
        a[0] = 0, a[1] = 1;
    float u[3] = {d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2], d[0] * a[1] - d[1] * a[0]};
    float ul = sqrtf(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; k++)
        u[k] /= ul;
    float v[3] = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
    for (int k = 0; k < 3; k++)
        out[k] = (float)(cos(angle) * d[k] + sin(angle) * (cos(phi) * u[k] + sin(phi) * v[k]));
}

static void random_unit(float out[3])
{
    double z = 2 * frand() - 1, phi = 2 * PI * frand(), s = sqrt(1 - z * z);
    out[0] = (float)(s * cos(phi)), out[1] = (float)(s * sin(phi)), out[2] = (float)z;
}

static void test_cone_bound(void)
{
    int outside = 0, not_tight = 0;
    for (int n = 0; n < 300; n++) {
        float apex[3] = {(float)(frand() * 20 - 10), (float)(frand() * 10), (float)(frand() * 20 - 10)};
        float dir[3];
        random_unit(dir);
        double t = (0.5 + frand() * 89.0) * PI / 180.0;
        float range = (float)(0.5 + frand() * 10);
        float c = (float)cos(t), s = (float)sin(t), centre[3], radius;
        light_cone_bound(apex, dir, range, c, s, centre, &radius);
        float slack = 1e-5f * range;
        /* Apex, rim and the cap, and points inside. */
        if (dist3(apex, centre) > radius + slack)
            outside++;
        double far = 0;
        for (int k = 0; k < 400; k++) {
            double a = k < 100 ? t : frand() * t, phi = frand() * 2 * PI;
            double len = k < 200 ? range : frand() * range;
            float u[3], p[3];
            around(dir, a, phi, u);
            for (int q = 0; q < 3; q++)
                p[q] = apex[q] + (float)len * u[q];
            float d = dist3(p, centre);
            if (d > radius + slack)
                outside++;
            far = fmax(far, d);
        }
        far = fmax(far, dist3(apex, centre));
        /* Tight: some point of the sector lies on the sphere (the rim always
         * does, and for t <= 45 the apex too). */
        if (far < radius * 0.999)
            not_tight++;
        if (t <= PI / 4)
            CHECK_NEAR(dist3(apex, centre), radius, 1e-4f * range);
        /* Never larger than the point light's sphere. */
        CHECK(radius <= range * 1.0001f);
    }
    CHECK(outside == 0);
    CHECK(not_tight == 0);
    /* The two cases meet at 45 degrees: r / sqrt 2 either way. */
    float apex[3] = {0, 0, 0}, dir[3] = {0, -1, 0}, centre[3], radius;
    float c45 = (float)cos(PI / 4);
    light_cone_bound(apex, dir, 4.0f, c45, c45, centre, &radius);
    CHECK_NEAR(radius, 4.0f / sqrtf(2.0f), 1e-5f);
    /* 30 degrees: centre r / (2 cos t) down the axis. */
    light_cone_bound(apex, dir, 4.0f, (float)cos(PI / 6), (float)sin(PI / 6), centre, &radius);
    CHECK_NEAR(radius, 4.0f / (2.0f * (float)cos(PI / 6)), 1e-5f);
    CHECK_NEAR(centre[1], -radius, 1e-5f);
}

static void test_cone_sphere(void)
{
    int missed = 0, culled = 0, touching = 0;
    for (int n = 0; n < 3000; n++) {
        float apex[3] = {0, 0, 0}, dir[3];
        random_unit(dir);
        double t = (1.0 + frand() * 88.0) * PI / 180.0;
        float range = 4.0f;
        float c[3] = {(float)(frand() * 12 - 6), (float)(frand() * 12 - 6), (float)(frand() * 12 - 6)};
        float r = (float)(0.1 + frand() * 2.0);
        bool says = light_cone_touches_sphere(apex, dir, range, (float)cos(t), (float)sin(t), c, r);
        /* Brute force: does a point of the sector lie in the sphere? */
        bool touches = dist3(apex, c) <= r;
        for (int k = 0; k < 4000 && !touches; k++) {
            double a = sqrt(frand()) * t, phi = frand() * 2 * PI, len = cbrt(frand()) * range;
            if (k < 1000)
                a = t; /* the side */
            else if (k < 2000)
                len = range; /* the cap */
            float u[3], p[3];
            around(dir, a, phi, u);
            for (int q = 0; q < 3; q++)
                p[q] = apex[q] + (float)len * u[q];
            touches = dist3(p, c) <= r;
        }
        touching += touches;
        if (touches && !says)
            missed++;
        culled += !says;
    }
    CHECK(missed == 0);
    /* And it does cull: most random spheres miss a narrow cone. */
    CHECK(culled > 1000);
    CHECK(touching > 100);
    /* Behind the apex, past the range, beside the cone. */
    float apex[3] = {0, 0, 0}, dir[3] = {0, -1, 0};
    float c30 = (float)cos(PI / 6), s30 = (float)sin(PI / 6);
    CHECK(!light_cone_touches_sphere(apex, dir, 4, c30, s30, (float[3]){0, 2, 0}, 1));
    CHECK(!light_cone_touches_sphere(apex, dir, 4, c30, s30, (float[3]){0, -6, 0}, 1));
    CHECK(!light_cone_touches_sphere(apex, dir, 4, c30, s30, (float[3]){3, -1, 0}, 0.5f));
    CHECK(light_cone_touches_sphere(apex, dir, 4, c30, s30, (float[3]){0, -3, 0}, 0.1f));
    CHECK(light_cone_touches_sphere(apex, dir, 4, c30, s30, (float[3]){0, 0.5f, 0}, 0.6f));
}

static void test_falloff_and_reach(void)
{
    struct scene_light l = {.type = SCENE_LIGHT_SPOT, .radius = 4, .direction = {0, -1, 0},
                            .cos_outer = (float)cos(PI / 6), .cos_inner = (float)cos(PI / 8)};
    CHECK(scene_spot_falloff(&l, l.cos_outer) == 0.0f);
    CHECK(scene_spot_falloff(&l, l.cos_outer - 1e-3f) == 0.0f);
    CHECK(scene_spot_falloff(&l, -1.0f) == 0.0f);
    CHECK(scene_spot_falloff(&l, l.cos_inner) > 0.999f);
    CHECK(scene_spot_falloff(&l, 1.0f) == 1.0f);
    float mid = 0.5f * (l.cos_inner + l.cos_outer);
    CHECK_NEAR(scene_spot_falloff(&l, mid), 0.25f, 1e-3f); /* glTF's ramp, squared */
    CHECK_NEAR(scene_light_sin_outer(&l), 0.5f, 1e-6f);
    /* Equal cosines: the scale is capped, never infinite. */
    struct scene_light hard = l;
    hard.cos_inner = hard.cos_outer;
    CHECK(isfinite(scene_light_cone_scale(&hard)));

    float pos[3] = {0, 5, 0}, centre[3], radius;
    CHECK(scene_light_bound(&l, pos, centre, &radius));
    CHECK(centre[1] < pos[1] && radius < l.radius);
    /* Under the spot, and beside it (inside its sphere, outside its cone). */
    CHECK(scene_light_reaches(&l, pos, (float[3]){0, 2, 0}, 0.5f));
    CHECK(!scene_light_reaches(&l, pos, (float[3]){3, 5, 0}, 0.5f));
    struct scene_light point = {.type = SCENE_LIGHT_POINT, .radius = 4};
    CHECK(scene_light_reaches(&point, pos, (float[3]){3, 5, 0}, 0.5f));
    /* A point light reaches as the scene always counted: strictly inside. */
    CHECK(!scene_light_reaches(&point, pos, (float[3]){4.5f, 5, 0}, 0.5f));
    CHECK(scene_light_reaches(&point, pos, (float[3]){4.49f, 5, 0}, 0.5f));
    struct scene_light sun = {.type = SCENE_LIGHT_DIRECTIONAL, .direction = {0, -1, 0}};
    CHECK(!scene_light_bound(&sun, pos, centre, &radius));
    CHECK(scene_light_reaches(&sun, pos, (float[3]){1000, -50, 9}, 0.1f));
}

static bool parse(const char *text, struct scene_spec *s, struct job_error *err)
{
    json_error_t je;
    json_t *j = json_loads(text, 0, &je);
    scene_spec_defaults(s);
    memset(err, 0, sizeof(*err));
    bool ok = j && scene_spec_parse(j, s, err);
    json_decref(j);
    return ok;
}

static void test_spec(void)
{
    struct scene_spec s;
    struct job_error err;
    CHECK(parse("{}", &s, &err));
    CHECK(s.light_type == SCENE_LIGHT_POINT && !s.sun && s.spot_angle_deg == 30.0);
    CHECK(parse("{\"preset\": \"lights\", \"light_type\": \"spot\", \"spot_angle_deg\": 20, "
                "\"sun\": true}", &s, &err));
    CHECK(s.light_type == SCENE_LIGHT_SPOT && s.sun && s.spot_angle_deg == 20.0);
    /* Written back, parsed again: the same spec. */
    json_t *j = scene_spec_to_json(&s);
    CHECK(strcmp(json_string_value(json_object_get(j, "light_type")), "spot") == 0);
    CHECK(json_is_true(json_object_get(j, "sun")));
    struct scene_spec again;
    scene_spec_defaults(&again);
    CHECK(scene_spec_parse(j, &again, &err));
    CHECK(memcmp(&again, &s, sizeof(s)) == 0);
    json_decref(j);
    /* Errors name the field. */
    CHECK(!parse("{\"light_type\": \"directional\"}", &s, &err));
    CHECK(strcmp(err.field, "scene.light_type") == 0);
    CHECK(!parse("{\"light_type\": 3}", &s, &err));
    CHECK(strcmp(err.field, "scene.light_type") == 0);
    CHECK(!parse("{\"spot_angle_deg\": 90}", &s, &err));
    CHECK(strcmp(err.field, "scene.spot_angle_deg") == 0);
    CHECK(!parse("{\"spot_angle_deg\": 0}", &s, &err));
    CHECK(strcmp(err.field, "scene.spot_angle_deg") == 0);
    CHECK(!parse("{\"sun\": \"yes\"}", &s, &err));
    CHECK(strcmp(err.field, "scene.sun") == 0);
}

static void test_scene(void)
{
    struct scene_spec spec;
    scene_spec_defaults(&spec);
    scene_spec_preset_defaults(&spec, SCENE_PRESET_LIGHTS);
    spec.lights = 64;
    struct scene points, spots;
    CHECK(scene_init(&points, &spec));
    spec.light_type = SCENE_LIGHT_SPOT;
    spec.spot_angle_deg = 25.0;
    spec.sun = true;
    CHECK(scene_init(&spots, &spec));
    CHECK(spots.light_count == 65 && points.light_count == 64);
    for (int i = 0; i < 64; i++) {
        const struct scene_light *l = &spots.lights[i];
        CHECK(l->type == SCENE_LIGHT_SPOT);
        CHECK(l->direction[0] == 0.0f && l->direction[1] == -1.0f && l->direction[2] == 0.0f);
        CHECK_NEAR(l->cos_outer, cos(25.0 * PI / 180), 1e-6);
        CHECK_NEAR(l->cos_inner, cos(25.0 * SCENE_SPOT_INNER_RATIO * PI / 180), 1e-6);
        /* Same places, colours and radii as the points. */
        CHECK(memcmp(l->centre, points.lights[i].centre, sizeof(l->centre)) == 0);
        CHECK(memcmp(l->color, points.lights[i].color, sizeof(l->color)) == 0);
        CHECK(l->radius == points.lights[i].radius);
        CHECK(points.lights[i].type == SCENE_LIGHT_POINT);
    }
    const struct scene_light *sun = &spots.lights[64];
    CHECK(sun->type == SCENE_LIGHT_DIRECTIONAL);
    CHECK_NEAR(sqrt(sun->direction[0] * sun->direction[0] + sun->direction[1] * sun->direction[1] +
                    sun->direction[2] * sun->direction[2]), 1.0, 1e-6);
    CHECK(sun->direction[1] < 0 && sun->color[0] == SCENE_SUN_COLOR[0]);

    /* Described: counts by type; spots reach fewer objects than points, the
     * sun every one. */
    json_t *dp = scene_describe(&points), *ds = scene_describe(&spots);
    json_t *lp = json_object_get(dp, "lights"), *ls = json_object_get(ds, "lights");
    json_t *bt = json_object_get(ls, "by_type");
    CHECK(json_integer_value(json_object_get(bt, "spot")) == 64);
    CHECK(json_integer_value(json_object_get(bt, "directional")) == 1);
    CHECK(json_integer_value(json_object_get(bt, "point")) == 0);
    double mp = json_real_value(json_object_get(json_object_get(lp, "per_object_at_frame_0"), "mean"));
    double ms = json_real_value(json_object_get(json_object_get(ls, "per_object_at_frame_0"), "mean"));
    CHECK(ms >= 1.0);      /* the sun reaches every object */
    CHECK(ms - 1.0 < mp);  /* the spots fewer than the same lights as points */
    json_decref(dp);
    json_decref(ds);

    /* OSL's "touched": the sun never forces a reshade. */
    struct scene_spec sun_only = spec;
    sun_only.lights = 0;
    sun_only.dynamic = true;
    struct scene only_sun;
    CHECK(scene_init(&only_sun, &sun_only));
    CHECK(only_sun.light_count == 1);
    bool any = false;
    for (int i = 0; i < only_sun.instance_count; i++)
        any |= osl_touched(&only_sun, i, 5);
    CHECK(!any);
    scene_finish(&only_sun);

    /* ... and a moving spot touches only objects its point would: a subset,
     * and a smaller one. */
    struct scene_spec moving = spec;
    moving.dynamic = true;
    moving.sun = false;
    struct scene spot_scene, point_scene;
    CHECK(scene_init(&spot_scene, &moving));
    moving.light_type = SCENE_LIGHT_POINT;
    CHECK(scene_init(&point_scene, &moving));
    int by_spot = 0, by_point = 0, outside = 0;
    for (int k = 0; k < 20; k++)
        for (int i = 0; i < spot_scene.instance_count; i++) {
            bool sp = osl_touched(&spot_scene, i, k), pt = osl_touched(&point_scene, i, k);
            by_spot += sp, by_point += pt, outside += sp && !pt;
        }
    CHECK(outside == 0 && by_spot > 0 && by_spot < by_point);
    scene_finish(&spot_scene);
    scene_finish(&point_scene);

    /* Shadows: the sun gets no map and is counted; spots are planned. */
    struct shadow_spec sh;
    shadow_spec_defaults(&sh);
    sh.enabled = true;
    struct shadow_plan plan;
    char err[256];
    CHECK(shadow_plan_init(&plan, spots.light_count, &sh));
    CHECK(shadow_plan_frame(&plan, &spots, &sh, 1, err, sizeof(err)));
    CHECK(plan.directional == 1);
    CHECK(plan.light[64].status == SHADOW_DIRECTIONAL && plan.light[64].size == 0);
    CHECK(plan.mapped + plan.culled + plan.no_casters + plan.dropped + plan.directional == 65);
    shadow_plan_finish(&plan);

    /* The sun's map: every corner of the scene's bounds inside its clip
     * box, nearer the sun nearer 0 in depth, the texel as stated. */
    float vp[16], texel, range;
    int size = shadow_sun_size(&sh);
    CHECK(size == sh.atlas / 2 || size == 4096 || size == 256);
    shadow_sun_fit(&spots.bounds, sun->direction, size, vp, &texel, &range);
    float prev = -2.0f;
    bool inside = true, ordered = true;
    for (int c = 0; c < 8; c++) {
        float p[3], q[4];
        for (int k = 0; k < 3; k++)
            p[k] = c >> k & 1 ? spots.bounds.max[k] : spots.bounds.min[k];
        for (int r = 0; r < 4; r++)
            q[r] = vp[r] * p[0] + vp[4 + r] * p[1] + vp[8 + r] * p[2] + vp[12 + r];
        inside &= q[3] == 1.0f && fabsf(q[0]) < 1 && fabsf(q[1]) < 1 && fabsf(q[2]) < 1;
        (void)prev;
    }
    /* Along the light, depth grows. */
    for (int k = 0; k < 5; k++) {
        float p[3] = {sun->direction[0] * (float)k, sun->direction[1] * (float)k,
                      sun->direction[2] * (float)k};
        float z = vp[2] * p[0] + vp[6] * p[1] + vp[10] * p[2] + vp[14];
        ordered &= z > prev;
        prev = z;
    }
    CHECK(inside && ordered);

    /* A spot's map draws only the faces its cone reaches: every direction
     * inside a cone lies in a face that passes (with widening 1, the
     * tightest), and a spot of up to 30 degrees down an axis needs one. */
    int missing = 0, passed = 0;
    for (int n = 0; n < 500; n++) {
        float axis[3];
        random_unit(axis);
        double t = (1.0 + frand() * 88.0) * PI / 180.0;
        for (int k = 0; k < 200; k++) {
            float u[3];
            around(axis, frand() * t, frand() * 2 * PI, u);
            missing += !shadow_cone_meets_face(axis, (float)cos(t), cube_face_of(u), 1.0f);
        }
        for (int f = 0; f < 6; f++)
            passed += shadow_cone_meets_face(axis, (float)cos(t), f, 1.0f);
    }
    CHECK(missing == 0);
    CHECK(passed < 500 * 6);
    int down_faces = 0;
    for (int f = 0; f < 6; f++)
        down_faces += shadow_cone_meets_face((float[3]){0, -1, 0}, (float)cos(PI / 6), f, 1.2f);
    CHECK(down_faces == 1);
    CHECK(texel > 0 && texel < 0.05f && range > 2.0f);
    printf("sun map on the lights preset: %d texels, %.4f units a texel, depth range %.2f\n", size,
           texel, range);

    scene_finish(&points);
    scene_finish(&spots);
}

int main(void)
{
    srand(11);
    test_cone_bound();
    test_cone_sphere();
    test_falloff_and_reach();
    test_spec();
    test_scene();
    return check_finish("test_light_shape");
}
