/* Light layouts: where the light centres stand in the scene's light volume.
 * Every layout is deterministic (Halton digits or a fixed hash), so a spec
 * builds the same lights on every run and machine. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/scene_build.h"

static const double PI = 3.14159265358979323846;

/* The thesis's spread, written so that the grid preset's volume gives
 * exactly the floats it always had: x = (h2 - 1/2) 40, y = 10 h3 - 0.5,
 * z = 1.5 - 24 h5. */
static void place_halton(const struct scene_box *b, int i, float out[3])
{
    unsigned k = (unsigned)i + 1;
    double size[3] = {(double)b->max[0] - b->min[0], (double)b->max[1] - b->min[1],
                      (double)b->max[2] - b->min[2]};
    double centre_x = 0.5 * ((double)b->min[0] + b->max[0]);
    out[0] = (float)((scene_radical_inverse(k, 2) - 0.5) * size[0] + centre_x);
    out[1] = (float)(scene_radical_inverse(k, 3) * size[1] + b->min[1]);
    out[2] = (float)(b->max[2] - scene_radical_inverse(k, 5) * size[2]);
}

static void place_uniform(const struct scene_box *b, int i, float out[3])
{
    for (int a = 0; a < 3; a++)
        out[a] = (float)(b->min[a] + scene_hash01((uint32_t)i, 11u + (uint32_t)a) *
                                         ((double)b->max[a] - b->min[a]));
}

/* A lattice with about equal spacing along each axis, filled layer by
 * layer from the bottom; the top layer's lights are spread evenly over its
 * cells, so no corner is left dark. */
static void place_grid(const struct scene_box *b, int n, int i, float out[3])
{
    double size[3];
    for (int a = 0; a < 3; a++)
        size[a] = fmax((double)b->max[a] - b->min[a], 1e-3);
    double t = cbrt((double)n / (size[0] * size[1] * size[2]));
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = (int)fmax(1.0, floor(size[a] * t));
    while ((long)dims[0] * dims[1] * dims[2] < n) {
        int widest = 0;
        for (int a = 1; a < 3; a++)
            if (size[a] / dims[a] > size[widest] / dims[widest])
                widest = a;
        dims[widest]++;
    }
    int per_layer = dims[0] * dims[2];
    int layers = (n + per_layer - 1) / per_layer;
    int layer = i / per_layer, cell = i % per_layer;
    if (layer == layers - 1) {
        int in_last = n - (layers - 1) * per_layer;
        cell = (int)((long)cell * per_layer / in_last);
    }
    int ix = cell % dims[0], iz = cell / dims[0];
    out[0] = (float)(b->min[0] + (ix + 0.5) * size[0] / dims[0]);
    out[1] = (float)(b->min[1] + (layer + 0.5) * size[1] / layers);
    out[2] = (float)(b->min[2] + (iz + 0.5) * size[2] / dims[2]);
}

/* About sqrt(n)/2 clusters at hashed centres (kept 15% inside the volume),
 * each light near its cluster's centre: a bell of width 3% of the volume
 * across and 10% of its height, clamped to the volume. */
static void place_clustered(const struct scene_box *b, int n, int i, float out[3])
{
    int clusters = (int)fmax(1.0, lround(sqrt((double)n) / 2.0));
    uint32_t c = (uint32_t)(i % clusters);
    for (int a = 0; a < 3; a++) {
        double lo = b->min[a], size = (double)b->max[a] - b->min[a];
        double centre = lo + size * (0.15 + 0.7 * scene_hash01(c, 21u + (uint32_t)a));
        double bell = scene_hash01((uint32_t)i, 31u + (uint32_t)a) +
                      scene_hash01((uint32_t)i, 41u + (uint32_t)a) +
                      scene_hash01((uint32_t)i, 51u + (uint32_t)a) - 1.5;
        double sigma = size * (a == 1 ? 0.1 : 0.03);
        out[a] = (float)fmin(fmax(centre + 2.0 * sigma * bell, lo), (double)b->max[a]);
    }
}

const float SCENE_SUN_DIRECTION[3] = {-0.3577709f, -0.8944272f, -0.2683282f};
const float SCENE_SUN_COLOR[3] = {0.6f, 0.57f, 0.5f};

bool scene_add_sun(struct scene *s)
{
    if (!s->spec.sun)
        return true;
    struct scene_light *grown = realloc(s->lights, (size_t)(s->light_count + 1) * sizeof(*grown));
    if (!grown)
        return false;
    s->lights = grown;
    struct scene_light *l = &s->lights[s->light_count++];
    /* In glTF's terms too (a directional light has no falloff, so the flag
     * changes no pixel): colour SCENE_SUN_COLOR x light_intensity at pi lux
     * is the shading colour, for the result's light list. */
    *l = (struct scene_light){.type = SCENE_LIGHT_DIRECTIONAL, .period = 1, .cos_inner = 1.0f,
                              .cos_outer = 1.0f, .falloff = SCENE_FALLOFF_GLTF,
                              .gltf_intensity = (float)PI};
    for (int k = 0; k < 3; k++) {
        l->direction[k] = SCENE_SUN_DIRECTION[k];
        l->color[k] = SCENE_SUN_COLOR[k] * (float)s->spec.light_intensity;
        l->gltf_color[k] = l->color[k];
    }
    return true;
}

