#include "daemon/scene/light_shape.h"

#include <math.h>

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void light_cone_bound(const float apex[3], const float dir[3], float range, float cos_half,
                      float sin_half, float centre[3], float *radius)
{
    /* cos t >= sin t exactly when t <= 45 degrees. */
    float along, r;
    if (cos_half >= sin_half) {
        r = range / (2.0f * cos_half);
        along = r;
    } else {
        r = range * sin_half;
        along = range * cos_half;
    }
    for (int k = 0; k < 3; k++)
        centre[k] = apex[k] + dir[k] * along;
    *radius = r;
}

bool light_cone_touches_sphere(const float apex[3], const float dir[3], float range,
                               float cos_half, float sin_half, const float c[3], float r)
{
    float v[3] = {c[0] - apex[0], c[1] - apex[1], c[2] - apex[2]};
    float v_len2 = dot3(v, v), v1 = dot3(v, dir);
    float side2 = v_len2 - v1 * v1;
    float side = side2 > 0.0f ? sqrtf(side2) : 0.0f;
    float closest = cos_half * side - v1 * sin_half;
    return !(closest > r || v1 > r + range || v1 < -r);
}

bool scene_light_bound(const struct scene_light *l, const float pos[3], float centre[3],
                       float *radius)
{
    switch (l->type) {
    case SCENE_LIGHT_DIRECTIONAL:
        *radius = INFINITY;
        for (int k = 0; k < 3; k++)
            centre[k] = pos[k];
        return false;
    case SCENE_LIGHT_SPOT:
        light_cone_bound(pos, l->direction, l->radius, l->cos_outer, scene_light_sin_outer(l),
                         centre, radius);
        return true;
    case SCENE_LIGHT_POINT:
    default:
        for (int k = 0; k < 3; k++)
            centre[k] = pos[k];
        *radius = l->radius;
        return true;
    }
}

bool scene_light_reaches(const struct scene_light *l, const float pos[3], const float c[3],
                         float r)
{
    float bc[3], br;
    if (!scene_light_bound(l, pos, bc, &br))
        return true;
    float d[3] = {bc[0] - c[0], bc[1] - c[1], bc[2] - c[2]};
    float reach = br + r;
    if (!(dot3(d, d) < reach * reach))
        return false;
    return l->type != SCENE_LIGHT_SPOT ||
           light_cone_touches_sphere(pos, l->direction, l->radius, l->cos_outer,
                                     scene_light_sin_outer(l), c, r);
}

float scene_light_sin_outer(const struct scene_light *l)
{
    float c = l->cos_outer;
    return c >= 1.0f ? 0.0f : c <= -1.0f ? 0.0f : sqrtf(1.0f - c * c);
}

float scene_light_cone_scale(const struct scene_light *l)
{
    return 1.0f / fmaxf(l->cos_inner - l->cos_outer, 1e-3f);
}

float scene_spot_falloff(const struct scene_light *l, float cd)
{
    float t = (cd - l->cos_outer) * scene_light_cone_scale(l);
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    return t * t;
}
