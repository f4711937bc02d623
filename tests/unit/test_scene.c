/* The scene: grid exactly as the thesis scene always was, the lights
 * preset's promises, light layouts, materials, camera paths, automatic
 * tessellation, the spec's JSON and scene_describe. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "daemon/scene/scene.h"
#include "daemon/scene/scene_build.h" /* scene_mat4_transform */
#include "tests/unit/check.h"

static const double PI = 3.14159265358979323846;

/* ---- The grid as it was built before the general scene (copied from the
 * code of that time, so that "unchanged" is checked against the old
 * arithmetic, not against the new code's own). ---- */

static double old_radical_inverse(unsigned i, unsigned base)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    for (; i; i /= base, f *= inv)
        r += f * (i % base);
    return r;
}

static void old_hsv_to_rgb(double h, double s, double v, float out[3])
{
    double c = v * s, hp = fmod(h, 1.0) * 6.0, x = c * (1 - fabs(fmod(hp, 2.0) - 1));
    double r = 0, g = 0, b = 0;
    if (hp < 1) r = c, g = x;
    else if (hp < 2) r = x, g = c;
    else if (hp < 3) g = c, b = x;
    else if (hp < 4) g = x, b = c;
    else if (hp < 5) r = x, b = c;
    else r = c, b = x;
    out[0] = (float)(r + v - c), out[1] = (float)(g + v - c), out[2] = (float)(b + v - c);
}

static void old_view_proj(float out[16], float aspect)
{
    const float eye[3] = {0.0f, 28.0f, 22.0f}, target[3] = {0.0f, 1.0f, -10.0f};
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    float up[3] = {0, 1, 0}, s[3], u[3], view[16] = {0}, proj[16] = {0};
    float len = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int i = 0; i < 3; i++)
        f[i] /= len;
    s[0] = f[1] * up[2] - f[2] * up[1], s[1] = f[2] * up[0] - f[0] * up[2],
    s[2] = f[0] * up[1] - f[1] * up[0];
    len = sqrtf(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int i = 0; i < 3; i++)
        s[i] /= len;
    u[0] = s[1] * f[2] - s[2] * f[1], u[1] = s[2] * f[0] - s[0] * f[2],
    u[2] = s[0] * f[1] - s[1] * f[0];
    for (int i = 0; i < 3; i++) {
        view[i * 4 + 0] = s[i];
        view[i * 4 + 1] = u[i];
        view[i * 4 + 2] = -f[i];
    }
    view[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    view[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    view[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
    view[15] = 1.0f;
    float t = 1.0f / tanf((float)(55.0f * PI / 360.0));
    proj[0] = t / aspect;
    proj[5] = t;
    proj[10] = (200.0f + 0.5f) / (0.5f - 200.0f);
    proj[11] = -1.0f;
    proj[14] = 2.0f * 200.0f * 0.5f / (0.5f - 200.0f);
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float sum = 0.0f;
            for (int k = 0; k < 4; k++)
                sum += proj[k * 4 + row] * view[c * 4 + k];
            out[c * 4 + row] = sum;
        }
}

/* Outward winding: every non-degenerate triangle faces away from the centre. */
static void check_mesh(const struct mesh *m)
{
    int outward = 0, inward = 0;
    for (uint32_t t = 0; t < m->index_count; t += 3) {
        const float *a = m->vertices[m->indices[t]].pos, *b = m->vertices[m->indices[t + 1]].pos,
                    *c = m->vertices[m->indices[t + 2]].pos;
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]};
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len < 1e-9f)
            continue;
        float centroid[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                             (a[2] + b[2] + c[2]) / 3};
        if (n[0] * centroid[0] + n[1] * centroid[1] + n[2] * centroid[2] > 0)
            outward++;
        else
            inward++;
    }
    CHECK(outward > 0 && inward == 0);
    /* UVs stay inside their chart, and charts inside the unit square. */
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const struct mesh_vertex *x = &m->vertices[v];
        CHECK(x->chart[0] >= 0 && x->chart[2] <= 1 && x->chart[1] >= 0 && x->chart[3] <= 1);
        CHECK(x->uv[0] >= x->chart[0] - 1e-6f && x->uv[0] <= x->chart[2] + 1e-6f);
        CHECK(x->uv[1] >= x->chart[1] - 1e-6f && x->uv[1] <= x->chart[3] + 1e-6f);
    }
}

/* The plane faces up, and its UVs cover the whole tile (OSL's texgen). */
static void check_plane(const struct mesh *m)
{
    float umin = 1, umax = 0, vmin = 1, vmax = 0, area = 0;
    for (uint32_t t = 0; t < m->index_count; t += 3) {
        const struct mesh_vertex *a = &m->vertices[m->indices[t]],
                                 *b = &m->vertices[m->indices[t + 1]],
                                 *c = &m->vertices[m->indices[t + 2]];
        float e1[3] = {b->pos[0] - a->pos[0], b->pos[1] - a->pos[1], b->pos[2] - a->pos[2]};
        float e2[3] = {c->pos[0] - a->pos[0], c->pos[1] - a->pos[1], c->pos[2] - a->pos[2]};
        CHECK(e1[2] * e2[0] - e1[0] * e2[2] > 0); /* normal.y of the winding */
        area += 0.5f * fabsf((b->uv[0] - a->uv[0]) * (c->uv[1] - a->uv[1]) -
                             (c->uv[0] - a->uv[0]) * (b->uv[1] - a->uv[1]));
    }
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const struct mesh_vertex *x = &m->vertices[v];
        CHECK(x->normal[1] == 1.0f && x->pos[1] == 0.0f);
        umin = fminf(umin, x->uv[0]), umax = fmaxf(umax, x->uv[0]);
        vmin = fminf(vmin, x->uv[1]), vmax = fmaxf(vmax, x->uv[1]);
    }
    CHECK(umin == 0 && umax == 1 && vmin == 0 && vmax == 1);
    CHECK_NEAR(area, 1.0f, 1e-6f);
}

static void mat4_mul(float out[16], const float a[16], const float b[16])
{
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float sum = 0.0f;
            for (int k = 0; k < 4; k++)
                sum += a[k * 4 + row] * b[c * 4 + k];
            out[c * 4 + row] = sum;
        }
}

