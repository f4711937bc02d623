#include "daemon/techniques/osl/osl_schedule.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/light_shape.h"

int osl_period(double distance, double async_distance)
{
    if (async_distance <= 0.0)
        return 1;
    double p = floor(distance / async_distance) + 1.0;
    return p > 1e6 ? 1000000 : (int)p;
}

bool osl_schedule_init(struct osl_schedule *s, const double *distances, int count,
                       double async_distance)
{
    memset(s, 0, sizeof(*s));
    s->period = calloc((size_t)count, sizeof(int));
    s->offset = calloc((size_t)count, sizeof(int));
    if (!s->period || !s->offset) {
        osl_schedule_finish(s);
        return false;
    }
    s->count = count;
    s->max_period = 1;
    for (int i = 0; i < count; i++) {
        s->period[i] = osl_period(distances[i], async_distance);
        if (s->period[i] > s->max_period)
            s->max_period = s->period[i];
    }
    /* Round-robin offsets within each period group: a group of n objects with
     * period p reshades about n/p of them each frame. */
    for (int i = 0; i < count; i++) {
        int seen = 0;
        for (int j = 0; j < i; j++)
            seen += s->period[j] == s->period[i];
        s->offset[i] = seen % s->period[i];
    }
    return true;
}

void osl_schedule_finish(struct osl_schedule *s)
{
    if (!s)
        return;
    free(s->period);
    free(s->offset);
    memset(s, 0, sizeof(*s));
}

int64_t osl_schedule_last(const struct osl_schedule *s, int i, int64_t frame)
{
    int64_t p = s->period[i];
    int64_t m = (frame + s->offset[i]) % p;
    if (m < 0)
        m += p;
    return frame - m;
}

bool osl_schedule_due(const struct osl_schedule *s, int i, int64_t frame)
{
    return osl_schedule_last(s, i, frame) == frame;
}

bool osl_touched(const struct scene *scene, int i, int64_t frame)
{
    if (!scene->spec.dynamic || scene->spec.light_speed <= 0)
        return false;
    const float *c = scene->instances[i].pos;
    float bound = scene_instance_bound(scene, i);
    for (int l = 0; l < scene->light_count; l++) {
        /* A directional light never moves, so it never changes what it
         * lights: it forces no reshade. A spot light reaches by its cone. */
        if (scene->lights[l].type == SCENE_LIGHT_DIRECTIONAL)
            continue;
        float p[3];
        scene_light_position(scene, l, frame, p);
        if (scene_light_reaches(&scene->lights[l], p, c, bound))
            return true;
    }
    return false;
}

int osl_schedule_plan(const struct osl_schedule *s, const struct scene *scene,
                      int64_t frame, bool initial, enum osl_reshade mode,
                      struct osl_work *out)
{
    int n = 0;
    for (int i = 0; i < s->count; i++) {
        if (initial) {
            out[n].instance = i;
            out[n++].time = osl_schedule_last(s, i, frame);
            continue;
        }
        if (!scene->spec.dynamic || scene->spec.light_speed <= 0 || !osl_schedule_due(s, i, frame))
            continue;
        if (mode == OSL_RESHADE_TOUCHED && !osl_touched(scene, i, frame) &&
            !osl_touched(scene, i, frame - s->period[i]))
            continue;
        out[n].instance = i;
        out[n++].time = frame;
    }
    return n;
}

double osl_change_bound(const struct scene *scene, int i, int64_t from, int64_t to,
                        bool lipschitz)
{
    if (from == to || !scene->spec.dynamic || scene->spec.light_speed <= 0)
        return 0.0;
    const struct scene_instance *in = &scene->instances[i];
    const float *c = in->pos;
    double b = scene_instance_bound(scene, i);
    double A = fmax(in->albedo[0], fmax(in->albedo[1], in->albedo[2]));
    double S = in->material.specular, n = in->material.shininess;
    double sum = 0.0;
    for (int l = 0; l < scene->light_count; l++) {
        const struct scene_light *L = &scene->lights[l];
        float p0[3], p1[3];
        scene_light_position(scene, l, from, p0);
        scene_light_position(scene, l, to, p1);
        double seg[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double delta = sqrt(seg[0] * seg[0] + seg[1] * seg[1] + seg[2] * seg[2]);
        if (delta == 0.0)
            continue;
        if (L->type != SCENE_LIGHT_POINT)
            return INFINITY;
        /* The closest point of the segment to the object's centre. */
        double t = ((c[0] - p0[0]) * seg[0] + (c[1] - p0[1]) * seg[1] + (c[2] - p0[2]) * seg[2]) /
                   (delta * delta);
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double q[3] = {p0[0] + t * seg[0] - c[0], p0[1] + t * seg[1] - c[1],
                       p0[2] + t * seg[2] - c[2]};
        double dmin = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - b;
        double r = L->radius;
        if (dmin < 0)
            dmin = 0;
        if (dmin >= r)
            continue;
        double C = fmax(L->color[0], fmax(L->color[1], L->color[2]));
        double a = 1.0 - dmin * dmin / (r * r);
        double bound = C * a * (A + S);
        /* The last term: Phong's specular can be above 0 where N.L reaches 0
         * and the contribution drops to 0, a step no motion bound covers. */
        if (lipschitz && dmin > 0 && n >= 1.0) {
            double smooth = C * (A + S) * 2.0 * delta / r + C * a * (A + n * S) * delta / dmin +
                            C * a * S;
            if (smooth < bound)
                bound = smooth;
        }
        sum += bound;
    }
    return sum;
}
