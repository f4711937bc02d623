/* scene.camera as a pose and scene.light_rig: the two ways a job states
 * its view and its lights as a user would (docs/scenes.md), parsed with
 * field-naming errors and written back. GL-free; any thread. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "daemon/scene/scene.h" /* scene_light_type_names, enum scene_light_type */
#include "daemon/scene/scene_spec.h"

/* Coordinates and sizes a job may give: well inside float range, so that
 * every matrix made of them stays finite. */
#define POSE_LIMIT 1e6

/* A 3-vector of numbers within +-limit at key (absent: *present false). */
static bool get_vec3(const json_t *obj, const char *key, const char *field, double limit,
                     double out[3], bool *present, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    *present = v != NULL;
    if (!v)
        return true;
    if (!json_is_array(v) || json_array_size(v) != 3)
        return job_error_set(err, field, "must be three numbers [x, y, z]");
    for (int k = 0; k < 3; k++) {
        json_t *c = json_array_get(v, (size_t)k);
        double x = json_is_number(c) ? json_number_value(c) : NAN;
        if (!(x >= -limit && x <= limit))
            return job_error_set(err, field, "must be three numbers from %g to %g", -limit,
                                 limit);
        out[k] = x;
    }
    return true;
}

static double length3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static json_t *vec3_json(const double v[3])
{
    return json_pack("[f, f, f]", v[0], v[1], v[2]);
}

bool scene_camera_pose_parse(const json_t *camera, struct scene_spec *s, struct job_error *err)
{
    struct scene_camera_spec *v = &s->view;
    bool has_eye, has_target, has_up;
    memset(v, 0, sizeof(*v));
    v->up[1] = 1.0;
    if (!get_vec3(camera, "eye", "scene.camera.eye", POSE_LIMIT, v->eye, &has_eye, err) ||
        !get_vec3(camera, "target", "scene.camera.target", POSE_LIMIT, v->target, &has_target,
                  err) ||
        !get_vec3(camera, "up", "scene.camera.up", POSE_LIMIT, v->up, &has_up, err))
        return false;
    if (!has_eye || !has_target)
        return job_error_set(err, has_eye ? "scene.camera.target" : "scene.camera.eye",
                             "a camera pose needs both eye and target ([x, y, z] each)");
    double f[3] = {v->target[0] - v->eye[0], v->target[1] - v->eye[1], v->target[2] - v->eye[2]};
    double lf = length3(f), lu = length3(v->up);
    if (!(lf > 1e-6))
        return job_error_set(err, "scene.camera.target", "must differ from eye");
    double c[3] = {f[1] * v->up[2] - f[2] * v->up[1], f[2] * v->up[0] - f[0] * v->up[2],
                   f[0] * v->up[1] - f[1] * v->up[0]};
    if (!(lu > 1e-9) || !(length3(c) > 1e-6 * lf * lu))
        return job_error_set(err, "scene.camera.up",
                             "must not be zero or parallel to the view direction (target - eye)");
    for (int k = 0; k < 3; k++)
        v->up[k] /= lu;
    json_t *ortho = json_object_get(camera, "orthographic");
    if (ortho && json_object_get(camera, "yfov_deg"))
        return job_error_set(err, "scene.camera.orthographic",
                             "a camera is perspective (yfov_deg) or orthographic, not both");
    if (!jf_get_number(camera, "yfov_deg", "scene.camera.yfov_deg", 0.01, 179.0, &v->yfov_deg,
                       err))
        return false;
    if (ortho) {
        static const char *const keys[] = {"xmag", "ymag", NULL};
        if (!json_is_object(ortho))
            return job_error_set(err, "scene.camera.orthographic",
                                 "must be {\"xmag\": half-width, \"ymag\": half-height}");
        if (!jf_check_keys(ortho, "scene.camera.orthographic.", keys, err))
            return false;
        if (!json_object_get(ortho, "ymag"))
            return job_error_set(err, "scene.camera.orthographic.ymag",
                                 "is required: the view's half-height in scene units");
        if (!jf_get_number(ortho, "ymag", "scene.camera.orthographic.ymag", 1e-6, POSE_LIMIT,
                           &v->ymag, err) ||
            !jf_get_number(ortho, "xmag", "scene.camera.orthographic.xmag", 1e-6, POSE_LIMIT,
                           &v->xmag, err))
            return false;
        v->orthographic = true;
        if (s->camera != SCENE_CAMERA_STATIC)
            return job_error_set(err, "scene.camera.orthographic",
                                 "an orthographic camera stands still: path must be \"static\"");
    }
    if (!jf_get_number(camera, "near", "scene.camera.near", 1e-6, POSE_LIMIT, &v->near_z, err) ||
        !jf_get_number(camera, "far", "scene.camera.far", 1e-6, POSE_LIMIT, &v->far_z, err))
        return false;
    bool has_near = json_object_get(camera, "near") != NULL;
    bool has_far = json_object_get(camera, "far") != NULL;
    if (has_near != has_far)
        return job_error_set(err, has_near ? "scene.camera.far" : "scene.camera.near",
                             "near and far are given together (or both left out: derived "
                             "from the scene's bounds)");
    if (has_far && !(v->far_z > v->near_z))
        return job_error_set(err, "scene.camera.far", "must be greater than near");
    /* far_z 0 means derived (both planes). */
    v->given = true;
    return true;
}

