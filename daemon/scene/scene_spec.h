#ifndef SHADEBENCH_SCENE_SPEC_H
#define SHADEBENCH_SCENE_SPEC_H

/* The job's "scene" object: presets and their options, defaults, parsing
 * with field-naming errors, and the JSON written back. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"

struct scene_spec {
    char preset[16];
    int lights;
    bool dynamic;
    int width, height;
    int sphere_segments; /* longitudinal segments; rings = segments / 2 */
    double light_speed;  /* scales how fast dynamic lights circle (1 = default) */
};

void scene_spec_defaults(struct scene_spec *s);

/* Applies the "scene" object over the current values (defaults first). */
bool scene_spec_parse(const json_t *scene, struct scene_spec *s, struct job_error *err);

/* The scene as understood, defaults filled in. New reference. */
json_t *scene_spec_to_json(const struct scene_spec *s);

#endif
