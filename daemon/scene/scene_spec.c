#define _POSIX_C_SOURCE 200809L
#include "daemon/scene/scene_spec.h"

#include "daemon/scene/scene.h" /* scene_light_type_names */

#include <stdio.h>
#include <string.h>

const char *const scene_preset_names[] = {"grid", "lights", "teapots", "chart", "sphere",
                                             "plane", "textured", NULL};
const char *const scene_layout_names[] = {"halton", "uniform", "grid", "clustered", NULL};
const char *const scene_materials_names[] = {"uniform", "varied", "preset", NULL};
const char *const scene_camera_names[] = {"static", "orbit", "flythrough", NULL};

/* What each preset chooses for itself. grid's values are the thesis's
 * (10 lights of radius 5 in a Halton spread, every object Phong with the
 * same constants); lights' give about five lights over each point of the
 * ground at 256 lights (see scene_describe's lights_per_object). */
static const struct {
    int lights;
    enum scene_light_layout layout;
    double light_radius;
    enum scene_materials materials;
} PRESETS[] = {
    [SCENE_PRESET_GRID] = {10, SCENE_LAYOUT_HALTON, 5.0, SCENE_MATERIALS_UNIFORM},
    [SCENE_PRESET_LIGHTS] = {256, SCENE_LAYOUT_UNIFORM, 4.0, SCENE_MATERIALS_VARIED},
    /* Seed 002's 80 lights through the air around the teapots, each
     * reaching two or three of them. */
    [SCENE_PRESET_TEAPOTS] = {80, SCENE_LAYOUT_UNIFORM, 2.5, SCENE_MATERIALS_PRESET},
    /* A row of lights in front of the chart, above the camera. */
    [SCENE_PRESET_CHART] = {4, SCENE_LAYOUT_GRID, 30.0, SCENE_MATERIALS_PRESET},
    [SCENE_PRESET_SPHERE] = {1, SCENE_LAYOUT_GRID, 10.0, SCENE_MATERIALS_UNIFORM},
    /* Lights low over the plane, so that its shading varies across it. */
    [SCENE_PRESET_PLANE] = {6, SCENE_LAYOUT_HALTON, 2.5, SCENE_MATERIALS_UNIFORM},
    /* Eight generated point lights around the asset, beside its spot and
     * directional ones (their range scaled to it: scene_asset.c). */
    [SCENE_PRESET_TEXTURED] = {8, SCENE_LAYOUT_UNIFORM, SCENE_LIGHT_RADIUS_AUTO,
                               SCENE_MATERIALS_PRESET},
};

bool scene_spec_is_asset(const struct scene_spec *s)
{
    return s->asset[0] || s->preset == SCENE_PRESET_TEXTURED;
}

void scene_spec_preset_defaults(struct scene_spec *s, enum scene_preset preset)
{
    s->preset = preset;
    s->lights = PRESETS[preset].lights;
    s->light_layout = PRESETS[preset].layout;
    s->light_radius = PRESETS[preset].light_radius;
    s->materials = PRESETS[preset].materials;
}

void scene_spec_defaults(struct scene_spec *s)
{
    memset(s, 0, sizeof(*s));
    scene_spec_preset_defaults(s, SCENE_PRESET_GRID);
    s->dynamic = false;
    s->width = 1080;
    s->height = 720;
    s->sphere_segments = 32;
    s->tessellation_error_px = 0.5;
    s->teapot_segments = 12;
    s->light_speed = 1.0;
    s->light_intensity = 1.0;
    s->light_type = SCENE_LIGHT_POINT;
    s->spot_angle_deg = 30.0;
    s->sun = false;
    /* The constants of the thesis's Phong (shaders/common/lighting.glsl);
     * roughness 0.25 is about the Beckmann roughness of Phong exponent 32,
     * sqrt(2 / (32 + 2)), for the lighting models to come. */
    s->specular = 0.5;
    s->shininess = 32.0;
    s->metallic = 0.0;
    s->roughness = 0.25;
    s->camera = SCENE_CAMERA_STATIC;
    s->camera_period = 360;
    s->asset_lights = true;
    s->normal_maps = true;
    s->mover = false;
    s->mover_period = 120;
}

