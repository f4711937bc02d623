/* Building a scene (preset, materials, bounds, camera rig, tessellation,
 * meshes) and the queries every technique and the harness make of it. */
#include "daemon/scene/scene.h"
#include "daemon/scene/light_shape.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/asset.h"
#include "daemon/scene/asset_synthetic.h"
#include "daemon/scene/scene_build.h"
#include "daemon/scene/teapot.h"

static const double PI = 3.14159265358979323846;

const char *const scene_mesh_names[] = {"sphere", "cube", "plane", "teapot", NULL};
const char *const scene_light_type_names[] = {"point", "spot", "directional", NULL};

/* Object-space half extents of instance i's axis-aligned box. */
static void instance_half_extent(const struct scene *s, const struct scene_instance *in,
                                 float out[3])
{
    switch ((enum scene_mesh)in->mesh) {
    case SCENE_MESH_SPHERE:
        out[0] = out[1] = out[2] = SCENE_SPHERE_RADIUS * in->scale;
        return;
    case SCENE_MESH_CUBE:
        out[0] = out[1] = out[2] = SCENE_CUBE_HALF * in->scale;
        return;
    case SCENE_MESH_TEAPOT:
        for (int k = 0; k < 3; k++)
            out[k] = SCENE_TEAPOT_HALF[k] * in->scale;
        return;
    case SCENE_MESH_PLANE:
        out[0] = out[2] = SCENE_PLANE_HALF * in->scale;
        out[1] = 0.0f;
        return;
    default:
        /* An asset's mesh, centred on its instance's position. */
        for (int k = 0; k < 3; k++)
            out[k] = fmaxf(-s->meshes[in->mesh].box_min[k], s->meshes[in->mesh].box_max[k]) *
                     in->scale;
        return;
    }
}

static void box_empty(struct scene_box *b)
{
    for (int k = 0; k < 3; k++) {
        b->min[k] = INFINITY;
        b->max[k] = -INFINITY;
    }
}

static void compute_bounds(struct scene *s)
{
    box_empty(&s->bounds);
    box_empty(&s->objects);
    for (int i = 0; i < s->instance_count; i++) {
        const struct scene_instance *in = &s->instances[i];
        float half[3];
        instance_half_extent(s, in, half);
        for (int k = 0; k < 3; k++) {
            s->bounds.min[k] = fminf(s->bounds.min[k], in->pos[k] - half[k]);
            s->bounds.max[k] = fmaxf(s->bounds.max[k], in->pos[k] + half[k]);
            if (in->mesh == SCENE_MESH_PLANE)
                continue;
            s->objects.min[k] = fminf(s->objects.min[k], in->pos[k] - half[k]);
            s->objects.max[k] = fmaxf(s->objects.max[k], in->pos[k] + half[k]);
        }
    }
    if (s->objects.min[0] > s->objects.max[0])
        s->objects = s->bounds; /* a scene of ground only */
}

bool scene_init(struct scene *out, const struct scene_spec *spec)
{
    char err[256];
    return scene_build(out, spec, NULL, err, sizeof(err));
}

bool scene_has_blended(const struct scene *s)
{
    return s->asset && s->asset_blend_first < s->mesh_count;
}

/* The asset path: the synthetic asset for the textured preset, the
 * caller's for scene.asset; instances, meshes, lights and pose from it. */
static bool build_from_asset(struct scene *out, const struct asset *asset, char *err,
                             size_t errlen)
{
    if (!out->spec.asset[0]) {
        if (!(out->owned_asset = calloc(1, sizeof(*out->owned_asset))) ||
            !asset_synthetic_textured(out->owned_asset, err, errlen)) {
            free(out->owned_asset);
            out->owned_asset = NULL;
            if (!err[0])
                snprintf(err, errlen, "out of memory building the textured preset");
            return false;
        }
        asset = out->owned_asset;
    } else if (!asset) {
        snprintf(err, errlen, "scene.asset: the asset \"%s\" was not loaded", out->spec.asset);
        return false;
    }
    out->asset = asset;
    /* The textured preset draws the look's sky behind it, as the other
     * presets with open backgrounds do; an uploaded asset is shown alone. */
    out->sky = !out->spec.asset[0];
    out->mesh_count = SCENE_MESH_PROCEDURAL + (int)asset->mesh_count;
    if (!(out->meshes = calloc((size_t)out->mesh_count, sizeof(*out->meshes)))) {
        snprintf(err, errlen, "out of memory for the asset's meshes");
        return false;
    }
    return scene_build_asset(out, err, errlen);
}

