#define _POSIX_C_SOURCE 200809L
#include "daemon/lighting/shadow_plan.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lighting/cube_faces.h"
#include "daemon/scene/light_shape.h"

int shadow_cube_layers(const struct shadow_spec *spec, int lights)
{
    double texels = (double)spec->atlas * spec->atlas;
    int fit = (int)(texels / (6.0 * spec->tile * spec->tile));
    return fit < lights ? fit : lights;
}

int shadow_border(int pcf) { return pcf + 1; }

/* Whether a spot light's cone (unit axis, outer half-angle) may reach cube
 * face f's frustum (widened by w): false only when the whole cone lies
 * behind one of the frustum's planes through the light (the face's own, or
 * a side's: inside is f w -+ s >= 0 and f w -+ t >= 0, as in
 * sphere_meets_face), that is when the axis makes more than 90 degrees plus
 * the half-angle with the plane's inward normal; a margin covers the
 * receivers' normal offset. A face the cone cannot reach is never looked
 * up: every point the spot lights lies in a face it reaches, and a point
 * it does not light returns before the lookup. */
bool shadow_cone_meets_face(const float axis[3], float cos_outer, int f, float w)
{
    float fw[3], sa[3], ta[3];
    cube_face_axes(f, fw, sa, ta);
    float sin_outer = sqrtf(fmaxf(0.0f, 1.0f - cos_outer * cos_outer)) + 0.02f;
    float a_f = axis[0] * fw[0] + axis[1] * fw[1] + axis[2] * fw[2];
    float a_s = axis[0] * sa[0] + axis[1] * sa[1] + axis[2] * sa[2];
    float a_t = axis[0] * ta[0] + axis[1] * ta[1] + axis[2] * ta[2];
    float norm = sqrtf(w * w + 1.0f);
    return a_f >= -sin_outer && (a_f * w - a_s) / norm >= -sin_outer &&
           (a_f * w + a_s) / norm >= -sin_outer && (a_f * w - a_t) / norm >= -sin_outer &&
           (a_f * w + a_t) / norm >= -sin_outer;
}

int shadow_sun_size(const struct shadow_spec *spec)
{
    /* Half the atlas's edge: a quarter of its memory a sun. */
    int size = spec->atlas / 2;
    return size < 256 ? 256 : size > 4096 ? 4096 : size;
}

void shadow_sun_fit(const struct scene_box *b, const float dir[3], int size, float view_proj[16],
                    float *texel_world, float *depth_range)
{
    /* A basis with f along the light: r and u span the map. */
    const float *f = dir;
    float up[3] = {0.0f, 1.0f, 0.0f};
    if (fabsf(f[1]) > 0.99f)
        up[1] = 0.0f, up[2] = 1.0f;
    float r[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                  f[0] * up[1] - f[1] * up[0]};
    float rl = sqrtf(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int k = 0; k < 3; k++)
        r[k] /= rl;
    float u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]};
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        float p[3];
        for (int k = 0; k < 3; k++)
            p[k] = c >> k & 1 ? b->max[k] : b->min[k];
        float q[3] = {r[0] * p[0] + r[1] * p[1] + r[2] * p[2],
                      u[0] * p[0] + u[1] * p[1] + u[2] * p[2],
                      f[0] * p[0] + f[1] * p[1] + f[2] * p[2]};
        for (int k = 0; k < 3; k++)
            lo[k] = fminf(lo[k], q[k]), hi[k] = fmaxf(hi[k], q[k]);
    }
    /* A margin of 1% and a unit: nothing on the box's faces at the edge. */
    float scale[3], shift[3];
    for (int k = 0; k < 3; k++) {
        float pad = 0.01f * (hi[k] - lo[k]) + (k == 2 ? 1.0f : 0.05f);
        lo[k] -= pad, hi[k] += pad;
        scale[k] = 2.0f / (hi[k] - lo[k]);
        shift[k] = -(hi[k] + lo[k]) / (hi[k] - lo[k]);
    }
    const float *axis[3] = {r, u, f};
    memset(view_proj, 0, 16 * sizeof(float));
    for (int row = 0; row < 3; row++) {
        for (int col = 0; col < 3; col++)
            view_proj[col * 4 + row] = scale[row] * axis[row][col];
        view_proj[12 + row] = shift[row];
    }
    view_proj[15] = 1.0f;
    *texel_world = fmaxf(hi[0] - lo[0], hi[1] - lo[1]) / (float)size;
    *depth_range = hi[2] - lo[2];
}