/* "mover": true, false, or {"period": frames}. */
static bool parse_mover(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    static const char *const keys[] = {"period", NULL};
    json_t *v = json_object_get(scene, "mover");
    if (!v)
        return true;
    if (json_is_boolean(v)) {
        s->mover = json_is_true(v);
    } else if (json_is_object(v)) {
        if (!jf_check_keys(v, "scene.mover.", keys, err) ||
            !jf_get_int(v, "period", "scene.mover.period", 2, SCENE_MAX_MOVER_PERIOD,
                        &s->mover_period, err))
            return false;
        s->mover = true;
    } else {
        return job_error_set(err, "scene.mover",
                             "must be true, false or {\"period\": frames} (2 to %d)",
                             SCENE_MAX_MOVER_PERIOD);
    }
    if (s->mover && scene_spec_is_asset(s))
        return job_error_set(err, "scene.mover", "needs a procedural preset (not scene.asset "
                             "or the textured preset)");
    return true;
}

/* "lights": a count, or "auto" (asset scenes: 0 when the asset has lights,
 * else SCENE_ASSET_DEFAULT_LIGHTS). An asset scene without the key is
 * "auto". */
static bool parse_lights(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    json_t *v = json_object_get(scene, "lights");
    if (!v) {
        if (json_object_get(scene, "asset"))
            s->lights = SCENE_LIGHTS_AUTO;
        return true;
    }
    if (json_is_string(v)) {
        if (strcmp(json_string_value(v), "auto") != 0 || !scene_spec_is_asset(s))
            return job_error_set(err, "scene.lights",
                                 "must be an integer from 0 to %d (\"auto\" only with "
                                 "scene.asset or the textured preset)",
                                 SCENE_MAX_LIGHTS);
        s->lights = SCENE_LIGHTS_AUTO;
        return true;
    }
    return jf_get_int(scene, "lights", "scene.lights", 0, SCENE_MAX_LIGHTS, &s->lights, err);
}

/* "asset_camera": an index into the asset's cameras or a camera's name. */
static bool parse_asset_camera(const json_t *scene, struct scene_spec *s,
                               struct job_error *err)
{
    json_t *v = json_object_get(scene, "asset_camera");
    if (!v)
        return true;
    if (!scene_spec_is_asset(s))
        return job_error_set(err, "scene.asset_camera", "needs scene.asset or the textured preset");
    if (json_is_integer(v) && json_integer_value(v) >= 0 && json_integer_value(v) < 1024) {
        snprintf(s->asset_camera, sizeof(s->asset_camera), "%d", (int)json_integer_value(v));
        return true;
    }
    const char *name = json_is_string(v) ? json_string_value(v) : NULL;
    if (!name || !name[0] || strlen(name) > SCENE_ASSET_CAMERA_MAX)
        return job_error_set(err, "scene.asset_camera",
                             "must be a camera's index (0 to 1023) or its name (1 to %d bytes)",
                             SCENE_ASSET_CAMERA_MAX);
    snprintf(s->asset_camera, sizeof(s->asset_camera), "%s", name);
    return true;
}

static bool parse_segments(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    static const char rule[] = "must be \"auto\" or an even integer from 8 to 256";
    json_t *v = json_object_get(scene, "sphere_segments");
    if (!v)
        return true;
    if (json_is_string(v)) {
        if (strcmp(json_string_value(v), "auto") != 0)
            return job_error_set(err, "scene.sphere_segments", rule);
        s->sphere_segments = SCENE_SEGMENTS_AUTO;
        return true;
    }
    int segments = s->sphere_segments;
    if (!jf_get_int(scene, "sphere_segments", "scene.sphere_segments", 8, 256, &segments, err))
        return job_error_set(err, "scene.sphere_segments", rule);
    if (segments % 2)
        return job_error_set(err, "scene.sphere_segments", rule);
    s->sphere_segments = segments;
    return true;
}

static bool parse_teapot_segments(const json_t *scene, struct scene_spec *s,
                                  struct job_error *err)
{
    static const char rule[] = "must be \"auto\" or an integer from 1 to 64 (segments per "
                               "Bezier patch edge)";
    json_t *v = json_object_get(scene, "teapot_segments");
    if (!v)
        return true;
    if (json_is_string(v)) {
        if (strcmp(json_string_value(v), "auto") != 0)
            return job_error_set(err, "scene.teapot_segments", rule);
        s->teapot_segments = SCENE_TEAPOT_SEGMENTS_AUTO;
        return true;
    }
    if (!jf_get_int(scene, "teapot_segments", "scene.teapot_segments", 1, 64,
                    &s->teapot_segments, err))
        return job_error_set(err, "scene.teapot_segments", rule);
    return true;
}