/* a b is the identity within eps (relative to the largest entry of a). */
static bool is_inverse(const float a[16], const float b[16], float eps)
{
    float p[16];
    mat4_mul(p, a, b);
    for (int i = 0; i < 16; i++)
        if (fabsf(p[i] - (i % 5 == 0 ? 1.0f : 0.0f)) > eps)
            return false;
    return true;
}

static bool build(struct scene *s, const char *json)
{
    struct scene_spec spec;
    struct job_error err;
    scene_spec_defaults(&spec);
    json_error_t jerr;
    json_t *j = json_loads(json, 0, &jerr);
    bool ok = j && scene_spec_parse(j, &spec, &err) && scene_init(s, &spec);
    if (!ok)
        fprintf(stderr, "cannot build %s: %s %s\n", json, err.field, err.message);
    json_decref(j);
    return ok;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

static void test_grid_unchanged(void)
{
    struct {
        struct scene_spec scene;
    } spec;
    scene_spec_defaults(&spec.scene);
    struct scene s;
    CHECK(scene_init(&s, &spec.scene));
    CHECK(s.instance_count == 512);
    CHECK(s.mesh_instance_count[SCENE_MESH_SPHERE] == 256);
    CHECK(s.mesh_instance_count[SCENE_MESH_CUBE] == 256);
    CHECK(s.mesh_instance_count[SCENE_MESH_PLANE] == 0);
    CHECK(s.light_count == 10);
    CHECK(scene_all_in_view(&s));

    /* Instances: the thesis layout and palette, bit for bit, with the
     * thesis's Phong constants as every material. */
    int next = 0, mismatched = 0;
    for (int mesh = 0; mesh < 2; mesh++)
        for (int layer = 0; layer < 4; layer++)
            for (int row = 0; row < 8; row++) {
                if (row % 2 != mesh)
                    continue;
                for (int col = 0; col < 16; col++) {
                    const struct scene_instance *in = &s.instances[next++];
                    float pos[3] = {((float)col - 15 * 0.5f) * 2.5f, (float)layer * 2.5f,
                                    -(float)row * 3.0f}, albedo[3];
                    unsigned cell = (unsigned)((layer * 8 + row) * 16 + col);
                    old_hsv_to_rgb(old_radical_inverse(cell + 1, 2), 0.45, 0.85, albedo);
                    mismatched += memcmp(in->pos, pos, sizeof(pos)) != 0 || in->scale != 1.0f ||
                                  (int)in->mesh != mesh ||
                                  memcmp(in->albedo, albedo, sizeof(albedo)) != 0 ||
                                  in->material.specular != 0.5f ||
                                  in->material.shininess != 32.0f ||
                                  in->material.metallic != 0.0f;
                }
            }
    CHECK(next == 512 && mismatched == 0);

    /* Lights: the Halton spread, radius 5, the same colours and periods. */
    mismatched = 0;
    for (int i = 0; i < s.light_count; i++) {
        const struct scene_light *l = &s.lights[i];
        unsigned k = (unsigned)i + 1;
        float centre[3] = {(float)((old_radical_inverse(k, 2) - 0.5) * 40.0),
                           (float)(old_radical_inverse(k, 3) * 10.0 - 0.5),
                           (float)(1.5 - old_radical_inverse(k, 5) * 24.0)}, color[3];
        old_hsv_to_rgb(i * 0.618033988749895, 0.6, 1.6, color);
        int period = 180 + 40 * (i % 7);
        mismatched += memcmp(l->centre, centre, sizeof(centre)) != 0 || l->orbit != 3.0f ||
                      l->radius != 5.0f || memcmp(l->color, color, sizeof(color)) != 0 ||
                      l->period != period || l->phase != (i * 37) % period;
    }
    CHECK(mismatched == 0);

    /* Camera: the thesis pose and matrices, the same at every frame. */
    float vp[16];
    old_view_proj(vp, 1080.0f / 720.0f);
    CHECK(memcmp(vp, s.view_proj, sizeof(vp)) == 0);
    CHECK(s.eye[0] == 0.0f && s.eye[1] == 28.0f && s.eye[2] == 22.0f);
    CHECK(s.fovy_deg == 55.0f && s.near_z == 0.5f && s.far_z == 200.0f);
    CHECK(!scene_camera_moves(&s));
    struct scene_camera c0, ck;
    scene_camera_at(&s, 0, &c0);
    scene_camera_at(&s, 123457, &ck);
    CHECK(memcmp(&c0, &ck, sizeof(c0)) == 0);
    CHECK(memcmp(c0.view_proj, s.view_proj, sizeof(vp)) == 0);
    CHECK(memcmp(c0.view, s.view, sizeof(vp)) == 0 && memcmp(c0.proj, s.proj, sizeof(vp)) == 0);
    CHECK(is_inverse(c0.view, c0.inv_view, 1e-5f) && is_inverse(c0.inv_view, c0.view, 1e-5f));
    CHECK(is_inverse(c0.proj, c0.inv_proj, 1e-5f) && is_inverse(c0.inv_proj, c0.proj, 1e-5f));

    /* Rows alternate: every sphere row's neighbours along z are cube rows. */
    int layers[4] = {0};
    for (int i = 0; i < s.instance_count; i++) {
        int row = (int)lroundf(-s.instances[i].pos[2] / 3.0f);
        CHECK((row % 2 == 0) == (s.instances[i].mesh == SCENE_MESH_SPHERE));
        layers[(int)lroundf(s.instances[i].pos[1] / 2.5f)]++;
    }
    CHECK(layers[0] == 128 && layers[3] == 128);

    /* Triangles: 32 segments x 16 rings x 2 per sphere, 12 per cube. */
    CHECK(s.sphere_segments == 32);
    CHECK(scene_triangles(&s) == 256ull * 32 * 16 * 2 + 256ull * 12);
    check_mesh(&s.meshes[SCENE_MESH_SPHERE]);
    check_mesh(&s.meshes[SCENE_MESH_CUBE]);
    check_plane(&s.meshes[SCENE_MESH_PLANE]);

    /* Static lights never move; dynamic ones are periodic in the frame index. */
    float a[3], b[3];
    scene_light_position(&s, 3, 0, a);
    scene_light_position(&s, 3, 12345, b);
    CHECK(memcmp(a, b, sizeof(a)) == 0);
    scene_finish(&s);

    spec.scene.dynamic = true;
    spec.scene.width = 320;
    spec.scene.height = 240;
    CHECK(scene_init(&s, &spec.scene));
    CHECK(scene_all_in_view(&s));
    for (int l = 0; l < s.light_count; l++) {
        scene_light_position(&s, l, 7, a);
        scene_light_position(&s, l, 7 + s.lights[l].period, b);
        CHECK(memcmp(a, b, sizeof(a)) == 0);
        scene_light_position(&s, l, -3, a);
        scene_light_position(&s, l, -3 + 2 * s.lights[l].period, b);
        CHECK(memcmp(a, b, sizeof(a)) == 0);
        scene_light_position(&s, l, 8, b);
        scene_light_position(&s, l, 7, a);
        CHECK(memcmp(a, b, sizeof(a)) != 0);
        CHECK(a[2] == s.lights[l].centre[2]); /* circles stay in the XY plane */
        /* The position as the thesis code computed it. */
        int64_t step = (7 + s.lights[l].phase) % s.lights[l].period;
        double ang = 2.0 * PI * (double)step / (double)s.lights[l].period;
        CHECK(a[0] == s.lights[l].centre[0] + 3.0f * (float)cos(ang));
        CHECK(a[1] == s.lights[l].centre[1] + 3.0f * (float)sin(ang));
    }
    /* light_speed 2 halves each revolution; 0 holds the lights still. */
    struct scene fast, still;
    struct scene_spec fs = spec.scene, ss = spec.scene;
    fs.light_speed = 2.0;
    ss.light_speed = 0.0;
    CHECK(scene_init(&fast, &fs) && scene_init(&still, &ss));
    for (int l = 0; l < fast.light_count; l++) {
        CHECK(abs(2 * fast.lights[l].period - s.lights[l].period) <= 1);
        scene_light_position(&still, l, 0, a);
        scene_light_position(&still, l, 77, b);
        CHECK(memcmp(a, b, sizeof(a)) == 0);
    }
    scene_finish(&fast);
    scene_finish(&still);

    /* Distances put the far corner in the thesis's "every third frame" band at d = 20. */
    float far = 0, near = 1e9f;
    for (int i = 0; i < s.instance_count; i++) {
        float d = scene_instance_distance(&s, i);
        far = d > far ? d : far;
        near = d < near ? d : near;
    }
    CHECK(far >= 40.0f && far < 60.0f);
    CHECK(near < 40.0f);
    scene_finish(&s);

    spec.scene.lights = 0;
    CHECK(scene_init(&s, &spec.scene));
    CHECK(s.light_count == 0);
    scene_finish(&s);
}

static bool inside_box(const struct scene_box *b, const float p[3], float slack)
{
    for (int k = 0; k < 3; k++)
        if (p[k] < b->min[k] - slack || p[k] > b->max[k] + slack)
            return false;
    return true;
}

static double lights_on_screen(const struct scene *s, int64_t frame)
{
    struct scene_camera c;
    scene_camera_at(s, frame, &c);
    int on = 0;
    for (int l = 0; l < s->light_count; l++) {
        float p[3];
        scene_light_position(s, l, frame, p);
        on += scene_sphere_in_frustum(c.view_proj, p, 0.0f, true);
    }
    return s->light_count ? (double)on / s->light_count : 1.0;
}

static void test_lights_preset(void)
{
    struct scene s, again;
    CHECK(build(&s, "{\"preset\":\"lights\",\"dynamic\":true}"));
    CHECK(s.spec.lights == 256 && s.spec.light_layout == SCENE_LAYOUT_UNIFORM);
    CHECK(s.spec.light_radius == 4.0 && s.spec.materials == SCENE_MATERIALS_VARIED);
    CHECK(s.mesh_instance_count[SCENE_MESH_PLANE] == 1);
    CHECK(s.mesh_instance_count[SCENE_MESH_SPHERE] > 50 && s.mesh_instance_count[SCENE_MESH_CUBE] > 50);
    CHECK(s.light_volume.min[1] > 0.0f);

    /* Every object rests on the ground (y = 0), none sinks into it, and
     * the ground spans every object and every light. */
    const struct scene_instance *ground = &s.instances[s.instance_count - 1];
    CHECK(ground->mesh == SCENE_MESH_PLANE && ground->pos[1] == 0.0f);
    float ground_half = ground->scale * 1.0f;
    int floating = 0, sunk = 0, off_ground = 0;
    for (int i = 0; i < s.instance_count - 1; i++) {
        const struct scene_instance *in = &s.instances[i];
        float half = (in->mesh == SCENE_MESH_SPHERE ? 0.8f : 0.65f) * in->scale;
        sunk += in->pos[1] - half < -1e-5f;
        floating += in->pos[1] - half > 1e-5f;
        off_ground += fabsf(in->pos[0]) + half > ground_half || fabsf(in->pos[2]) + half > ground_half;
    }
    CHECK(sunk == 0 && floating == 0 && off_ground == 0);
    CHECK(s.bounds.min[1] == 0.0f);
    CHECK(fabsf(s.light_volume.min[0]) < ground_half && s.light_volume.max[2] < ground_half);

    /* Lights stay in their volume (within their orbit) and above the ground
     * at every frame; most are on screen and the scene's objects too. */
    int outside = 0, below = 0;
    for (int64_t k = -5; k < 400; k += 13)
        for (int l = 0; l < s.light_count; l++) {
            float p[3];
            scene_light_position(&s, l, k, p);
            outside += !inside_box(&s.light_volume, p, s.lights[l].orbit + 1e-4f);
            below += p[1] <= 0.0f;
            if (k == -5)
                outside += !inside_box(&s.light_volume, s.lights[l].centre, 0.0f);
        }
    CHECK(outside == 0 && below == 0);
    double on0 = lights_on_screen(&s, 0), on_later = lights_on_screen(&s, 100);
    CHECK(on0 >= 0.9 && on_later >= 0.9);
    struct scene_camera c;
    scene_camera_at(&s, 0, &c);
    CHECK(scene_instances_in_view(&s, &c) >= s.instance_count * 3 / 4);

    /* Materials vary per object, within their ranges, and a second build is
     * identical to the byte (no unseeded randomness). */
    float spec_min = 1e9f, spec_max = 0, shin_min = 1e9f, shin_max = 0;
    int metallic = 0;
    for (int i = 0; i < s.instance_count; i++) {
        const struct scene_material *m = &s.instances[i].material;
        spec_min = fminf(spec_min, m->specular), spec_max = fmaxf(spec_max, m->specular);
        shin_min = fminf(shin_min, m->shininess), shin_max = fmaxf(shin_max, m->shininess);
        metallic += m->metallic == 1.0f;
        CHECK(m->roughness > 0.0f && m->roughness <= 1.0f);
    }
    CHECK(spec_min >= 0.125f - 1e-6f && spec_max <= 0.875f + 1e-6f && spec_max - spec_min > 0.3f);
    CHECK(shin_min >= 8.0f && shin_max <= 128.0f && shin_max / shin_min >= 8.0f);
    CHECK(metallic > s.instance_count / 8 && metallic < s.instance_count / 2);
    CHECK(build(&again, "{\"preset\":\"lights\",\"dynamic\":true}"));
    CHECK(again.instance_count == s.instance_count && again.light_count == s.light_count);
    CHECK(memcmp(again.instances, s.instances, sizeof(*s.instances) * (size_t)s.instance_count) == 0);
    CHECK(memcmp(again.lights, s.lights, sizeof(*s.lights) * (size_t)s.light_count) == 0);
    scene_finish(&again);

    /* "uniform" materials give every object the spec's values. */
    CHECK(build(&again, "{\"preset\":\"lights\",\"materials\":\"uniform\",\"specular\":0.25,"
                        "\"shininess\":64,\"metallic\":0.5,\"roughness\":0.75}"));
    int differ = 0;
    for (int i = 0; i < again.instance_count; i++) {
        const struct scene_material *m = &again.instances[i].material;
        differ += m->specular != 0.25f || m->shininess != 64.0f || m->metallic != 0.5f ||
                  m->roughness != 0.75f;
    }
    CHECK(differ == 0);
    scene_finish(&again);

    /* Light radius and intensity reach every light. */
    CHECK(build(&again, "{\"preset\":\"lights\",\"light_radius\":2.5,\"light_intensity\":2}"));
    for (int l = 0; l < again.light_count; l++) {
        CHECK(again.lights[l].radius == 2.5f);
        for (int k = 0; k < 3; k++)
            CHECK(again.lights[l].color[k] == 2.0f * s.lights[l].color[k]);
    }
    scene_finish(&again);
    scene_finish(&s);

    /* Many lights build quickly, and most stay on screen. */
    double t0 = now_s();
    CHECK(build(&s, "{\"preset\":\"lights\",\"lights\":16384}"));
    double built = now_s() - t0;
    CHECK(s.light_count == 16384);
    CHECK(built < 1.0);
    CHECK(lights_on_screen(&s, 0) >= 0.9);
    printf("lights preset: 16384 lights built in %.1f ms, %.1f%% on screen\n", built * 1e3,
           100.0 * lights_on_screen(&s, 0));
    scene_finish(&s);
    t0 = now_s();
    CHECK(build(&s, "{\"preset\":\"lights\",\"lights\":65536,\"light_layout\":\"clustered\"}"));
    CHECK(now_s() - t0 < 2.0);
    scene_finish(&s);
}

/* Mean distance from each light to its nearest neighbour. */
static double mean_nearest(const struct scene *s)
{
    double sum = 0;
    for (int i = 0; i < s->light_count; i++) {
        double best = INFINITY;
        for (int j = 0; j < s->light_count; j++) {
            if (j == i)
                continue;
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double d = (double)s->lights[i].centre[k] - s->lights[j].centre[k];
                d2 += d * d;
            }
            best = fmin(best, d2);
        }
        sum += sqrt(best);
    }
    return sum / s->light_count;
}