float shadow_face_widen(int size, int border)
{
    int inner = size - 2 * border;
    return inner > 0 ? (float)size / (float)inner : 1.0f;
}

bool shadow_plan_init(struct shadow_plan *p, int lights, const struct shadow_spec *spec)
{
    memset(p, 0, sizeof(*p));
    size_t n = (size_t)(lights ? lights : 1);
    p->lights = lights;
    p->light = calloc(n, sizeof(*p->light));
    p->order = calloc(n * 6, sizeof(int));
    p->sizes = calloc(n * 6, sizeof(int));
    p->slots = calloc(n * 6, sizeof(int));
    p->tiles = calloc(n * 6, sizeof(*p->tiles));
    if (!p->light || !p->order || !p->sizes || !p->slots || !p->tiles) {
        shadow_plan_finish(p);
        return false;
    }
    if (spec->layout == SHADOW_LAYOUT_CUBES)
        p->layers = shadow_cube_layers(spec, lights);
    return true;
}

void shadow_plan_finish(struct shadow_plan *p)
{
    if (!p)
        return;
    free(p->light);
    free(p->order);
    free(p->sizes);
    free(p->slots);
    free(p->tiles);
    memset(p, 0, sizeof(*p));
}

static int nearest_pow2(double v)
{
    if (!(v > 1.0))
        return 1;
    double l = round(log2(v));
    return l > 30 ? 1 << 30 : 1 << (int)l;
}

/* Whether a caster (any object but the ground) lies within the light (its
 * sphere, or a spot light's cone). */
static bool has_caster(const struct scene *s, const struct scene_light *light, const float pos[3])
{
    for (int i = 0; i < s->instance_count; i++) {
        const struct scene_instance *in = &s->instances[i];
        if (in->mesh == SCENE_MESH_PLANE)
            continue;
        if (scene_light_reaches(light, pos, in->pos, scene_instance_bound(s, i)))
            return true;
    }
    return false;
}

/* Indices of lights needing maps, most important first (ties by index):
 * an insertion into a sorted run would be quadratic for 16,384 lights, so
 * a heap sort, which needs no scratch. */
static bool before(const struct shadow_plan *p, int a, int b)
{
    float ia = p->light[a].importance, ib = p->light[b].importance;
    return ia > ib || (ia == ib && a < b);
}

static void sift(const struct shadow_plan *p, int *h, int n, int i)
{
    for (;;) {
        int l = 2 * i + 1, r = l + 1, last = i;
        /* A max-heap on "after": the root is the least important. */
        if (l < n && before(p, h[last], h[l]))
            last = l;
        if (r < n && before(p, h[last], h[r]))
            last = r;
        if (last == i)
            return;
        int t = h[i];
        h[i] = h[last];
        h[last] = t;
        i = last;
    }
}

static void sort_by_importance(const struct shadow_plan *p, int *h, int n)
{
    for (int i = n / 2 - 1; i >= 0; i--)
        sift(p, h, n, i);
    for (int end = n - 1; end > 0; end--) {
        int t = h[0];
        h[0] = h[end];
        h[end] = t;
        sift(p, h, end, 0);
    }
}