json_t *scene_camera_pose_to_json(const struct scene_camera_spec *v)
{
    json_t *o = json_pack("{s:o, s:o, s:o}", "eye", vec3_json(v->eye), "target",
                          vec3_json(v->target), "up", vec3_json(v->up));
    if (!o)
        return NULL;
    if (v->orthographic) {
        json_t *ortho = json_pack("{s:f}", "ymag", v->ymag);
        if (v->xmag > 0)
            json_object_set_new(ortho, "xmag", json_real(v->xmag));
        json_object_set_new(o, "orthographic", ortho);
    } else if (v->yfov_deg > 0) {
        json_object_set_new(o, "yfov_deg", json_real(v->yfov_deg));
    }
    if (v->far_z > 0) {
        json_object_set_new(o, "near", json_real(v->near_z));
        json_object_set_new(o, "far", json_real(v->far_z));
    }
    return o;
}

static bool parse_rig_light(const json_t *l, const char *prefix, struct scene_rig_light *out,
                            struct job_error *err)
{
    static const char *const keys[] = {"type", "position", "direction", "color", "intensity",
                                       "range", "inner_cone_deg", "outer_cone_deg", NULL};
    char field[64];
    memset(out, 0, sizeof(*out));
    if (!json_is_object(l)) {
        snprintf(field, sizeof(field), "%.*s", (int)strlen(prefix) - 1, prefix);
        return job_error_set(err, field, "must be {\"type\": \"point\" | \"spot\" | "
                             "\"directional\", \"position\": ..., \"direction\": ..., ...}");
    }
    if (!jf_check_keys(l, prefix, keys, err))
        return false;
    snprintf(field, sizeof(field), "%stype", prefix);
    if (!json_object_get(l, "type"))
        return job_error_set(err, field, "is required: \"point\", \"spot\" or \"directional\"");
    if (!jf_get_choice(l, "type", field, scene_light_type_names, &out->type, err))
        return false;
    bool has_pos, has_dir, has_color;
    out->color[0] = out->color[1] = out->color[2] = 1.0;
    out->intensity = 1.0;
    out->outer_cone_deg = 45.0; /* glTF's default, pi / 4 */
    snprintf(field, sizeof(field), "%sposition", prefix);
    if (!get_vec3(l, "position", field, POSE_LIMIT, out->position, &has_pos, err))
        return false;
    if (out->type == SCENE_LIGHT_DIRECTIONAL && has_pos)
        return job_error_set(err, field, "a directional light has no position (it shines "
                             "along direction from everywhere)");
    if (out->type != SCENE_LIGHT_DIRECTIONAL && !has_pos)
        return job_error_set(err, field, "is required for a %s light: [x, y, z]",
                             scene_light_type_names[out->type]);
    snprintf(field, sizeof(field), "%sdirection", prefix);
    if (!get_vec3(l, "direction", field, POSE_LIMIT, out->direction, &has_dir, err))
        return false;
    if (out->type == SCENE_LIGHT_POINT && has_dir)
        return job_error_set(err, field, "a point light shines every way: give no direction");
    if (out->type != SCENE_LIGHT_POINT) {
        double len = length3(out->direction);
        if (!has_dir || !(len > 1e-9))
            return job_error_set(err, field, "is required for a %s light: the way it shines, "
                                 "[x, y, z], not zero", scene_light_type_names[out->type]);
        for (int k = 0; k < 3; k++)
            out->direction[k] /= len;
    }
    snprintf(field, sizeof(field), "%scolor", prefix);
    if (!get_vec3(l, "color", field, 1000.0, out->color, &has_color, err))
        return false;
    for (int k = 0; k < 3; k++)
        if (out->color[k] < 0)
            return job_error_set(err, field, "must be three linear values from 0 to 1000");
    snprintf(field, sizeof(field), "%sintensity", prefix);
    if (!jf_get_number(l, "intensity", field, 0.0, 1e9, &out->intensity, err))
        return false;
    snprintf(field, sizeof(field), "%srange", prefix);
    if (json_object_get(l, "range") && out->type == SCENE_LIGHT_DIRECTIONAL)
        return job_error_set(err, field, "a directional light has no range");
    if (!jf_get_number(l, "range", field, 1e-6, POSE_LIMIT, &out->range, err))
        return false;
    bool cones = json_object_get(l, "inner_cone_deg") || json_object_get(l, "outer_cone_deg");
    snprintf(field, sizeof(field), "%s%s", prefix,
             json_object_get(l, "inner_cone_deg") ? "inner_cone_deg" : "outer_cone_deg");
    if (cones && out->type != SCENE_LIGHT_SPOT)
        return job_error_set(err, field, "only a spot light has cone angles");
    snprintf(field, sizeof(field), "%sinner_cone_deg", prefix);
    if (!jf_get_number(l, "inner_cone_deg", field, 0.0, 90.0, &out->inner_cone_deg, err))
        return false;
    snprintf(field, sizeof(field), "%souter_cone_deg", prefix);
    if (!jf_get_number(l, "outer_cone_deg", field, 0.01, 90.0, &out->outer_cone_deg, err))
        return false;
    if (out->type == SCENE_LIGHT_SPOT && !(out->inner_cone_deg < out->outer_cone_deg)) {
        snprintf(field, sizeof(field), "%sinner_cone_deg", prefix);
        return job_error_set(err, field, "must be less than outer_cone_deg (%g)",
                             out->outer_cone_deg);
    }
    return true;
}

