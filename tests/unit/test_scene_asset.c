#define _GNU_SOURCE /* M_PI */
/* The asset -> scene mapping (daemon/scene/scene_asset.c), GL-free: the
 * textured preset's synthetic asset and small hand-made ones. Instances and
 * their ordering by alpha mode, re-centring, bounds, camera choice by index
 * and name, light conversion, the "auto" light count, errors naming the
 * field, and the scene keys' parsing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/asset.h"
#include "daemon/scene/asset_synthetic.h"
#include "daemon/scene/scene.h"
#include "tests/unit/check.h"

static void spec_for(struct scene_spec *spec, const char *json)
{
    scene_spec_defaults(spec);
    json_error_t jerr;
    json_t *j = json_loads(json, 0, &jerr);
    struct job_error err = {0};
    CHECK(j && scene_spec_parse(j, spec, &err));
    json_decref(j);
}

static void test_textured_preset(void)
{
    struct scene_spec spec;
    spec_for(&spec, "{\"preset\": \"textured\", \"width\": 160, \"height\": 120}");
    struct scene s;
    char err[256];
    CHECK(scene_build(&s, &spec, NULL, err, sizeof(err)));
    CHECK(s.asset != NULL && s.owned_asset != NULL);
    const struct asset *a = s.asset;
    CHECK(s.instance_count == (int)a->mesh_count);
    CHECK(s.mesh_count == SCENE_MESH_PROCEDURAL + (int)a->mesh_count);
    /* Opaque, then masked, then blended. */
    CHECK(s.asset_mask_first == s.mesh_count - 2);
    CHECK(s.asset_blend_first == s.mesh_count - 1);
    CHECK(scene_has_blended(&s));
    for (int i = 0; i < s.instance_count; i++) {
        const struct scene_instance *in = &s.instances[i];
        int am = s.mesh_asset_index[in->mesh];
        CHECK(am >= 0 && am < (int)a->mesh_count);
        CHECK(in->asset_material == a->meshes[am].material);
        CHECK(in->scale == 1.0f);
        const struct asset_mesh *src = &a->meshes[am];
        const struct mesh *m = &s.meshes[in->mesh];
        for (int k = 0; k < 3; k++) {
            /* Re-centred: the instance at the box's centre, the mesh's box
             * symmetric about the origin. */
            CHECK_NEAR(in->pos[k], 0.5f * (src->box_min[k] + src->box_max[k]), 1e-5f);
            CHECK_NEAR(m->box_min[k], -m->box_max[k], 1e-4f);
        }
        /* Vertices: world position = instance + object position; tex the
         * file's TEXCOORD_0 and _1, uv uv1 inside its chart's rectangle
         * (mesh_chart_rects), tangent and colour
         * copied. */
        CHECK(m->vertex_count == src->vertex_count && m->index_count == src->index_count);
        for (uint32_t v = 0; v < m->vertex_count; v += 7) {
            for (int k = 0; k < 3; k++)
                CHECK_NEAR(m->vertices[v].pos[k] + in->pos[k], src->vertices[v].pos[k], 1e-5f);
            CHECK(m->vertices[v].tex[0] == src->vertices[v].uv0[0]);
            CHECK(m->vertices[v].tex[3] == src->vertices[v].texcoord1[1]);
            CHECK(m->vertices[v].color[2] == src->vertices[v].color[2]);
            CHECK(m->vertices[v].uv[1] == src->vertices[v].uv1[1]);
            const float *c = m->vertices[v].chart, *uv = m->vertices[v].uv;
            CHECK(c[0] <= uv[0] && uv[0] <= c[2] && c[1] <= uv[1] && uv[1] <= c[3]);
            CHECK(m->vertices[v].tangent[3] == src->vertices[v].tangent[3]);
        }
        CHECK(m->bound_radius > 0.0f);
        CHECK(scene_instance_bound(&s, i) == m->bound_radius);
    }
    /* Bounds: the asset's box. */
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(s.bounds.min[k], a->box_min[k], 1e-4f);
        CHECK_NEAR(s.bounds.max[k], a->box_max[k], 1e-4f);
    }
    /* Lights: the preset's 8 generated, then the spot and the sun, all in
     * glTF's falloff: colour = glTF colour x intensity / pi. */
    CHECK(s.generated_light_count == 8 && s.asset_light_count == 2 && s.light_count == 10);
    const struct scene_light *spot = &s.lights[8], *sun = &s.lights[9];
    CHECK(spot->type == SCENE_LIGHT_SPOT && sun->type == SCENE_LIGHT_DIRECTIONAL);
    CHECK(spot->falloff == SCENE_FALLOFF_GLTF && sun->falloff == SCENE_FALLOFF_GLTF);
    CHECK_NEAR(spot->color[0], 150.0f / (float)M_PI, 1e-4f);
    CHECK(spot->range == 0.0f && spot->gltf_intensity == 150.0f);
    /* No range: cut where 150 cd off white falls below 1/1024. */
    CHECK_NEAR(spot->radius, sqrtf(150.0f * 1024.0f / (float)M_PI), 1e-2f);
    CHECK_NEAR(spot->cos_inner, cosf(0.35f), 1e-6f);
    CHECK_NEAR(spot->cos_outer, cosf(0.6f), 1e-6f);
    CHECK(spot->centre[1] == 7.0f);
    CHECK_NEAR(sun->color[1], 0.98f * 2.0f / (float)M_PI, 1e-5f);
    for (int i = 0; i < 8; i++) {
        CHECK(s.lights[i].type == SCENE_LIGHT_POINT);
        CHECK(s.lights[i].falloff == SCENE_FALLOFF_GLTF && s.lights[i].range > 0.0f);
        for (int k = 0; k < 3; k++)
            CHECK(s.lights[i].centre[k] >= s.light_volume.min[k] &&
                  s.lights[i].centre[k] <= s.light_volume.max[k]);
    }
    /* Camera: the first ("main"). */
    CHECK(s.asset_camera == 0);
    CHECK_NEAR(s.eye[1], 6.5f, 1e-5f);
    CHECK_NEAR(s.fovy_deg, 50.0f, 1e-3f);
    json_t *d = scene_describe(&s);
    json_t *ad = json_object_get(d, "asset");
    CHECK(ad && json_integer_value(json_object_get(ad, "meshes")) == 7);
    CHECK(json_integer_value(json_object_get(json_object_get(ad, "materials"), "blend")) == 1);
    CHECK(json_integer_value(json_object_get(json_object_get(ad, "lights"), "spot")) == 1);
    CHECK(strcmp(json_string_value(json_object_get(ad, "camera")), "main") == 0);
    json_decref(d);
    scene_finish(&s);

    /* By name and by index; asset lights off; a wrong camera names the field. */
    spec_for(&spec, "{\"preset\": \"textured\", \"asset_camera\": \"top\", \"asset_lights\": false}");
    CHECK(scene_build(&s, &spec, NULL, err, sizeof(err)));
    CHECK(s.asset_camera == 1 && s.asset_light_count == 0 && s.light_count == 8);
    CHECK_NEAR(s.eye[1], 16.0f, 1e-5f);
    scene_finish(&s);
    spec_for(&spec, "{\"preset\": \"textured\", \"asset_camera\": 1}");
    CHECK(scene_build(&s, &spec, NULL, err, sizeof(err)) && s.asset_camera == 1);
    scene_finish(&s);
    spec_for(&spec, "{\"preset\": \"textured\", \"asset_camera\": \"side\"}");
    CHECK(!scene_build(&s, &spec, NULL, err, sizeof(err)));
    CHECK(strstr(err, "scene.asset_camera") && strstr(err, "\"side\"") && strstr(err, "main"));
    spec_for(&spec, "{\"preset\": \"textured\", \"asset_camera\": 5}");
    CHECK(!scene_build(&s, &spec, NULL, err, sizeof(err)) && strstr(err, "no camera 5"));
}