bool shadow_plan_frame(struct shadow_plan *p, const struct scene *s, const struct shadow_spec *spec,
                       int64_t frame, char *err, size_t errlen)
{
    struct scene_camera cam;
    scene_camera_at(s, frame, &cam);
    p->mapped = p->culled = p->no_casters = p->dropped = p->directional = 0;
    p->texels = 0;
    int need = 0;
    for (int i = 0; i < p->lights; i++) {
        struct shadow_light_plan *l = &p->light[i];
        const struct scene_light *light = &s->lights[i];
        float radius = light->radius, centre[3], bound;
        scene_light_position(s, i, frame, l->pos);
        l->size = 0;
        l->importance = 0;
        if (!scene_light_bound(light, l->pos, centre, &bound)) {
            l->status = SHADOW_DIRECTIONAL;
            p->directional++;
            continue;
        }
        if (!scene_sphere_in_frustum(cam.view_proj, centre, bound, false)) {
            l->status = SHADOW_CULLED;
            p->culled++;
            continue;
        }
        if (!has_caster(s, light, l->pos)) {
            l->status = SHADOW_NO_CASTERS;
            p->no_casters++;
            continue;
        }
        l->status = SHADOW_MAPPED;
        l->importance = scene_sphere_radius_px(&cam, s->spec.width, s->spec.height, l->pos, radius);
        int size = spec->tile ? spec->tile : nearest_pow2(l->importance);
        if (!spec->tile)
            size = size < spec->min_tile ? spec->min_tile : size > spec->max_tile ? spec->max_tile : size;
        l->size = size;
        p->order[need++] = i;
    }
    sort_by_importance(p, p->order, need);

    int kept = need;
    if (spec->layout == SHADOW_LAYOUT_CUBES) {
        kept = need < p->layers ? need : p->layers;
    } else {
        double cap = (double)spec->atlas * spec->atlas, total = 0;
        for (int k = 0; k < need; k++)
            total += 6.0 * p->light[p->order[k]].size * p->light[p->order[k]].size;
        /* Shrink the least important first, each down to min_tile. */
        for (int k = need - 1; k >= 0 && total > cap && !spec->tile; k--) {
            struct shadow_light_plan *l = &p->light[p->order[k]];
            while (l->size > spec->min_tile && total > cap) {
                total -= 6.0 * l->size * l->size * 0.75;
                l->size /= 2;
            }
        }
        /* Then drop, least important first. */
        while (kept > 0 && total > cap) {
            struct shadow_light_plan *l = &p->light[p->order[--kept]];
            total -= 6.0 * l->size * l->size;
        }
    }
    for (int k = kept; k < need; k++) {
        struct shadow_light_plan *l = &p->light[p->order[k]];
        l->status = SHADOW_DROPPED;
        l->size = 0;
        p->dropped++;
    }
    if (p->dropped && spec->overflow == SHADOW_OVERFLOW_FAIL) {
        int used = snprintf(err, errlen, "frame %lld: look.shadows.atlas %d cannot hold the maps "
                            "of %d lights at their smallest size; lights without shadows:",
                            (long long)frame, spec->atlas, need);
        for (int k = kept; k < need && used > 0 && (size_t)used < errlen; k++)
            used += snprintf(err + used, errlen - (size_t)used, "%s %d", k > kept ? "," : "",
                             p->order[k]);
        if (used > 0 && (size_t)used < errlen)
            snprintf(err + used, errlen - (size_t)used, " (raise look.shadows.atlas, lower "
                     "min_tile, or set overflow \"drop_report\")");
        return false;
    }
    p->mapped = kept;
    if (spec->layout == SHADOW_LAYOUT_CUBES) {
        for (int k = 0; k < kept; k++) {
            struct shadow_light_plan *l = &p->light[p->order[k]];
            l->x[0] = k;
            p->texels += 6.0 * l->size * l->size;
        }
        return true;
    }
    /* Six faces a light, in importance order, into one atlas square. */
    for (int k = 0; k < kept; k++)
        for (int f = 0; f < 6; f++)
            p->sizes[k * 6 + f] = p->light[p->order[k]].size;
    atlas_place(p->sizes, kept * 6, spec->atlas, spec->atlas, p->slots, p->tiles);
    for (int k = 0; k < kept; k++) {
        struct shadow_light_plan *l = &p->light[p->order[k]];
        for (int f = 0; f < 6; f++) {
            l->x[f] = p->tiles[k * 6 + f].x;
            l->y[f] = p->tiles[k * 6 + f].y;
        }
        p->texels += 6.0 * l->size * l->size;
    }
    return true;
}
