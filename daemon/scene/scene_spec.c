#define _POSIX_C_SOURCE 200809L
#include "daemon/scene/scene_spec.h"

#include <stdio.h>
#include <string.h>

void scene_spec_defaults(struct scene_spec *s)
{
    memset(s, 0, sizeof(*s));
    snprintf(s->preset, sizeof(s->preset), "grid");
    s->lights = 10;
    s->dynamic = false;
    s->width = 1080;
    s->height = 720;
    s->sphere_segments = 32;
    s->light_speed = 1.0;
}

bool scene_spec_parse(const json_t *scene, struct scene_spec *s, struct job_error *err)
{
    static const char *const keys[] = {"preset", "lights", "dynamic", "width",
                                       "height", "sphere_segments", "light_speed", NULL};
    if (!jf_check_keys(scene, "scene.", keys, err))
        return false;
    json_t *preset = json_object_get(scene, "preset");
    if (preset) {
        if (!json_is_string(preset) || strcmp(json_string_value(preset), "grid") != 0)
            return job_error_set(err, "scene.preset", "must be one of: \"grid\"");
        snprintf(s->preset, sizeof(s->preset), "%s", json_string_value(preset));
    }
    if (!jf_get_int(scene, "lights", "scene.lights", 0, 1024, &s->lights, err) ||
        !jf_get_bool(scene, "dynamic", "scene.dynamic", &s->dynamic, err) ||
        !jf_get_int(scene, "width", "scene.width", 16, 8192, &s->width, err) ||
        !jf_get_int(scene, "height", "scene.height", 16, 8192, &s->height, err) ||
        !jf_get_int(scene, "sphere_segments", "scene.sphere_segments", 8, 256,
                 &s->sphere_segments, err) ||
        !jf_get_number(scene, "light_speed", "scene.light_speed", 0.0, 100.0, &s->light_speed, err))
        return false;
    if (s->sphere_segments % 2)
        return job_error_set(err, "scene.sphere_segments", "must be an even integer from 8 to 256");
    return true;
}

json_t *scene_spec_to_json(const struct scene_spec *s)
{
    return json_pack("{s:s, s:i, s:b, s:i, s:i, s:i, s:f}", "preset", s->preset, "lights",
                     s->lights, "dynamic", s->dynamic, "width", s->width, "height", s->height,
                     "sphere_segments", s->sphere_segments, "light_speed", s->light_speed);
}