/* A one-triangle asset, for the error and default paths. */
static struct asset_vertex tri_v[3] = {
    {{0, 0, 0}, {0, 0, 1}, {1, 0, 0, 1}, {0, 0}, {0, 0}, {0, 0}, {1, 1, 1, 1}},
    {{2, 0, 0}, {0, 0, 1}, {1, 0, 0, 1}, {1, 0}, {1, 0}, {1, 0}, {1, 1, 1, 1}},
    {{0, 2, 0}, {0, 0, 1}, {1, 0, 0, 1}, {0, 1}, {0, 1}, {0, 1}, {1, 1, 1, 1}},
};
static uint32_t tri_i[3] = {0, 1, 2};

static void tiny(struct asset *a, struct asset_mesh *m)
{
    memset(a, 0, sizeof(*a));
    memset(m, 0, sizeof(*m));
    m->vertices = tri_v, m->indices = tri_i, m->vertex_count = 3, m->index_count = 3;
    m->material = -1;
    m->box_max[0] = m->box_max[1] = 2.0f;
    a->meshes = m, a->mesh_count = 1;
    a->box_max[0] = a->box_max[1] = 2.0f;
}

static void test_user_asset(void)
{
    struct asset a;
    struct asset_mesh m;
    tiny(&a, &m);
    struct scene_spec spec;
    spec_for(&spec, "{\"asset\": \"tri\", \"width\": 160, \"height\": 120}");
    CHECK(spec.lights == SCENE_LIGHTS_AUTO);
    struct scene s;
    char err[256];
    CHECK(!scene_build(&s, &spec, NULL, err, sizeof(err)) && strstr(err, "scene.asset"));
    CHECK(scene_build(&s, &spec, &a, err, sizeof(err)));
    /* No lights of its own: 16 generated; no camera: framed, every corner
     * of the bounds in view. */
    CHECK(s.light_count == SCENE_ASSET_DEFAULT_LIGHTS && s.asset_camera == -1);
    CHECK(s.instances[0].asset_material == -1 && s.instances[0].albedo[0] == 1.0f);
    CHECK(scene_all_in_view(&s));
    CHECK(!scene_has_blended(&s));
    /* Generated lights stand around and over it, outside its bounds. */
    for (int i = 0; i < s.light_count; i++) {
        const float *c = s.lights[i].centre;
        bool inside = true;
        for (int k = 0; k < 3; k++)
            inside = inside && c[k] >= a.box_min[k] && c[k] <= a.box_max[k];
        CHECK(!inside && c[1] > 0.5f * (a.box_min[1] + a.box_max[1]));
    }
    scene_finish(&s);
    /* Every layout, lights of small range hugging the surfaces, circling:
     * at every frame no light is inside the box. */
    static const char *const layouts[] = {"halton", "uniform", "grid", "clustered"};
    for (int li = 0; li < 4; li++)
        for (int small = 0; small < 2; small++) {
            char json[256];
            snprintf(json, sizeof(json), "{\"asset\": \"tri\", \"lights\": 64, \"dynamic\": true, "
                     "\"light_layout\": \"%s\"%s}", layouts[li],
                     small ? ", \"light_radius\": 0.05" : "");
            struct scene_spec sp;
            spec_for(&sp, json);
            CHECK(scene_build(&s, &sp, &a, err, sizeof(err)) && s.light_count == 64);
            int inside_count = 0;
            for (int i = 0; i < s.light_count; i++)
                for (int64_t f = 0; f < 400; f += 13) {
                    float p[3];
                    scene_light_position(&s, i, f, p);
                    bool inside = true;
                    for (int k = 0; k < 3; k++)
                        inside = inside && p[k] >= a.box_min[k] && p[k] <= a.box_max[k];
                    inside_count += inside;
                }
            CHECK(inside_count == 0);
            CHECK(s.lights[0].range == (small ? 0.05f : 5.0f * sqrtf(2.0f)));
            scene_finish(&s);
        }

    /* A point light without range, and one with; lights "auto" with asset
     * lights: none generated. */
    struct asset_light l[2] = {{.type = ASSET_LIGHT_POINT, .color = {1, 1, 1}, .intensity = 400},
                               {.type = ASSET_LIGHT_POINT, .color = {1, 0, 0}, .intensity = 50,
                                .range = 3}};
    a.lights = l, a.light_count = 2;
    CHECK(scene_build(&s, &spec, &a, err, sizeof(err)));
    CHECK(s.light_count == 2 && s.generated_light_count == 0);
    CHECK_NEAR(s.lights[0].radius, sqrtf(400.0f * 1024.0f / (float)M_PI), 1e-2f);
    CHECK_NEAR(s.lights[0].color[0], 400.0f / (float)M_PI, 1e-3f);
    CHECK(s.lights[1].radius == 3.0f && s.lights[1].range == 3.0f);
    scene_finish(&s);

    /* Errors name the field. */
    m.material = 3;
    CHECK(!scene_build(&s, &spec, &a, err, sizeof(err)));
    CHECK(strstr(err, "asset.meshes[0].material") != NULL);
    m.material = -1;
    tri_i[2] = 9;
    CHECK(!scene_build(&s, &spec, &a, err, sizeof(err)));
    CHECK(strstr(err, "asset.meshes[0].indices[2]") != NULL);
    tri_i[2] = 2;
    struct asset_material mat = {.alpha_mode = ASSET_ALPHA_OPAQUE};
    for (int t = 0; t < ASSET_TEX_SLOTS; t++)
        mat.tex[t].image = -1;
    mat.tex[ASSET_TEX_NORMAL].image = 0;
    a.materials = &mat, a.material_count = 1, m.material = 0;
    CHECK(!scene_build(&s, &spec, &a, err, sizeof(err)));
    CHECK(strstr(err, "asset.materials[0].normal.image") != NULL);
}