static void test_layouts(void)
{
    static const char *const layouts[] = {"halton", "uniform", "grid", "clustered"};
    double nearest[4];
    for (int l = 0; l < 4; l++) {
        char json[128];
        snprintf(json, sizeof(json), "{\"preset\":\"lights\",\"lights\":1000,\"light_layout\":\"%s\"}",
                 layouts[l]);
        struct scene s;
        CHECK(build(&s, json));
        int outside = 0;
        for (int i = 0; i < s.light_count; i++)
            outside += !inside_box(&s.light_volume, s.lights[i].centre, 1e-4f);
        CHECK(outside == 0);
        nearest[l] = mean_nearest(&s);
        if (l == 2) {
            /* The lattice: no two lights share a point, and spacing is even. */
            double least = INFINITY;
            for (int i = 0; i < s.light_count; i++)
                for (int j = i + 1; j < s.light_count; j++) {
                    double d2 = 0;
                    for (int k = 0; k < 3; k++) {
                        double d = (double)s.lights[i].centre[k] - s.lights[j].centre[k];
                        d2 += d * d;
                    }
                    least = fmin(least, d2);
                }
            CHECK(sqrt(least) > 0.5 * nearest[l]);
        }
        scene_finish(&s);
    }
    /* Hot spots: clustered lights sit much closer together than uniform
     * ones, the lattice and Halton spread them at least as evenly. */
    CHECK(nearest[3] < 0.5 * nearest[1]);
    CHECK(nearest[2] > nearest[1] && nearest[0] > nearest[1]);
    printf("nearest light, mean over 1000: halton %.2f uniform %.2f grid %.2f clustered %.2f\n",
           nearest[0], nearest[1], nearest[2], nearest[3]);
}

