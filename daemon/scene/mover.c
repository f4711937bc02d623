/* scene.mover: one sphere sliding to and fro across the objects at a
 * constant speed, a little above them, so that object motion (motion
 * vectors, TAA's ghosting behind a moving object) can be measured on any
 * procedural preset. Its position is a pure function of the frame. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/scene.h"
#include "daemon/scene/scene_build.h"

bool scene_add_mover(struct scene *s)
{
    s->mover = -1;
    if (!s->spec.mover)
        return true;
    struct scene_instance *grown =
        realloc(s->instances, (size_t)(s->instance_count + 1) * sizeof(*grown));
    if (!grown)
        return false;
    s->instances = grown;
    /* After the last sphere: instances stay grouped by mesh. */
    int at = s->mesh_instance_count[SCENE_MESH_SPHERE];
    memmove(&s->instances[at + 1], &s->instances[at],
            (size_t)(s->instance_count - at) * sizeof(*s->instances));
    s->instance_count++;
    s->mesh_instance_count[SCENE_MESH_SPHERE]++;
    s->mover = at;
    /* Across the objects' width, at their middle in depth, its lowest point
     * a little above their tops: a fifth of the width across. */
    const struct scene_box *b = &s->objects;
    float width = b->max[0] - b->min[0], depth = b->max[2] - b->min[2];
    float radius = 0.1f * fmaxf(width, depth);
    if (!(radius > 0.0f))
        radius = 1.0f;
    float y = b->max[1] + 1.2f * radius, z = 0.5f * (b->min[2] + b->max[2]);
    s->mover_from[0] = b->min[0] + radius, s->mover_to[0] = b->max[0] - radius;
    if (s->mover_to[0] < s->mover_from[0])
        s->mover_to[0] = s->mover_from[0] + 2.0f * radius;
    s->mover_from[1] = s->mover_to[1] = y;
    s->mover_from[2] = s->mover_to[2] = z;
    struct scene_instance *in = &s->instances[at];
    *in = (struct scene_instance){
        .scale = radius / SCENE_SPHERE_RADIUS,
        .albedo = {0.95f, 0.55f, 0.15f},
        .mesh = SCENE_MESH_SPHERE,
        .material = {(float)s->spec.specular, (float)s->spec.shininess, (float)s->spec.metallic,
                     (float)s->spec.roughness},
        .asset_material = -1,
    };
    memcpy(in->pos, s->mover_from, sizeof(in->pos));
    return true;
}

void scene_instance_at(const struct scene *s, int i, int64_t frame, float out[4])
{
    const struct scene_instance *in = &s->instances[i];
    out[3] = in->scale;
    if (i != s->mover) {
        memcpy(out, in->pos, 3 * sizeof(float));
        return;
    }
    /* A triangle wave: from one end to the other in half a period, back in
     * the other half. */
    int64_t period = s->spec.mover_period > 1 ? s->spec.mover_period : 2;
    int64_t step = frame % period;
    if (step < 0)
        step += period;
    double t = 2.0 * (double)step / (double)period;
    if (t > 1.0)
        t = 2.0 - t;
    for (int k = 0; k < 3; k++)
        out[k] = (float)(s->mover_from[k] + t * ((double)s->mover_to[k] - s->mover_from[k]));
}

bool scene_mover_disc(const struct scene *s, int64_t frame, const struct scene_camera *c,
                      int width, int height, float out[3])
{
    if (s->mover < 0)
        return false;
    float at[4], clip[4];
    scene_instance_at(s, s->mover, frame, at);
    scene_mat4_transform(c->view_proj, at, 1.0f, clip);
    if (!(clip[3] > 0.0f))
        return false;
    out[0] = (clip[0] / clip[3] * 0.5f + 0.5f) * (float)width;
    out[1] = (clip[1] / clip[3] * 0.5f + 0.5f) * (float)height;
    out[2] = scene_sphere_radius_px(c, width, height, at, SCENE_SPHERE_RADIUS * at[3]);
    return true;
}