static void test_spec_keys(void)
{
    struct scene_spec spec;
    scene_spec_defaults(&spec);
    struct job_error err = {0};
    json_t *j = json_pack("{s:s}", "asset_camera", "main");
    CHECK(!scene_spec_parse(j, &spec, &err) && strcmp(err.field, "scene.asset_camera") == 0);
    json_decref(j);
    scene_spec_defaults(&spec);
    j = json_pack("{s:b}", "normal_maps", 0);
    CHECK(!scene_spec_parse(j, &spec, &err) && strcmp(err.field, "scene.normal_maps") == 0);
    json_decref(j);
    scene_spec_defaults(&spec);
    j = json_pack("{s:s}", "lights", "auto");
    CHECK(!scene_spec_parse(j, &spec, &err) && strcmp(err.field, "scene.lights") == 0);
    json_decref(j);
    /* Round trip of an asset spec. */
    spec_for(&spec, "{\"asset\": \"x\", \"asset_camera\": 2, \"normal_maps\": false}");
    json_t *out = scene_spec_to_json(&spec);
    CHECK(strcmp(json_string_value(json_object_get(out, "lights")), "auto") == 0);
    struct scene_spec back;
    scene_spec_defaults(&back);
    CHECK(scene_spec_parse(out, &back, &err));
    CHECK(back.lights == SCENE_LIGHTS_AUTO && !back.normal_maps && strcmp(back.asset_camera, "2") == 0);
    json_decref(out);
    /* A preset spec writes no asset keys. */
    scene_spec_defaults(&spec);
    out = scene_spec_to_json(&spec);
    CHECK(!json_object_get(out, "normal_maps") && !json_object_get(out, "asset_lights"));
    json_decref(out);
}

int main(void)
{
    test_textured_preset();
    test_user_asset();
    test_spec_keys();
    return check_finish("test_scene_asset");
}