static bool same_camera(const struct scene_camera *a, const struct scene_camera *b)
{
    return memcmp(a, b, sizeof(*a)) == 0;
}

static void test_camera_paths(void)
{
    static const char *const scenes[] = {
        "{\"camera\":{\"path\":\"orbit\",\"period\":240}}",
        "{\"camera\":{\"path\":\"flythrough\",\"period\":240}}",
        "{\"preset\":\"lights\",\"camera\":{\"path\":\"orbit\",\"period\":240}}",
        "{\"preset\":\"lights\",\"camera\":{\"path\":\"flythrough\",\"period\":240}}",
        "{\"preset\":\"lights\",\"camera\":\"orbit\",\"width\":320,\"height\":480}",
    };
    for (int t = 0; t < 5; t++) {
        struct scene s;
        CHECK(build(&s, scenes[t]));
        CHECK(scene_camera_moves(&s));
        int period = s.spec.camera_period;
        bool orbit = s.spec.camera == SCENE_CAMERA_ORBIT;
        struct scene_camera a, b, prev;
        /* A pure function of the frame, periodic, negatives included. */
        for (int64_t k = -3; k < 40; k += 7) {
            scene_camera_at(&s, k, &a);
            scene_camera_at(&s, k, &b);
            CHECK(same_camera(&a, &b));
            scene_camera_at(&s, k + period, &b);
            CHECK(same_camera(&a, &b));
            scene_camera_at(&s, k - 3 * (int64_t)period, &b);
            CHECK(same_camera(&a, &b));
            scene_camera_at(&s, k + 1, &b);
            CHECK(memcmp(a.eye, b.eye, sizeof(a.eye)) != 0);
        }
        /* Frame 0 is the scene's flat camera. */
        scene_camera_at(&s, 0, &a);
        CHECK(memcmp(a.view_proj, s.view_proj, sizeof(a.view_proj)) == 0);
        CHECK(memcmp(a.eye, s.eye, sizeof(a.eye)) == 0);

        /* The scene stays in view: the orbit keeps every object (and the
         * light volume) in the frustum; the flythrough stays above the
         * objects, never nearer than the near plane, and always sees a
         * tenth of them whole or more (it flies low over the dense grid).
         * Smooth: no jump between frames. */
        double largest_step = 0, least_share = 1;
        int objects = s.instance_count - s.mesh_instance_count[SCENE_MESH_PLANE];
        scene_camera_at(&s, -1, &prev);
        for (int k = 0; k < period; k++) {
            scene_camera_at(&s, k, &a);
            CHECK(is_inverse(a.view, a.inv_view, 1e-4f) && is_inverse(a.proj, a.inv_proj, 1e-4f));
            int seen = 0, too_near = 0;
            for (int i = 0; i < s.instance_count; i++) {
                if (s.instances[i].mesh == SCENE_MESH_PLANE)
                    continue;
                seen += scene_instance_in_view(&s, i, &a);
                float d[3] = {a.eye[0] - s.instances[i].pos[0], a.eye[1] - s.instances[i].pos[1],
                              a.eye[2] - s.instances[i].pos[2]};
                too_near += sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) <
                            scene_instance_bound(&s, i) + a.near_z;
            }
            CHECK(too_near == 0);
            least_share = fmin(least_share, (double)seen / objects);
            if (orbit) {
                CHECK(seen == objects);
                CHECK(lights_on_screen(&s, k) > 0.97);
            } else {
                CHECK(a.eye[1] >= s.objects.max[1] + 1.0f);
                CHECK(inside_box(&s.objects, (float[3]){a.eye[0], s.objects.min[1], a.eye[2]}, 0));
            }
            double step = 0;
            for (int m = 0; m < 3; m++)
                step += (double)(a.eye[m] - prev.eye[m]) * (a.eye[m] - prev.eye[m]);
            largest_step = fmax(largest_step, sqrt(step));
            prev = a;
        }
        /* One loop is at most about 2 pi times the scene's half-diagonal. */
        double extent = 0;
        for (int m = 0; m < 3; m++)
            extent += (double)(s.bounds.max[m] - s.bounds.min[m]) * (s.bounds.max[m] - s.bounds.min[m]);
        double loop = 2.0 * PI * (orbit ? s.rig.orbit_distance : sqrt(extent) / 2);
        CHECK(largest_step < 1.5 * loop / period);
        CHECK(least_share >= (orbit ? 1.0 : 0.1));
        printf("camera %s on %s: objects in view at least %.0f%%, largest step %.3f\n",
               scene_camera_names[s.spec.camera], scene_preset_names[s.spec.preset],
               100 * least_share, largest_step);
        scene_finish(&s);
    }
    /* period 1 never moves. */
    struct scene s;
    CHECK(build(&s, "{\"camera\":{\"path\":\"orbit\",\"period\":1}}"));
    CHECK(!scene_camera_moves(&s));
    scene_finish(&s);
}