/* "camera": "orbit", {"path": "orbit", "period": 240}, or a pose
 * {"eye", "target", "up", "yfov_deg" | "orthographic", "near", "far"}
 * (scene_camera_spec.c), with or without path and period. */
static bool parse_camera(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    static const char *const keys[] = {"path", "period", "eye", "target", "up", "yfov_deg",
                                       "orthographic", "near", "far", NULL};
    static const char *const pose_keys[] = {"eye", "target", "up", "yfov_deg",
                                            "orthographic", "near", "far", NULL};
    json_t *v = json_object_get(scene, "camera");
    int path = (int)s->camera;
    if (!v)
        return true;
    if (json_is_object(v)) {
        if (!jf_check_keys(v, "scene.camera.", keys, err) ||
            !jf_get_choice(v, "path", "scene.camera.path", scene_camera_names, &path, err) ||
            !jf_get_int(v, "period", "scene.camera.period", 1, SCENE_MAX_CAMERA_PERIOD,
                        &s->camera_period, err))
            return false;
        s->camera = (enum scene_camera_path)path;
        bool pose = false;
        for (int i = 0; pose_keys[i]; i++)
            pose = pose || json_object_get(v, pose_keys[i]);
        memset(&s->view, 0, sizeof(s->view));
        return !pose || scene_camera_pose_parse(v, s, err);
    } else if (json_is_string(v)) {
        if (!jf_get_choice(scene, "camera", "scene.camera", scene_camera_names, &path, err))
            return false;
    } else {
        char list[128];
        jf_list_choices(scene_camera_names, list, sizeof(list));
        return job_error_set(err, "scene.camera",
                             "must be one of %s, {\"path\": ..., \"period\": frames}, or a pose "
                             "{\"eye\", \"target\", ...}", list);
    }
    s->camera = (enum scene_camera_path)path;
    memset(&s->view, 0, sizeof(s->view));
    return true;
}

/* "light_radius": a distance, or "auto" (asset scenes: scaled to the
 * asset's size). An asset scene without the key is "auto". */
static bool parse_light_radius(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    json_t *v = json_object_get(scene, "light_radius");
    if (!v) {
        if (json_object_get(scene, "asset"))
            s->light_radius = SCENE_LIGHT_RADIUS_AUTO;
        return true;
    }
    if (json_is_string(v)) {
        if (strcmp(json_string_value(v), "auto") != 0 || !scene_spec_is_asset(s))
            return job_error_set(err, "scene.light_radius",
                                 "must be a number from 0.01 to 1000 (\"auto\" only with "
                                 "scene.asset or the textured preset)");
        s->light_radius = SCENE_LIGHT_RADIUS_AUTO;
        return true;
    }
    return jf_get_number(scene, "light_radius", "scene.light_radius", 0.01, 1000.0,
                         &s->light_radius, err);
}

bool scene_asset_name_valid(const char *name)
{
    size_t n = strlen(name);
    if (n == 0 || n > SCENE_ASSET_NAME_MAX || name[0] == '.')
        return false;
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == '-'))
            return false;
    }
    return true;
}

static bool parse_asset(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    json_t *v = json_object_get(scene, "asset");
    if (!v) {
        if (json_object_get(scene, "asset_sha256"))
            return job_error_set(err, "scene.asset_sha256", "needs scene.asset");
        return true;
    }
    if (!json_is_string(v) || !scene_asset_name_valid(json_string_value(v)))
        return job_error_set(err, "scene.asset",
                             "must be the name of a stored asset (GET /v1/assets): 1 to %d "
                             "letters, digits, '.', '_' or '-', not starting with '.'",
                             SCENE_ASSET_NAME_MAX);
    snprintf(s->asset, sizeof(s->asset), "%s", json_string_value(v));
    s->asset_sha256[0] = '\0';
    /* A spec written back carries the hash; a client may pin one too (the
     * job is then refused when the stored asset of that name differs). */
    json_t *h = json_object_get(scene, "asset_sha256");
    if (!h)
        return true;
    const char *hex = json_is_string(h) ? json_string_value(h) : "";
    bool ok = strlen(hex) == 64;
    for (int i = 0; ok && i < 64; i++)
        ok = (hex[i] >= '0' && hex[i] <= '9') || (hex[i] >= 'a' && hex[i] <= 'f');
    if (!ok)
        return job_error_set(err, "scene.asset_sha256",
                             "must be 64 lowercase hexadecimal digits (the asset's SHA-256)");
    memcpy(s->asset_sha256, hex, 65);
    return true;
}

