/* Per-instance materials. "uniform" gives every object the spec's values
 * (the grid's default: the thesis's constants, so its pixels stay the
 * same); "varied" spreads them per object with a fixed hash, so that a
 * lighting model's cost and look are measured over more than one material. */
#include <math.h>

#include "daemon/scene/scene_build.h"

void scene_assign_materials(struct scene *s)
{
    const struct scene_spec *spec = &s->spec;
    for (int i = 0; i < s->instance_count; i++) {
        struct scene_material *m = &s->instances[i].material;
        m->specular = (float)spec->specular;
        m->shininess = (float)spec->shininess;
        m->metallic = (float)spec->metallic;
        m->roughness = (float)spec->roughness;
        if (spec->materials != SCENE_MATERIALS_VARIED)
            continue;
        uint32_t id = (uint32_t)i;
        /* Specular 0.25 to 1.75 times the spec's, shininess a quarter to four
         * times it in octaves, one object in four metallic, and roughness
         * following shininess as Beckmann's does Phong's (sqrt(2 / (n + 2))). */
        double shininess = spec->shininess * exp2(floor(scene_hash01(id, 62) * 5.0) - 2.0);
        m->specular = (float)(spec->specular * (0.25 + 1.5 * scene_hash01(id, 61)));
        m->shininess = (float)fmax(1.0, shininess);
        m->metallic = scene_hash01(id, 63) < 0.25 ? 1.0f : (float)spec->metallic;
        m->roughness = (float)fmin(1.0, spec->roughness * sqrt((spec->shininess + 2.0) /
                                                               (shininess + 2.0)));
    }
}