/* The deepest a point of the mesh lies inside its sphere, as a fraction of
 * the radius (sampled over every triangle). */
static double mesh_depression(const struct mesh *m, float radius)
{
    double least = INFINITY;
    for (uint32_t t = 0; t < m->index_count; t += 3) {
        const float *a = m->vertices[m->indices[t]].pos, *b = m->vertices[m->indices[t + 1]].pos,
                    *c = m->vertices[m->indices[t + 2]].pos;
        for (int i = 0; i <= 12; i++)
            for (int j = 0; i + j <= 12; j++) {
                double u = i / 12.0, v = j / 12.0, w = 1 - u - v, d2 = 0;
                for (int k = 0; k < 3; k++) {
                    double p = u * a[k] + v * b[k] + w * c[k];
                    d2 += p * p;
                }
                least = fmin(least, sqrt(d2));
            }
    }
    return 1.0 - least / radius;
}

static void test_tessellation(void)
{
    /* The error model is the mesh's: the deepest point of a lat-long sphere
     * is sin^2(pi/n) of its radius inside it (and no shallower than 90% of it). */
    int sizes[] = {8, 16, 24, 32, 64};
    for (int i = 0; i < 5; i++) {
        struct mesh m;
        CHECK(mesh_create_sphere(&m, 0.8f, sizes[i]));
        double dep = mesh_depression(&m, 0.8f), model = scene_sphere_error(sizes[i]);
        CHECK(dep <= model * 1.001 + 1e-6 && dep >= 0.9 * model);
        mesh_finish(&m);
    }
    /* The coarsest that meets the bound, monotone in size. */
    int last = 8;
    for (double r = 1; r < 5000; r *= 1.3) {
        int n = scene_auto_segments(r, 0.5);
        CHECK(n % 2 == 0 && n >= 8 && n <= 256 && n >= last);
        CHECK(n == 256 || r * scene_sphere_error(n) <= 0.5);
        CHECK(n == 8 || r * scene_sphere_error(n - 2) > 0.5);
        last = n;
    }
    CHECK(scene_auto_segments(1e6, 0.5) == 256);

    /* Projected radius: exact against points of the sphere projected by
     * the camera itself, off axis as well as on it. */
    struct scene s;
    CHECK(build(&s, "{\"preset\":\"lights\"}"));
    struct scene_camera c;
    scene_camera_at(&s, 0, &c);
    int compared = 0;
    for (int t = 0; t < s.instance_count; t += 7) {
        if (s.instances[t].mesh != SCENE_MESH_SPHERE)
            continue;
        const float *centre = s.instances[t].pos;
        float r = 0.8f * s.instances[t].scale, q[4];
        /* The ellipse's major axis points from the image centre through the
         * projected centre; measure the projected points' extent along it. */
        scene_mat4_transform(c.view_proj, centre, 1.0f, q);
        double px = q[0] / q[3] * s.spec.width * 0.5, py = q[1] / q[3] * s.spec.height * 0.5;
        double plen = sqrt(px * px + py * py), ux = plen > 1e-6 ? px / plen : 1.0,
               uy = plen > 1e-6 ? py / plen : 0.0, lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i <= 200; i++)
            for (int j = 0; j < 400; j++) {
                double th = PI * i / 200, ph = 2 * PI * j / 400;
                float p[3] = {centre[0] + r * (float)(sin(th) * cos(ph)),
                              centre[1] + r * (float)cos(th),
                              centre[2] + r * (float)(sin(th) * sin(ph))};
                scene_mat4_transform(c.view_proj, p, 1.0f, q);
                double x = q[0] / q[3] * s.spec.width * 0.5, y = q[1] / q[3] * s.spec.height * 0.5;
                lo = fmin(lo, x * ux + y * uy), hi = fmax(hi, x * ux + y * uy);
            }
        double brute = (hi - lo) / 2;
        double exact = scene_sphere_radius_px(&c, s.spec.width, s.spec.height, centre, r);
        CHECK(fabs(brute - exact) <= 0.005 * exact);
        compared++;
    }
    CHECK(compared >= 5);
    scene_finish(&s);

    /* "auto" meets its bound over the whole camera path, and is coarser for
     * smaller spheres (a smaller image) and finer for nearer ones (a
     * flythrough passes close to them). */
    struct scene big, small, fly;
    CHECK(build(&big, "{\"sphere_segments\":\"auto\"}"));
    CHECK(build(&small, "{\"sphere_segments\":\"auto\",\"width\":160,\"height\":120}"));
    CHECK(build(&fly, "{\"sphere_segments\":\"auto\",\"camera\":\"flythrough\"}"));
    CHECK(big.sphere_error_px <= 0.5f && small.sphere_error_px <= 0.5f && fly.sphere_error_px <= 0.5f);
    CHECK(small.sphere_segments < big.sphere_segments);
    CHECK(fly.sphere_segments > big.sphere_segments);
    CHECK(big.sphere_radius_px > 4.0f * small.sphere_radius_px);
    /* Independent check: the largest sphere on screen over the flythrough,
     * frame by frame, is within the sampled largest (which it sampled). */
    double largest = 0;
    for (int k = 0; k < fly.spec.camera_period; k++) {
        struct scene_camera fc;
        scene_camera_at(&fly, k, &fc);
        for (int i = 0; i < fly.instance_count; i++)
            if (fly.instances[i].mesh == SCENE_MESH_SPHERE &&
                scene_sphere_in_frustum(fc.view_proj, fly.instances[i].pos, 0.8f, false))
                largest = fmax(largest, scene_sphere_radius_px(&fc, 1080, 720, fly.instances[i].pos, 0.8f));
    }
    CHECK(largest * scene_sphere_error(fly.sphere_segments) <= 0.5 * 1.05);
    /* A tighter bound gives more segments. */
    CHECK(build(&s, "{\"sphere_segments\":\"auto\",\"tessellation_error_px\":0.1}"));
    CHECK(s.sphere_segments > big.sphere_segments && s.sphere_error_px <= 0.1f);
    CHECK(scene_triangles(&s) > scene_triangles(&big));
    printf("auto segments: 1080x720 %d (r %.1f px, error %.2f px), 160x120 %d, flythrough %d, "
           "bound 0.1: %d\n", big.sphere_segments, big.sphere_radius_px, big.sphere_error_px,
           small.sphere_segments, fly.sphere_segments, s.sphere_segments);
    scene_finish(&s);
    scene_finish(&big);
    scene_finish(&small);
    scene_finish(&fly);
}