/* "light_type": the generated lights are points or spots; a directional
 * light is the sun's option (one light, not hundreds of suns). */
static bool parse_light_type(const json_t *scene, int *type, struct job_error *err)
{
    static const char *const generated[] = {"point", "spot", NULL};
    if (!jf_get_choice(scene, "light_type", "scene.light_type", generated, type, err))
        return false;
    /* The enum's order is the names' (scene_light_type_names). */
    return true;
}

bool scene_spec_parse(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    static const char *const keys[] = {
        "preset", "lights", "dynamic", "width", "height", "sphere_segments",
        "teapot_segments", "tessellation_error_px", "light_speed", "light_radius", "light_intensity",
        "light_layout", "light_type", "spot_angle_deg", "sun", "materials", "specular",
        "shininess", "metallic", "roughness", "camera", "asset", "asset_sha256", "asset_camera",
        "asset_lights", "normal_maps", "light_rig", "mover", NULL};
    if (!jf_check_keys(scene, "scene.", keys, err))
        return false;
    int preset = (int)s->preset, layout, materials, light_type = s->light_type;
    if (!jf_get_choice(scene, "preset", "scene.preset", scene_preset_names, &preset, err))
        return false;
    if (json_object_get(scene, "preset"))
        scene_spec_preset_defaults(s, (enum scene_preset)preset);
    layout = (int)s->light_layout;
    materials = (int)s->materials;
    /* The asset first: whether "lights": "auto" and the asset keys are
     * allowed depends on it. */
    if (!parse_asset(scene, s, err) || !parse_lights(scene, s, err) ||
        !jf_get_bool(scene, "dynamic", "scene.dynamic", &s->dynamic, err) ||
        !jf_get_int(scene, "width", "scene.width", 16, 8192, &s->width, err) ||
        !jf_get_int(scene, "height", "scene.height", 16, 8192, &s->height, err) ||
        !parse_segments(scene, s, err) || !parse_teapot_segments(scene, s, err) ||
        !jf_get_number(scene, "tessellation_error_px", "scene.tessellation_error_px", 0.01,
                       100.0, &s->tessellation_error_px, err) ||
        !jf_get_number(scene, "light_speed", "scene.light_speed", 0.0, 100.0, &s->light_speed,
                       err) ||
        !parse_light_radius(scene, s, err) ||
        !jf_get_number(scene, "light_intensity", "scene.light_intensity", 0.0, 1000.0,
                       &s->light_intensity, err) ||
        !jf_get_choice(scene, "light_layout", "scene.light_layout", scene_layout_names, &layout,
                       err) ||
        !parse_light_type(scene, &light_type, err) ||
        !jf_get_number(scene, "spot_angle_deg", "scene.spot_angle_deg", 0.5, 89.0,
                       &s->spot_angle_deg, err) ||
        !jf_get_bool(scene, "sun", "scene.sun", &s->sun, err) ||
        !jf_get_choice(scene, "materials", "scene.materials", scene_materials_names,
                       &materials, err) ||
        !jf_get_number(scene, "specular", "scene.specular", 0.0, 16.0, &s->specular, err) ||
        !jf_get_number(scene, "shininess", "scene.shininess", 1.0, 4096.0, &s->shininess, err) ||
        !jf_get_number(scene, "metallic", "scene.metallic", 0.0, 1.0, &s->metallic, err) ||
        !jf_get_number(scene, "roughness", "scene.roughness", 0.0, 1.0, &s->roughness, err) ||
        !parse_camera(scene, s, err) || !parse_asset_camera(scene, s, err) ||
        !parse_mover(scene, s, err))
        return false;
    if ((json_object_get(scene, "asset_lights") || json_object_get(scene, "normal_maps")) &&
        !scene_spec_is_asset(s))
        return job_error_set(err, json_object_get(scene, "asset_lights") ? "scene.asset_lights"
                                                                         : "scene.normal_maps",
                             "needs scene.asset or the textured preset");
    /* A light rig states the lights: the generated ones and an asset's own
     * are off unless asked for. */
    json_t *rig = json_object_get(scene, "light_rig");
    if (rig) {
        if (!scene_light_rig_parse(rig, s, err))
            return false;
        if (!json_object_get(scene, "lights"))
            s->lights = 0;
        if (!json_object_get(scene, "asset_lights"))
            s->asset_lights = false;
    }
    if (!jf_get_bool(scene, "asset_lights", "scene.asset_lights", &s->asset_lights, err) ||
        !jf_get_bool(scene, "normal_maps", "scene.normal_maps", &s->normal_maps, err))
        return false;
    s->light_layout = (enum scene_light_layout)layout;
    s->light_type = light_type;
    s->materials = (enum scene_materials)materials;
    return true;
}