bool scene_place_lights(struct scene *s, float orbit)
{
    const struct scene_spec *spec = &s->spec;
    s->light_count = spec->lights;
    s->lights = calloc((size_t)(spec->lights ? spec->lights : 1), sizeof(*s->lights));
    if (!s->lights)
        return false;
    for (int i = 0; i < s->light_count; i++) {
        struct scene_light *l = &s->lights[i];
        switch (spec->light_layout) {
        case SCENE_LAYOUT_HALTON:
            place_halton(&s->light_volume, i, l->centre);
            break;
        case SCENE_LAYOUT_UNIFORM:
            place_uniform(&s->light_volume, i, l->centre);
            break;
        case SCENE_LAYOUT_GRID:
            place_grid(&s->light_volume, s->light_count, i, l->centre);
            break;
        case SCENE_LAYOUT_CLUSTERED:
            place_clustered(&s->light_volume, s->light_count, i, l->centre);
            break;
        }
        l->orbit = orbit;
        /* grid's radius 5 reaches about 100 objects a frame at async
         * distance 20, close to the 90 the thesis reports (chapter 4.1). */
        l->radius = (float)spec->light_radius;
        scene_hsv_to_rgb(i * 0.618033988749895, 0.6, 1.6, l->color);
        for (int k = 0; k < 3; k++)
            l->color[k] *= (float)spec->light_intensity;
        if (spec->light_type == SCENE_LIGHT_SPOT) {
            /* Straight down, at the light volume's floor and the objects. */
            double outer = spec->spot_angle_deg * PI / 180.0;
            l->type = SCENE_LIGHT_SPOT;
            l->direction[1] = -1.0f;
            l->cos_outer = (float)cos(outer);
            l->cos_inner = (float)cos(outer * SCENE_SPOT_INNER_RATIO);
        }
        /* Whole frames per revolution keep positions exact for any frame
         * index; light_speed divides the period (0 holds the lights still). */
        int base_period = 180 + 40 * (i % 7);
        l->period = spec->light_speed > 0
                        ? (int)fmax(1.0, lround(base_period / spec->light_speed))
                        : base_period;
        l->phase = (i * 37) % base_period % l->period;
    }
    return true;
}

float scene_gltf_light_radius(float intensity, const float color[3], float range, float reach)
{
    if (range > 0.0f)
        return range;
    /* I c / (pi d^2) = SCENE_LIGHT_CUTOFF */
    double c = fmax(color[0], fmax(color[1], color[2]));
    double d = sqrt(fmax(intensity * c, 0.0) / (PI * SCENE_LIGHT_CUTOFF));
    return (float)fmax(d, reach);
}

bool scene_add_rig(struct scene *s)
{
    const struct scene_spec *spec = &s->spec;
    if (!spec->rig_count)
        return true;
    struct scene_light *grown =
        realloc(s->lights, (size_t)(s->light_count + spec->rig_count) * sizeof(*grown));
    if (!grown)
        return false;
    s->lights = grown;
    /* A light without a range reaches at least across the bounds. */
    double diag2 = 0;
    for (int k = 0; k < 3; k++)
        diag2 += pow((double)s->bounds.max[k] - s->bounds.min[k], 2);
    float reach = (float)fmax(sqrt(diag2), 1.0);
    for (int i = 0; i < spec->rig_count; i++) {
        const struct scene_rig_light *r = &spec->rig[i];
        struct scene_light *l = &s->lights[s->light_count + i];
        memset(l, 0, sizeof(*l));
        l->type = (enum scene_light_type)r->type;
        l->period = 1; /* stands where the job put it */
        l->falloff = SCENE_FALLOFF_GLTF;
        l->range = (float)r->range;
        l->gltf_intensity = (float)r->intensity;
        for (int k = 0; k < 3; k++) {
            l->centre[k] = (float)r->position[k];
            l->direction[k] = (float)r->direction[k];
            l->gltf_color[k] = (float)r->color[k];
            l->color[k] = (float)(r->color[k] * r->intensity / PI);
        }
        if (l->type == SCENE_LIGHT_DIRECTIONAL) {
            /* As an asset's: no position, but a centre far up-light of the
             * bounds for the code that measures distances to lights. */
            for (int k = 0; k < 3; k++)
                l->centre[k] = 0.5f * (s->bounds.min[k] + s->bounds.max[k]) -
                               4.0f * reach * l->direction[k];
            l->radius = 16.0f * reach;
            l->cos_inner = l->cos_outer = -1.0f;
            continue;
        }
        l->radius = scene_gltf_light_radius(l->gltf_intensity, l->gltf_color, l->range, reach);
        if (l->type == SCENE_LIGHT_SPOT) {
            l->cos_inner = (float)cos(r->inner_cone_deg * PI / 180.0);
            l->cos_outer = (float)cos(r->outer_cone_deg * PI / 180.0);
        }
    }
    s->light_count += spec->rig_count;
    s->rig_light_count = spec->rig_count;
    return true;
}