static bool rejects(const char *json, const char *field)
{
    struct scene_spec spec;
    struct job_error err = {{0}, {0}};
    scene_spec_defaults(&spec);
    json_t *j = json_loads(json, 0, NULL);
    bool ok = j && !scene_spec_parse(j, &spec, &err) && strcmp(err.field, field) == 0 &&
              strlen(err.message) > 5;
    if (!ok)
        fprintf(stderr, "  for %s: got '%s' (%s)\n", json, err.field, err.message);
    json_decref(j);
    return ok;
}

static bool round_trips(const char *json)
{
    struct scene_spec a, b;
    struct job_error err;
    scene_spec_defaults(&a);
    scene_spec_defaults(&b);
    json_t *in = json_loads(json, 0, NULL);
    if (!in || !scene_spec_parse(in, &a, &err))
        return false;
    json_t *out = scene_spec_to_json(&a);
    bool ok = scene_spec_parse(out, &b, &err);
    json_t *again = scene_spec_to_json(&b);
    ok = ok && json_equal(out, again) && memcmp(&a, &b, sizeof(a)) == 0;
    /* Every option is written back. */
    ok = ok && json_object_size(out) == 21;
    json_decref(in);
    json_decref(out);
    json_decref(again);
    return ok;
}

static void test_spec(void)
{
    struct scene_spec s;
    scene_spec_defaults(&s);
    CHECK(s.preset == SCENE_PRESET_GRID && s.lights == 10 && s.light_radius == 5.0);
    CHECK(s.light_layout == SCENE_LAYOUT_HALTON && s.materials == SCENE_MATERIALS_UNIFORM);
    CHECK(s.light_intensity == 1.0 && s.specular == 0.5 && s.shininess == 32.0);
    CHECK(s.camera == SCENE_CAMERA_STATIC && s.sphere_segments == 32);
    json_t *j = scene_spec_to_json(&s);
    CHECK(strcmp(json_string_value(json_object_get(j, "preset")), "grid") == 0);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(j, "camera"), "path")),
                 "static") == 0);
    json_decref(j);

    CHECK(round_trips("{}"));
    CHECK(round_trips("{\"preset\":\"lights\"}"));
    CHECK(round_trips("{\"preset\":\"lights\",\"lights\":16384,\"light_layout\":\"clustered\","
                      "\"light_radius\":1.5,\"light_intensity\":0.25,\"sphere_segments\":\"auto\","
                      "\"tessellation_error_px\":0.2,\"materials\":\"uniform\",\"specular\":0.1,"
                      "\"shininess\":8,\"metallic\":1,\"roughness\":0.9,\"dynamic\":true,"
                      "\"light_speed\":3,\"camera\":{\"path\":\"flythrough\",\"period\":99},"
                      "\"width\":160,\"height\":120}"));
    CHECK(round_trips("{\"camera\":\"orbit\"}"));
    CHECK(round_trips("{\"preset\":\"teapots\",\"teapot_segments\":\"auto\"}"));
    CHECK(round_trips("{\"preset\":\"chart\",\"teapot_segments\":3,\"materials\":\"preset\"}"));

    /* The preset's defaults come first, whatever the key order. */
    struct job_error err;
    scene_spec_defaults(&s);
    j = json_loads("{\"lights\":5,\"light_radius\":2,\"preset\":\"lights\"}", 0, NULL);
    CHECK(scene_spec_parse(j, &s, &err));
    CHECK(s.lights == 5 && s.light_radius == 2.0 && s.light_layout == SCENE_LAYOUT_UNIFORM);
    json_decref(j);
    scene_spec_defaults(&s);
    j = json_loads("{\"camera\":{\"path\":\"orbit\"}}", 0, NULL);
    CHECK(scene_spec_parse(j, &s, &err) && s.camera == SCENE_CAMERA_ORBIT && s.camera_period == 360);
    json_decref(j);

    CHECK(rejects("{\"preset\":\"sponza\"}", "scene.preset"));
    CHECK(rejects("{\"lights\":65537}", "scene.lights"));
    CHECK(rejects("{\"lights\":-1}", "scene.lights"));
    CHECK(rejects("{\"light_radius\":0}", "scene.light_radius"));
    CHECK(rejects("{\"light_radius\":\"big\"}", "scene.light_radius"));
    CHECK(rejects("{\"light_intensity\":-1}", "scene.light_intensity"));
    CHECK(rejects("{\"light_layout\":\"spiral\"}", "scene.light_layout"));
    CHECK(rejects("{\"materials\":\"shiny\"}", "scene.materials"));
    CHECK(rejects("{\"specular\":-0.5}", "scene.specular"));
    CHECK(rejects("{\"shininess\":0}", "scene.shininess"));
    CHECK(rejects("{\"metallic\":2}", "scene.metallic"));
    CHECK(rejects("{\"roughness\":1.5}", "scene.roughness"));
    CHECK(rejects("{\"sphere_segments\":15}", "scene.sphere_segments"));
    CHECK(rejects("{\"sphere_segments\":\"fine\"}", "scene.sphere_segments"));
    CHECK(rejects("{\"sphere_segments\":512}", "scene.sphere_segments"));
    CHECK(rejects("{\"tessellation_error_px\":0}", "scene.tessellation_error_px"));
    CHECK(rejects("{\"camera\":\"drone\"}", "scene.camera"));
    CHECK(rejects("{\"camera\":5}", "scene.camera"));
    CHECK(rejects("{\"camera\":{\"path\":\"drone\"}}", "scene.camera.path"));
    CHECK(rejects("{\"camera\":{\"period\":0}}", "scene.camera.period"));
    CHECK(rejects("{\"camera\":{\"perid\":10}}", "scene.camera.perid"));
    CHECK(rejects("{\"ligth_radius\":3}", "scene.ligth_radius"));
}