bool scene_build(struct scene *out, const struct scene_spec *spec, const struct asset *asset,
                 char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    out->spec = *spec;
    out->asset_camera = -1;
    err[0] = '\0';
    bool materials_set = false;
    if (scene_spec_is_asset(spec)) {
        if (!build_from_asset(out, asset, err, errlen))
            goto fail;
        materials_set = true; /* the materials' factors, whatever scene.materials says */
        out->spec.materials = SCENE_MATERIALS_PRESET;
    } else {
        out->mesh_count = SCENE_MESH_PROCEDURAL;
        if (!(out->meshes = calloc((size_t)out->mesh_count, sizeof(*out->meshes))) ||
            !scene_build_preset(out, &materials_set))
            goto fail;
        for (int i = 0; i < out->instance_count; i++)
            out->instances[i].asset_material = -1;
        out->asset_mask_first = out->asset_blend_first = out->mesh_count;
    }
    if (!scene_add_sun(out) || !(out->mesh_instance_count = calloc((size_t)out->mesh_count, sizeof(int))))
        goto fail;
    for (int i = 0; i < out->instance_count; i++) {
        /* Each mesh is one instanced draw over a contiguous range. */
        int m = out->instances[i].mesh;
        if ((i && m < out->instances[i - 1].mesh) || m < 0 || m >= out->mesh_count)
            goto fail;
        out->mesh_instance_count[m]++;
    }
    scene_assign_materials(out, materials_set);
    compute_bounds(out);
    /* After the bounds, which frame the camera without it: the mover
     * crosses what the camera already sees. */
    out->mover = -1;
    if (!scene_add_mover(out))
        goto fail;
    if (!scene_add_rig(out))
        goto fail;
    scene_apply_pose(out);
    scene_rig_derive(out);
    scene_choose_segments(out);
    if (!mesh_create_sphere(&out->meshes[SCENE_MESH_SPHERE], SCENE_SPHERE_RADIUS,
                            out->sphere_segments) ||
        !mesh_create_cube(&out->meshes[SCENE_MESH_CUBE], SCENE_CUBE_HALF) ||
        !mesh_create_plane(&out->meshes[SCENE_MESH_PLANE], SCENE_PLANE_HALF) ||
        (out->mesh_instance_count[SCENE_MESH_TEAPOT] &&
         !mesh_create_teapot(&out->meshes[SCENE_MESH_TEAPOT], out->teapot_segments, 1.0f)))
        goto fail;
    for (int m = 0; m < out->mesh_count; m++)
        mesh_compute_box(&out->meshes[m]);

    struct scene_camera cam;
    scene_camera_at(out, 0, &cam);
    memcpy(out->eye, cam.eye, sizeof(out->eye));
    memcpy(out->target, cam.target, sizeof(out->target));
    out->fovy_deg = cam.fovy_deg;
    out->near_z = cam.near_z;
    out->far_z = cam.far_z;
    memcpy(out->view, cam.view, sizeof(out->view));
    memcpy(out->proj, cam.proj, sizeof(out->proj));
    memcpy(out->view_proj, cam.view_proj, sizeof(out->view_proj));
    return true;
fail:
    if (!err[0])
        snprintf(err, errlen, "out of memory building the scene");
    scene_finish(out);
    return false;
}


void scene_finish(struct scene *s)
{
    if (!s)
        return;
    for (int m = 0; s->meshes && m < s->mesh_count; m++)
        mesh_finish(&s->meshes[m]);
    free(s->meshes);
    free(s->mesh_instance_count);
    free(s->instances);
    free(s->lights);
    free(s->mesh_asset_index);
    if (s->owned_asset) {
        asset_finish(s->owned_asset);
        free(s->owned_asset);
    }
    memset(s, 0, sizeof(*s));
}

void scene_light_position(const struct scene *s, int light, int64_t frame,
                          float out[3])
{
    const struct scene_light *l = &s->lights[light];
    int64_t t = s->spec.dynamic && s->spec.light_speed > 0 ? frame : 0;
    int64_t step = (t + l->phase) % l->period;
    if (step < 0)
        step += l->period;
    /* Integer frame arithmetic first, so the angle never loses precision
     * however long the run is. */
    double a = 2.0 * PI * (double)step / (double)l->period;
    if (s->light_orbit_plane == SCENE_ORBIT_XY) {
        out[0] = l->centre[0] + l->orbit * (float)cos(a);
        out[1] = l->centre[1] + l->orbit * (float)sin(a);
        out[2] = l->centre[2];
    } else {
        out[0] = l->centre[0] + l->orbit * (float)cos(a);
        out[1] = l->centre[1];
        out[2] = l->centre[2] + l->orbit * (float)sin(a);
    }
}