bool scene_light_rig_parse(const json_t *rig, struct scene_spec *s, struct job_error *err)
{
    if (!json_is_array(rig) || json_array_size(rig) > SCENE_RIG_MAX_LIGHTS)
        return job_error_set(err, "scene.light_rig",
                             "must be a list of at most %d lights, each {\"type\": ..., "
                             "\"position\" or \"direction\": [x, y, z], \"color\", "
                             "\"intensity\", ...}",
                             SCENE_RIG_MAX_LIGHTS);
    size_t i;
    json_t *l;
    s->rig_count = 0;
    json_array_foreach(rig, i, l) {
        char prefix[48];
        snprintf(prefix, sizeof(prefix), "scene.light_rig[%zu].", i);
        if (!parse_rig_light(l, prefix, &s->rig[i], err))
            return false;
        s->rig_count = (int)i + 1;
    }
    return true;
}

json_t *scene_light_rig_to_json(const struct scene_spec *s)
{
    json_t *out = json_array();
    for (int i = 0; out && i < s->rig_count; i++) {
        const struct scene_rig_light *l = &s->rig[i];
        json_t *o = json_pack("{s:s, s:o, s:f}", "type", scene_light_type_names[l->type],
                              "color", vec3_json(l->color), "intensity", l->intensity);
        if (l->type != SCENE_LIGHT_DIRECTIONAL)
            json_object_set_new(o, "position", vec3_json(l->position));
        if (l->type != SCENE_LIGHT_POINT)
            json_object_set_new(o, "direction", vec3_json(l->direction));
        if (l->range > 0)
            json_object_set_new(o, "range", json_real(l->range));
        if (l->type == SCENE_LIGHT_SPOT) {
            json_object_set_new(o, "inner_cone_deg", json_real(l->inner_cone_deg));
            json_object_set_new(o, "outer_cone_deg", json_real(l->outer_cone_deg));
        }
        json_array_append_new(out, o);
    }
    return out;
}