static void test_describe(void)
{
    struct scene s;
    CHECK(build(&s, "{\"preset\":\"lights\",\"lights\":300,\"sphere_segments\":\"auto\","
                    "\"camera\":{\"path\":\"orbit\",\"period\":50}}"));
    json_t *d = scene_describe(&s);
    CHECK(d != NULL);
    CHECK(strcmp(json_string_value(json_object_get(d, "preset")), "lights") == 0);
    CHECK(json_integer_value(json_object_get(d, "instances")) == s.instance_count);
    CHECK(json_integer_value(json_object_get(d, "triangles_per_frame")) ==
          (json_int_t)scene_triangles(&s));
    json_t *tess = json_object_get(d, "sphere_tessellation");
    CHECK(json_integer_value(json_object_get(tess, "segments")) == s.sphere_segments);
    CHECK(strcmp(json_string_value(json_object_get(tess, "mode")), "auto") == 0);
    CHECK(json_real_value(json_object_get(tess, "silhouette_error_px")) <= 0.5);
    json_t *lights = json_object_get(d, "lights");
    CHECK(json_integer_value(json_object_get(lights, "count")) == 300);
    CHECK(json_real_value(json_object_get(lights, "on_screen_at_frame_0")) > 0.9);
    CHECK(json_real_value(json_object_get(json_object_get(lights, "per_object_at_frame_0"),
                                          "mean")) > 1.0);
    json_t *cam = json_object_get(d, "camera");
    CHECK(strcmp(json_string_value(json_object_get(cam, "path")), "orbit") == 0);
    CHECK(json_integer_value(json_object_get(cam, "period")) == 50);
    CHECK(json_is_true(json_object_get(cam, "moves")));
    CHECK(json_array_size(json_object_get(json_object_get(d, "bounds"), "min")) == 3);
    CHECK(json_integer_value(json_object_get(json_object_get(d, "instances_by_mesh"), "plane")) == 1);
    json_decref(d);
    scene_finish(&s);

    /* Zero lights describe too. */
    CHECK(build(&s, "{\"lights\":0}"));
    d = scene_describe(&s);
    CHECK(d && json_integer_value(json_object_get(json_object_get(d, "lights"), "count")) == 0);
    json_decref(d);
    scene_finish(&s);
}