float scene_instance_bound(const struct scene *s, int i)
{
    const struct scene_instance *in = &s->instances[i];
    return s->meshes[in->mesh].bound_radius * in->scale;
}

float scene_instance_distance(const struct scene *s, int i)
{
    const float *p = s->instances[i].pos;
    float d[3] = {p[0] - s->eye[0], p[1] - s->eye[1], p[2] - s->eye[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

float scene_projected_diameter(const struct scene *s, int i)
{
    float dist = scene_instance_distance(s, i), r = scene_instance_bound(s, i);
    float half_height_px = 0.5f * (float)s->spec.height;
    float tan_half = tanf((float)(s->fovy_deg * PI / 360.0));
    return 2.0f * r / (dist * tan_half) * half_height_px;
}

uint64_t scene_triangles(const struct scene *s)
{
    uint64_t total = 0;
    for (int m = 0; m < s->mesh_count; m++)
        total += (uint64_t)s->mesh_instance_count[m] * (s->meshes[m].index_count / 3);
    return total;
}

bool scene_all_in_view(const struct scene *s)
{
    for (int i = 0; i < s->instance_count; i++)
        if (!scene_sphere_in_frustum(s->view_proj, s->instances[i].pos,
                                     scene_instance_bound(s, i), true))
            return false;
    return true;
}

static bool point_in_clip(const float view_proj[16], const float p[3])
{
    float c[4];
    scene_mat4_transform(view_proj, p, 1.0f, c);
    return c[3] > 0 && fabsf(c[0]) <= c[3] && fabsf(c[1]) <= c[3] && fabsf(c[2]) <= c[3];
}

bool scene_instance_in_view(const struct scene *s, int i, const struct scene_camera *c)
{
    const struct scene_instance *in = &s->instances[i];
    float half[3];
    instance_half_extent(s, in, half);
    for (int corner = 0; corner < 8; corner++) {
        float p[3];
        for (int k = 0; k < 3; k++)
            p[k] = in->pos[k] + (corner >> k & 1 ? half[k] : -half[k]);
        if (!point_in_clip(c->view_proj, p))
            return false;
    }
    return true;
}

int scene_instances_in_view(const struct scene *s, const struct scene_camera *c)
{
    int n = 0;
    for (int i = 0; i < s->instance_count; i++)
        n += scene_instance_in_view(s, i, c);
    return n;
}

static json_t *vec3_json(const float v[3])
{
    return json_pack("[f, f, f]", (double)v[0], (double)v[1], (double)v[2]);
}

static json_t *box_json(const struct scene_box *b)
{
    return json_pack("{s:o, s:o}", "min", vec3_json(b->min), "max", vec3_json(b->max));
}

static json_t *describe_lights(const struct scene *s)
{
    /* How many lights reach each object at frame 0 (a light's region, its
     * sphere or a spot's cone, meets the object's bounding sphere, as
     * light_shape.h tests it; a directional light reaches every object; the
     * ground left out) and how many light positions are on screen (of the
     * lights that have one): the overlap the light radius controls. */
    struct scene_camera cam;
    scene_camera_at(s, 0, &cam);
    float *pos = malloc((size_t)(s->light_count ? s->light_count : 1) * 3 * sizeof(float));
    if (!pos)
        return NULL;
    int on_screen = 0, positioned = 0, by_type[3] = {0, 0, 0};
    for (int l = 0; l < s->light_count; l++) {
        scene_light_position(s, l, 0, &pos[l * 3]);
        by_type[s->lights[l].type]++;
        if (s->lights[l].type == SCENE_LIGHT_DIRECTIONAL)
            continue;
        positioned++;
        on_screen += point_in_clip(cam.view_proj, &pos[l * 3]);
    }
    double sum = 0;
    int most = 0, objects = 0;
    for (int i = 0; i < s->instance_count; i++) {
        const struct scene_instance *in = &s->instances[i];
        if (in->mesh == SCENE_MESH_PLANE)
            continue;
        float bound = scene_instance_bound(s, i);
        int reach = 0;
        for (int l = 0; l < s->light_count; l++)
            reach += scene_light_reaches(&s->lights[l], &pos[l * 3], in->pos, bound);
        sum += reach;
        most = reach > most ? reach : most;
        objects++;
    }
    free(pos);
    json_t *out = json_pack(
        "{s:i, s:s, s:f, s:f, s:o, s:s, s:f, s:f, s:{s:f, s:i}, s:{s:i, s:i, s:i}, s:s, s:b}",
        "count", s->light_count, "layout", scene_layout_names[s->spec.light_layout], "radius",
        s->spec.light_radius, "intensity", s->spec.light_intensity, "volume",
        box_json(&s->light_volume), "orbit_plane",
        s->light_orbit_plane == SCENE_ORBIT_XY ? "xy" : "xz", "orbit",
        s->light_count ? (double)s->lights[0].orbit : 0.0, "on_screen_at_frame_0",
        positioned ? (double)on_screen / positioned : 0.0, "per_object_at_frame_0", "mean",
        objects ? sum / objects : 0.0, "max", most, "by_type", "point",
        by_type[SCENE_LIGHT_POINT], "spot", by_type[SCENE_LIGHT_SPOT], "directional",
        by_type[SCENE_LIGHT_DIRECTIONAL], "type", scene_light_type_names[s->spec.light_type],
        "sun", s->spec.sun);
    if (out && s->spec.light_type == SCENE_LIGHT_SPOT)
        json_object_set_new(out, "spot",
                            json_pack("{s:f, s:f, s:[f, f, f]}", "outer_deg",
                                      s->spec.spot_angle_deg, "inner_deg",
                                      s->spec.spot_angle_deg * SCENE_SPOT_INNER_RATIO,
                                      "direction", 0.0, -1.0, 0.0));
    if (out && s->spec.sun)
        json_object_set_new(out, "sun_light",
                            json_pack("{s:i, s:o, s:[f, f, f]}", "index", s->light_count - 1,
                                      "direction", vec3_json(SCENE_SUN_DIRECTION), "color",
                                      (double)s->lights[s->light_count - 1].color[0],
                                      (double)s->lights[s->light_count - 1].color[1],
                                      (double)s->lights[s->light_count - 1].color[2]));
    return out;
}

static json_t *mat4_json(const float m[16])
{
    json_t *a = json_array();
    for (int i = 0; a && i < 16; i++)
        json_array_append_new(a, json_real(m[i]));
    return a;
}

static json_t *describe_camera(const struct scene *s)
{
    const struct scene_rig *r = &s->rig;
    struct scene_camera cam;
    scene_camera_at(s, 0, &cam);
    json_t *o = json_pack("{s:s, s:i, s:b, s:f, s:f, s:f, s:o, s:o}", "path",
                          scene_camera_names[s->spec.camera], "period", s->spec.camera_period,
                          "moves", scene_camera_moves(s), "fovy_deg", (double)cam.fovy_deg,
                          "near", (double)cam.near_z, "far", (double)cam.far_z,
                          "eye_at_frame_0", vec3_json(cam.eye), "target_at_frame_0",
                          vec3_json(cam.target));
    /* The frame-0 camera exactly as drawn, for a renderer that must
     * reproduce it (the glTF reference): column-major, GL clip space. */
    json_object_set_new(o, "up_at_frame_0", vec3_json(cam.up));
    json_object_set_new(o, "projection", json_string(cam.orthographic ? "orthographic"
                                                                      : "perspective"));
    json_object_set_new(o, "aspect", json_real((double)s->spec.width / s->spec.height));
    if (cam.orthographic)
        json_object_set_new(o, "orthographic", json_pack("{s:f, s:f}", "xmag", (double)cam.xmag,
                                                         "ymag", (double)cam.ymag));
    json_object_set_new(o, "view_matrix", mat4_json(cam.view));
    json_object_set_new(o, "projection_matrix", mat4_json(cam.proj));
    json_object_set_new(o, "source", json_string(s->spec.view.given ? "scene.camera"
                                                 : s->asset_camera >= 0 ? "asset camera"
                                                 : s->asset ? "framed from the bounds"
                                                            : "preset"));
    if (s->spec.camera == SCENE_CAMERA_ORBIT)
        json_object_update_new(o, json_pack("{s:o, s:f, s:f}", "centre", vec3_json(r->centre),
                                            "distance", (double)r->orbit_distance,
                                            "elevation_deg",
                                            r->orbit_elevation * 180.0 / PI));
    else if (s->spec.camera == SCENE_CAMERA_FLYTHROUGH)
        json_object_update_new(o, json_pack("{s:[f, f], s:[f, f], s:f}", "radius_xz",
                                            (double)r->fly_radius[0], (double)r->fly_radius[1],
                                            "height", (double)r->fly_height[0],
                                            (double)r->fly_height[1], "look_at_height",
                                            (double)r->fly_look_y));
    return o;
}

/* The lights in glTF's terms (KHR_lights_punctual), where they have them:
 * every light of an asset scene and scene.light_rig's, at frame 0, in
 * order, at most SCENE_DESCRIBE_MAX_GLTF_LIGHTS. */
#define SCENE_DESCRIBE_MAX_GLTF_LIGHTS 1024
static json_t *describe_gltf_lights(const struct scene *s)
{
    json_t *list = json_array();
    int listed = 0;
    for (int i = 0; list && i < s->light_count; i++) {
        const struct scene_light *l = &s->lights[i];
        if (l->falloff != SCENE_FALLOFF_GLTF)
            continue;
        if (listed++ >= SCENE_DESCRIBE_MAX_GLTF_LIGHTS)
            continue;
        const char *source = i < s->generated_light_count ? "generated"
                             : i < s->generated_light_count + s->asset_light_count ? "asset"
                             : i >= s->light_count - s->rig_light_count ? "light_rig"
                                                                         : "sun";
        json_t *o = json_pack("{s:i, s:s, s:s, s:o, s:f, s:f}", "index", i, "source", source,
                              "type", scene_light_type_names[l->type], "color",
                              vec3_json(l->gltf_color), "intensity", (double)l->gltf_intensity,
                              "radius", (double)l->radius);
        if (l->type != SCENE_LIGHT_DIRECTIONAL) {
            float p[3];
            scene_light_position(s, i, 0, p);
            json_object_set_new(o, "position", vec3_json(p));
            json_object_set_new(o, "range", l->range > 0 ? json_real(l->range) : json_null());
        }
        if (l->type != SCENE_LIGHT_POINT)
            json_object_set_new(o, "direction", vec3_json(l->direction));
        if (l->type == SCENE_LIGHT_SPOT) {
            json_object_set_new(o, "inner_cone_deg", json_real(acos(l->cos_inner) * 180.0 / PI));
            json_object_set_new(o, "outer_cone_deg", json_real(acos(l->cos_outer) * 180.0 / PI));
        }
        json_array_append_new(list, o);
    }
    json_t *out = json_pack("{s:o, s:i, s:s}", "lights", list, "count", listed, "units",
                            "KHR_lights_punctual: intensity in candela (point, spot) or lux "
                            "(directional), colour linear; falloff 1 / d^2 times the range "
                            "window; radius: where the light is cut (its range, or where its "
                            "radiance off a white surface falls below 1/1024)");
    if (out && listed > SCENE_DESCRIBE_MAX_GLTF_LIGHTS)
        json_object_set_new(out, "truncated_to", json_integer(SCENE_DESCRIBE_MAX_GLTF_LIGHTS));
    return out;
}

/* What an asset scene is: which asset, its size, materials by alpha mode,
 * the textures they read, the lights by type and where the camera is. */
static json_t *describe_asset(const struct scene *s)
{
    const struct asset *a = s->asset;
    uint64_t triangles = 0, vertices = 0;
    for (uint32_t m = 0; m < a->mesh_count; m++) {
        triangles += a->meshes[m].index_count / 3;
        vertices += a->meshes[m].vertex_count;
    }
    int modes[3] = {0, 0, 0}, slots[ASSET_TEX_SLOTS] = {0};
    for (uint32_t m = 0; m < a->material_count; m++) {
        modes[a->materials[m].alpha_mode]++;
        for (int t = 0; t < ASSET_TEX_SLOTS; t++)
            slots[t] += a->materials[m].tex[t].image >= 0;
    }
    json_t *by_slot = json_object();
    for (int t = 0; t < ASSET_TEX_SLOTS; t++)
        json_object_set_new(by_slot, asset_texture_slot_names[t], json_integer(slots[t]));
    int types[3] = {0, 0, 0};
    for (int l = s->generated_light_count;
         l < s->generated_light_count + s->asset_light_count; l++)
        types[s->lights[l].type]++;
    uint64_t texels = 0;
    for (uint32_t i = 0; i < a->image_count; i++)
        texels += (uint64_t)a->images[i].width * a->images[i].height;
    return json_pack(
        "{s:s, s:s, s:i, s:I, s:I, s:{s:i, s:i, s:i, s:i}, s:{s:i, s:I, s:o}, "
        "s:{s:i, s:i, s:i, s:i, s:i}, s:s, s:b, s:o}",
        "name", s->spec.asset[0] ? s->spec.asset : "textured (built in)", "sha256",
        s->spec.asset_sha256, "meshes", (int)a->mesh_count, "triangles", (json_int_t)triangles,
        "vertices", (json_int_t)vertices, "materials", "count", (int)a->material_count, "opaque",
        modes[ASSET_ALPHA_OPAQUE], "mask", modes[ASSET_ALPHA_MASK], "blend",
        modes[ASSET_ALPHA_BLEND], "textures", "images", (int)a->image_count, "texels",
        (json_int_t)texels, "materials_by_slot", by_slot, "lights", "from_asset",
        s->asset_light_count, "point", types[SCENE_LIGHT_POINT], "spot", types[SCENE_LIGHT_SPOT],
        "directional", types[SCENE_LIGHT_DIRECTIONAL], "generated", s->generated_light_count,
        "camera", s->asset_camera >= 0 ? a->cameras[s->asset_camera].name : "framed from the bounds",
        "normal_maps", s->spec.normal_maps, "box",
        box_json(&(struct scene_box){{a->box_min[0], a->box_min[1], a->box_min[2]},
                                     {a->box_max[0], a->box_max[1], a->box_max[2]}}));
}

json_t *scene_describe(const struct scene *s)
{
    json_t *by_mesh = json_object();
    for (int m = 0; m < SCENE_MESH_PROCEDURAL; m++)
        json_object_set_new(by_mesh, scene_mesh_names[m], json_integer(s->mesh_instance_count[m]));
    json_t *lights = describe_lights(s);
    if (!lights) {
        json_decref(by_mesh);
        return NULL;
    }
    bool automatic = s->spec.sphere_segments == SCENE_SEGMENTS_AUTO;
    json_t *segments = json_pack("{s:s, s:i, s:i, s:f, s:f}", "mode",
                                 automatic ? "auto" : "fixed", "segments", s->sphere_segments,
                                 "triangles_per_sphere",
                                 (int)(s->meshes[SCENE_MESH_SPHERE].index_count / 3),
                                 "largest_radius_px", (double)s->sphere_radius_px,
                                 "silhouette_error_px", (double)s->sphere_error_px);
    if (automatic)
        json_object_set_new(segments, "error_bound_px", json_real(s->spec.tessellation_error_px));
    json_t *out = json_pack("{s:s, s:i, s:o, s:I, s:o, s:o, s:s, s:o, s:o, s:b}", "preset",
                            scene_preset_names[s->spec.preset], "instances", s->instance_count,
                            "instances_by_mesh", by_mesh, "triangles_per_frame",
                            (json_int_t)scene_triangles(s), "sphere_tessellation", segments,
                            "lights", lights, "materials",
                            scene_materials_names[s->spec.materials], "camera",
                            describe_camera(s), "bounds", box_json(&s->bounds), "sky", s->sky);
    if (out && s->asset)
        json_object_set_new(out, "asset", describe_asset(s));
    if (out && s->mover >= 0)
        json_object_set_new(out, "mover",
                            json_pack("{s:i, s:o, s:o, s:f, s:i}", "instance", s->mover, "from",
                                      vec3_json(s->mover_from), "to", vec3_json(s->mover_to),
                                      "radius",
                                      (double)(SCENE_SPHERE_RADIUS *
                                               s->instances[s->mover].scale),
                                      "period", s->spec.mover_period));
    if (out && (s->asset || s->rig_light_count))
        json_object_set_new(out, "gltf_lights", describe_gltf_lights(s));
    if (out && s->mesh_instance_count[SCENE_MESH_TEAPOT])
        json_object_set_new(
            out, "teapot_tessellation",
            json_pack("{s:s, s:i, s:i, s:f, s:f}", "mode",
                      s->spec.teapot_segments == SCENE_TEAPOT_SEGMENTS_AUTO ? "auto" : "fixed",
                      "segments", s->teapot_segments, "triangles_per_teapot",
                      (int)(s->meshes[SCENE_MESH_TEAPOT].index_count / 3), "largest_px_per_unit",
                      (double)s->teapot_px_per_unit, "error_px", (double)s->teapot_error_px));
    return out;
}
