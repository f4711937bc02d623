#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/scene.h"
#include "tests/unit/check.h"

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

int main(void)
{
    struct {
        struct scene_spec scene;
    } spec;
    scene_spec_defaults(&spec.scene);
    struct scene s;
    CHECK(scene_create(&s, &spec.scene));
    CHECK(s.instance_count == 512);
    CHECK(s.mesh_instance_count[SCENE_MESH_SPHERE] == 256);
    CHECK(s.mesh_instance_count[SCENE_MESH_CUBE] == 256);
    CHECK(s.light_count == 10);
    CHECK(scene_all_in_view(&s));

    /* Rows alternate: every sphere row's neighbours along z are cube rows. */
    int layers[4] = {0};
    for (int i = 0; i < s.instance_count; i++) {
        int row = (int)lroundf(-s.instances[i].pos[2] / 3.0f);
        CHECK((row % 2 == 0) == (s.instances[i].mesh == SCENE_MESH_SPHERE));
        layers[(int)lroundf(s.instances[i].pos[1] / 2.5f)]++;
    }
    CHECK(layers[0] == 128 && layers[3] == 128);

    /* Triangles: 32 segments x 16 rings x 2 per sphere, 12 per cube. */
    CHECK(scene_triangles(&s) == 256ull * 32 * 16 * 2 + 256ull * 12);
    check_mesh(&s.meshes[SCENE_MESH_SPHERE]);
    check_mesh(&s.meshes[SCENE_MESH_CUBE]);

    /* Static lights never move; dynamic ones are periodic in the frame index. */
    float a[3], b[3];
    scene_light_position(&s, 3, 0, a);
    scene_light_position(&s, 3, 12345, b);
    CHECK(memcmp(a, b, sizeof(a)) == 0);
    scene_finish(&s);

    spec.scene.dynamic = true;
    spec.scene.width = 320;
    spec.scene.height = 240;
    CHECK(scene_create(&s, &spec.scene));
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
    }
    /* light_speed 2 halves each revolution; 0 holds the lights still. */
    struct scene fast, still;
    struct scene_spec fs = spec.scene, ss = spec.scene;
    fs.light_speed = 2.0;
    ss.light_speed = 0.0;
    CHECK(scene_create(&fast, &fs) && scene_create(&still, &ss));
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
    CHECK(scene_create(&s, &spec.scene));
    CHECK(s.light_count == 0);
    scene_finish(&s);
    return check_finish("test_scene");
}