/* The teapots preset (seed 002): eight teapots on the ground around a
 * container, each its own material, a sky, 80 lights by default; the chart
 * spans metallic by roughness; "preset" materials can be overridden. */
static void test_teapots_preset(void)
{
    struct scene_spec spec;
    struct job_error err;
    scene_spec_defaults(&spec);
    json_t *j = json_loads("{\"preset\":\"teapots\",\"width\":320,\"height\":240}", 0, NULL);
    CHECK(scene_spec_parse(j, &spec, &err));
    json_decref(j);
    CHECK(spec.lights == 80 && spec.materials == SCENE_MATERIALS_PRESET && spec.teapot_segments == 12);
    struct scene s;
    CHECK(scene_init(&s, &spec));
    CHECK(s.mesh_instance_count[SCENE_MESH_TEAPOT] == 8 && s.mesh_instance_count[SCENE_MESH_CUBE] == 1 &&
          s.mesh_instance_count[SCENE_MESH_PLANE] == 1 && s.sky && s.light_count == 80);
    CHECK(s.teapot_segments == 12 && s.meshes[SCENE_MESH_TEAPOT].index_count == 32 * 12 * 12 * 6);
    int metals = 0, distinct = 0;
    for (int i = 0; i < s.instance_count; i++) {
        const struct scene_instance *in = &s.instances[i];
        if (in->mesh != SCENE_MESH_TEAPOT)
            continue;
        metals += in->material.metallic == 1.0f;
        /* Resting on the ground: the mesh is centred, its half height up. */
        CHECK(fabsf(in->pos[1] - 1.575f * in->scale) < 1e-5f);
        bool seen = false;
        for (int k = 0; k < i; k++)
            seen |= s.instances[k].mesh == SCENE_MESH_TEAPOT &&
                    s.instances[k].material.roughness == in->material.roughness &&
                    s.instances[k].material.metallic == in->material.metallic;
        distinct += !seen;
        /* Every teapot is on screen from the preset's camera. */
        struct scene_camera cam;
        scene_camera_at(&s, 0, &cam);
        CHECK(scene_instance_in_view(&s, i, &cam));
    }
    CHECK(metals == 4 && distinct == 8);
    json_t *d = scene_describe(&s);
    CHECK(d && json_integer_value(json_object_get(json_object_get(d, "teapot_tessellation"),
                                                  "segments")) == 12);
    CHECK(json_is_true(json_object_get(d, "sky")));
    json_decref(d);
    scene_finish(&s);

    /* "auto" picks from the teapots' size on screen, finer for a larger image. */
    spec.teapot_segments = SCENE_TEAPOT_SEGMENTS_AUTO;
    CHECK(scene_init(&s, &spec));
    int small = s.teapot_segments;
    CHECK(small >= 1 && s.teapot_error_px <= spec.tessellation_error_px + 1e-6);
    scene_finish(&s);
    spec.width = 1280, spec.height = 960;
    CHECK(scene_init(&s, &spec));
    CHECK(s.teapot_segments > small);
    scene_finish(&s);

    /* Uniform materials override the preset's. */
    spec.materials = SCENE_MATERIALS_UNIFORM;
    CHECK(scene_init(&s, &spec));
    CHECK(s.instances[2].material.roughness == (float)spec.roughness);
    scene_finish(&s);

    /* The chart: metallic by row, roughness by column, corners 0 and 1. */
    scene_spec_defaults(&spec);
    scene_spec_preset_defaults(&spec, SCENE_PRESET_CHART);
    CHECK(scene_init(&s, &spec));
    CHECK(s.instance_count == 35 && s.mesh_instance_count[SCENE_MESH_SPHERE] == 35);
    CHECK(s.instances[0].material.metallic == 0.0f && s.instances[0].material.roughness == 0.0f);
    CHECK(s.instances[34].material.metallic == 1.0f && s.instances[34].material.roughness == 1.0f);
    CHECK(s.teapot_segments == 0 && s.meshes[SCENE_MESH_TEAPOT].index_count == 0);
    scene_finish(&s);

    /* One white sphere in the spec's material. */
    scene_spec_preset_defaults(&spec, SCENE_PRESET_SPHERE);
    spec.roughness = 1.0;
    CHECK(scene_init(&s, &spec));
    CHECK(s.instance_count == 2 && s.instances[0].albedo[0] == 1.0f &&
          s.instances[0].material.roughness == 1.0f);
    scene_finish(&s);

    /* Bad tessellations are named. */
    scene_spec_defaults(&spec);
    j = json_loads("{\"teapot_segments\":65}", 0, NULL);
    CHECK(!scene_spec_parse(j, &spec, &err) && strcmp(err.field, "scene.teapot_segments") == 0);
    json_decref(j);
    j = json_loads("{\"teapot_segments\":\"fine\"}", 0, NULL);
    CHECK(!scene_spec_parse(j, &spec, &err) && strcmp(err.field, "scene.teapot_segments") == 0);
    json_decref(j);
}

int main(void)
{
    test_grid_unchanged();
    test_lights_preset();
    test_layouts();
    test_camera_paths();
    test_tessellation();
    test_spec();
    test_describe();
    test_teapots_preset();
    return check_finish("test_scene");
}