json_t *scene_spec_to_json(const struct scene_spec *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "preset", json_string(scene_preset_names[s->preset]));
    json_object_set_new(o, "lights", s->lights == SCENE_LIGHTS_AUTO ? json_string("auto")
                                                                    : json_integer(s->lights));
    json_object_set_new(o, "dynamic", json_boolean(s->dynamic));
    json_object_set_new(o, "width", json_integer(s->width));
    json_object_set_new(o, "height", json_integer(s->height));
    json_object_set_new(o, "sphere_segments", s->sphere_segments == SCENE_SEGMENTS_AUTO
                                                  ? json_string("auto")
                                                  : json_integer(s->sphere_segments));
    json_object_set_new(o, "teapot_segments", s->teapot_segments == SCENE_TEAPOT_SEGMENTS_AUTO
                                                  ? json_string("auto")
                                                  : json_integer(s->teapot_segments));
    json_object_set_new(o, "tessellation_error_px", json_real(s->tessellation_error_px));
    json_object_set_new(o, "light_speed", json_real(s->light_speed));
    json_object_set_new(o, "light_radius", s->light_radius == SCENE_LIGHT_RADIUS_AUTO
                                               ? json_string("auto")
                                               : json_real(s->light_radius));
    json_object_set_new(o, "light_intensity", json_real(s->light_intensity));
    json_object_set_new(o, "light_layout", json_string(scene_layout_names[s->light_layout]));
    json_object_set_new(o, "light_type", json_string(scene_light_type_names[s->light_type]));
    json_object_set_new(o, "spot_angle_deg", json_real(s->spot_angle_deg));
    json_object_set_new(o, "sun", json_boolean(s->sun));
    json_object_set_new(o, "materials", json_string(scene_materials_names[s->materials]));
    json_object_set_new(o, "specular", json_real(s->specular));
    json_object_set_new(o, "shininess", json_real(s->shininess));
    json_object_set_new(o, "metallic", json_real(s->metallic));
    json_object_set_new(o, "roughness", json_real(s->roughness));
    json_t *camera = s->view.given ? scene_camera_pose_to_json(&s->view) : json_object();
    json_object_set_new(camera, "path", json_string(scene_camera_names[s->camera]));
    json_object_set_new(camera, "period", json_integer(s->camera_period));
    json_object_set_new(o, "camera", camera);
    if (s->rig_count) /* only when given: the presets' specs stay as they were */
        json_object_set_new(o, "light_rig", scene_light_rig_to_json(s));
    if (s->asset[0]) {
        json_object_set_new(o, "asset", json_string(s->asset));
        if (s->asset_sha256[0])
            json_object_set_new(o, "asset_sha256", json_string(s->asset_sha256));
    }
    if (s->mover) /* written only when on: the other specs are unchanged */
        json_object_set_new(o, "mover", json_pack("{s:i}", "period", s->mover_period));
    if (scene_spec_is_asset(s)) {
        /* Written only for asset scenes, so the presets' specs (and the
         * stored records compared against them) are unchanged. */
        if (s->asset_camera[0])
            json_object_set_new(o, "asset_camera", json_string(s->asset_camera));
        json_object_set_new(o, "asset_lights", json_boolean(s->asset_lights));
        json_object_set_new(o, "normal_maps", json_boolean(s->normal_maps));
    }
    return o;
}
