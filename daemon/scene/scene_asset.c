/* A scene from an asset (daemon/scene/asset.h): each asset mesh one scene
 * mesh and one instance, its vertices re-centred on its box's centre and
 * the instance standing there (scale 1), so that bounding spheres, shadow
 * casters and culling see each mesh where it is; its camera (up vector and
 * orthographic projection honoured), or a view framing the bounds; its
 * KHR_lights_punctual lights, and generated point lights around and over
 * it, outside its bounds.
 *
 * Every light of an asset scene is a glTF punctual light (scene.h:
 * SCENE_FALLOFF_GLTF; docs/scenes.md): intensity in candela (point, spot)
 * or lux (directional), falling off as 1 / d^2 times the range window, so
 * that the Khronos glTF Sample Viewer given the result's light list draws
 * the same light. The shading library's light colour is then
 * color * intensity / pi (its BRDF is pi times glTF's), times
 * scene.light_intensity. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/asset.h"
#include "daemon/scene/mesh_charts.h"
#include "daemon/scene/scene_build.h"

static const double PI = 3.14159265358979323846;

static const char *const SLOT_NAMES[ASSET_TEX_SLOTS] = {
    "base_color", "metallic_roughness", "normal", "occlusion", "emissive"};

/* Every count and index the scene reads, checked, so that a bad asset is
 * an error naming the field, never a crash (the cache reader checks these
 * too; the synthetic asset and a future converter get the same check). */
static bool check_asset(const struct asset *a, char *err, size_t errlen)
{
    if (!a->mesh_count) {
        snprintf(err, errlen, "asset.meshes: the asset has no meshes to draw");
        return false;
    }
    for (uint32_t i = 0; i < a->mesh_count; i++) {
        const struct asset_mesh *m = &a->meshes[i];
        if (m->material < -1 || m->material >= (int32_t)a->material_count) {
            snprintf(err, errlen, "asset.meshes[%u].material: %d is not a material (the asset has %u)",
                     i, (int)m->material, a->material_count);
            return false;
        }
        if (!m->vertex_count || !m->index_count || m->index_count % 3) {
            snprintf(err, errlen, "asset.meshes[%u]: %u vertices and %u indices are not triangles",
                     i, m->vertex_count, m->index_count);
            return false;
        }
        for (uint32_t k = 0; k < m->index_count; k++)
            if (m->indices[k] >= m->vertex_count) {
                snprintf(err, errlen, "asset.meshes[%u].indices[%u]: %u is past the %u vertices",
                         i, k, m->indices[k], m->vertex_count);
                return false;
            }
        for (int k = 0; k < 3; k++)
            if (!(m->box_min[k] <= m->box_max[k]) || !isfinite(m->box_min[k]) ||
                !isfinite(m->box_max[k])) {
                snprintf(err, errlen, "asset.meshes[%u].box: not a finite box", i);
                return false;
            }
    }
    for (uint32_t i = 0; i < a->material_count; i++) {
        const struct asset_material *m = &a->materials[i];
        if ((unsigned)m->alpha_mode > ASSET_ALPHA_BLEND) {
            snprintf(err, errlen, "asset.materials[%u].alpha_mode: %d is not a mode", i,
                     (int)m->alpha_mode);
            return false;
        }
        for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
            const struct asset_texture_ref *t = &m->tex[s];
            if (t->image < -1 || t->image >= (int32_t)a->image_count) {
                snprintf(err, errlen, "asset.materials[%u].%s.image: %d is not an image (the asset has %u)",
                         i, SLOT_NAMES[s], (int)t->image, a->image_count);
                return false;
            }
            if (t->image >= 0 && t->uv_set != 0 && t->uv_set != 1) {
                snprintf(err, errlen, "asset.materials[%u].%s.uv_set: %d, only 0 and 1 are drawn",
                         i, SLOT_NAMES[s], (int)t->uv_set);
                return false;
            }
        }
    }
    for (uint32_t i = 0; i < a->image_count; i++)
        if (!a->images[i].width || !a->images[i].height || !a->images[i].rgba) {
            snprintf(err, errlen, "asset.images[%u]: empty image", i);
            return false;
        }
    for (uint32_t i = 0; i < a->light_count; i++)
        if ((unsigned)a->lights[i].type > ASSET_LIGHT_DIRECTIONAL ||
            !(a->lights[i].intensity >= 0) || !(a->lights[i].range >= 0)) {
            snprintf(err, errlen, "asset.lights[%u]: type, intensity or range out of range", i);
            return false;
        }
    for (int k = 0; k < 3; k++)
        if (!(a->box_min[k] <= a->box_max[k])) {
            snprintf(err, errlen, "asset.box: not a box");
            return false;
        }
    return true;
}

static enum asset_alpha_mode mesh_alpha(const struct asset *a, uint32_t m)
{
    int mat = a->meshes[m].material;
    return mat < 0 ? ASSET_ALPHA_OPAQUE : a->materials[mat].alpha_mode;
}

/* Scene mesh from asset mesh am: vertices less the box's centre. */
static bool build_mesh(struct mesh *out, const struct asset_mesh *am, const float centre[3])
{
    out->vertex_count = am->vertex_count;
    out->index_count = am->index_count;
    out->vertices = calloc(am->vertex_count, sizeof(*out->vertices));
    out->indices = malloc(am->index_count * sizeof(*out->indices));
    if (!out->vertices || !out->indices)
        return false;
    memcpy(out->indices, am->indices, am->index_count * sizeof(*out->indices));
    float r2 = 0.0f;
    for (uint32_t i = 0; i < am->vertex_count; i++) {
        const struct asset_vertex *v = &am->vertices[i];
        struct mesh_vertex *o = &out->vertices[i];
        float d2 = 0.0f;
        for (int k = 0; k < 3; k++) {
            o->pos[k] = v->pos[k] - centre[k];
            o->normal[k] = v->normal[k];
            d2 += o->pos[k] * o->pos[k];
        }
        r2 = fmaxf(r2, d2);
        /* OSL's unique parametrisation is uv1; its charts' rectangles are
         * set below (mesh_chart_rects). */
        o->uv[0] = v->uv1[0], o->uv[1] = v->uv1[1];
        o->tex[0] = v->uv0[0], o->tex[1] = v->uv0[1];
        o->tex[2] = v->texcoord1[0], o->tex[3] = v->texcoord1[1];
        memcpy(o->tangent, v->tangent, sizeof(o->tangent));
        memcpy(o->color, v->color, sizeof(o->color));
    }
    out->bound_radius = sqrtf(r2);
    mesh_compute_box(out); /* the scene's bounds are computed before the procedural meshes exist */
    /* uv units per unit of surface: the square root of the ratio of uv1
     * area to world area over the triangles. */
    double uv_area = 0.0, area = 0.0;
    for (uint32_t t = 0; t + 2 < am->index_count; t += 3) {
        const struct asset_vertex *p0 = &am->vertices[am->indices[t]],
                                  *p1 = &am->vertices[am->indices[t + 1]],
                                  *p2 = &am->vertices[am->indices[t + 2]];
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++)
            e1[k] = (double)p1->pos[k] - p0->pos[k], e2[k] = (double)p2->pos[k] - p0->pos[k];
        double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        area += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        uv_area += 0.5 * fabs(((double)p1->uv1[0] - p0->uv1[0]) * ((double)p2->uv1[1] - p0->uv1[1]) -
                              ((double)p2->uv1[0] - p0->uv1[0]) * ((double)p1->uv1[1] - p0->uv1[1]));
    }
    out->uv_per_unit = area > 0.0 ? (float)sqrt(uv_area / area) : 1.0f;
    return mesh_chart_rects(out, NULL);
}

/* The asset camera spec.asset_camera names: "" the first, digits an index,
 * else a name. -1 when the asset has none and none was asked for. */
static bool choose_camera(const struct scene *s, int *out, char *err, size_t errlen)
{
    const struct asset *a = s->asset;
    const char *want = s->spec.asset_camera;
    *out = -1;
    if (!want[0]) {
        *out = a->camera_count ? 0 : -1;
        return true;
    }
    char names[256] = "";
    for (uint32_t i = 0; i < a->camera_count && strlen(names) < sizeof(names) - 80; i++)
        snprintf(names + strlen(names), sizeof(names) - strlen(names), "%s%u \"%s\"",
                 i ? ", " : "", i, a->cameras[i].name);
    bool digits = true;
    for (const char *p = want; *p; p++)
        digits = digits && *p >= '0' && *p <= '9';
    if (digits) {
        long idx = strtol(want, NULL, 10);
        if (idx < (long)a->camera_count) {
            *out = (int)idx;
            return true;
        }
        snprintf(err, errlen, "scene.asset_camera: no camera %ld: the asset has %u%s%s%s", idx,
                 a->camera_count, a->camera_count ? " (" : "", names, a->camera_count ? ")" : "");
        return false;
    }
    for (uint32_t i = 0; i < a->camera_count; i++)
        if (strcmp(a->cameras[i].name, want) == 0) {
            *out = (int)i;
            return true;
        }
    snprintf(err, errlen, "scene.asset_camera: no camera named \"%s\": the asset has %u%s%s%s",
             want, a->camera_count, a->camera_count ? " (" : "", names,
             a->camera_count ? ")" : "");
    return false;
}

static void static_pose(struct scene *s, int cam)
{
    const struct asset *a = s->asset;
    struct scene_rig *r = &s->rig;
    float c[3], half2 = 0.0f;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5f * (a->box_min[k] + a->box_max[k]);
        float h = 0.5f * (a->box_max[k] - a->box_min[k]);
        half2 += h * h;
    }
    float radius = fmaxf(sqrtf(half2), 1e-3f);
    if (cam >= 0) {
        const struct asset_camera *ac = &a->cameras[cam];
        float to[3] = {c[0] - ac->eye[0], c[1] - ac->eye[1], c[2] - ac->eye[2]};
        float dist = fmaxf(sqrtf(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]), 1.0f);
        for (int k = 0; k < 3; k++) {
            r->eye[k] = ac->eye[k];
            r->target[k] = ac->eye[k] + dist * ac->forward[k];
            r->up[k] = ac->up[k];
        }
        /* The node's up, unless it lies along the view (a degenerate file). */
        float dot = ac->up[0] * ac->forward[0] + ac->up[1] * ac->forward[1] +
                    ac->up[2] * ac->forward[2];
        float up2 = ac->up[0] * ac->up[0] + ac->up[1] * ac->up[1] + ac->up[2] * ac->up[2];
        if (!(up2 > 0.5f) || fabsf(dot) > 0.999f)
            r->up[0] = r->up[2] = 0.0f, r->up[1] = 1.0f;
        if (ac->perspective) {
            r->fovy_deg = ac->yfov > 0.0f ? (float)(ac->yfov * 180.0 / PI) : 50.0f;
        } else {
            /* The cache keeps an orthographic camera's ymag in yfov and
             * xmag / ymag in aspect (asset.h). */
            r->orthographic = true;
            r->fovy_deg = 50.0f; /* unused */
            r->ymag = ac->yfov > 0.0f ? ac->yfov : radius;
            r->xmag = ac->aspect > 0.0f ? r->ymag * ac->aspect
                                        : r->ymag * (float)s->spec.width / (float)s->spec.height;
        }
        r->near_z = ac->znear > 0.0f ? ac->znear : 0.01f * dist;
        r->far_z = ac->zfar > r->near_z ? ac->zfar : dist + 2.0f * radius;
        return;
    }
    /* Framed: from above and in front (+z), at the distance where the
     * bounds' sphere fills the narrower field of view. */
    r->fovy_deg = 50.0f;
    double half_y = r->fovy_deg * PI / 360.0;
    double half_x = atan((double)s->spec.width / s->spec.height * tan(half_y));
    float dist = (float)(radius / sin(fmin(half_x, half_y)));
    const float dir[3] = {0.0f, 0.447213595f, 0.894427191f};
    for (int k = 0; k < 3; k++) {
        r->target[k] = c[k];
        r->eye[k] = c[k] + dist * dir[k];
    }
    r->near_z = fmaxf(0.01f * dist, 0.5f * (dist - radius));
    r->far_z = dist + 2.0f * radius;
}

/* The asset's bounding sphere: centre and radius (half the box's diagonal). */
static float asset_sphere(const struct asset *a, float c[3])
{
    float half2 = 0.0f;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5f * (a->box_min[k] + a->box_max[k]);
        float h = 0.5f * (a->box_max[k] - a->box_min[k]);
        half2 += h * h;
    }
    return fmaxf(sqrtf(half2), 1e-3f);
}

/* A light of glTF colour and intensity in the shading library's terms. */
static void set_gltf(const struct scene *s, struct scene_light *l, const float color[3],
                     float intensity)
{
    l->falloff = SCENE_FALLOFF_GLTF;
    l->gltf_intensity = (float)(intensity * s->spec.light_intensity);
    for (int k = 0; k < 3; k++) {
        l->gltf_color[k] = color[k];
        l->color[k] = (float)(color[k] * l->gltf_intensity / PI);
    }
}

/* The asset's lights, converted (see the top of this file). */
static void convert_light(const struct scene *s, const struct asset_light *al,
                          struct scene_light *l)
{
    float c[3], radius = asset_sphere(s->asset, c);
    memset(l, 0, sizeof(*l));
    l->period = 1; /* still: an asset's lights stand where the file puts them */
    set_gltf(s, l, al->color, al->intensity);
    memcpy(l->direction, al->direction, sizeof(l->direction));
    switch (al->type) {
    case ASSET_LIGHT_POINT:
    case ASSET_LIGHT_SPOT:
        l->type = al->type == ASSET_LIGHT_SPOT ? SCENE_LIGHT_SPOT : SCENE_LIGHT_POINT;
        memcpy(l->centre, al->position, sizeof(l->centre));
        l->range = al->range > 0.0f ? al->range : 0.0f;
        l->radius = scene_gltf_light_radius(l->gltf_intensity, l->gltf_color, l->range,
                                            4.0f * radius);
        l->cos_inner = cosf(al->inner_cone);
        l->cos_outer = cosf(al->outer_cone);
        break;
    case ASSET_LIGHT_DIRECTIONAL:
        /* No position: the lighting library and the light grids read the
         * type and direction alone. The centre is still set far up-light of
         * the bounds with a radius that covers them, for the code that
         * measures distances to every light (scene_describe's counts). */
        l->type = SCENE_LIGHT_DIRECTIONAL;
        for (int k = 0; k < 3; k++)
            l->centre[k] = c[k] - 8.0f * radius * al->direction[k];
        l->radius = 32.0f * radius;
        l->cos_inner = l->cos_outer = -1.0f;
        break;
    }
}

/* Generated lights around and over the asset (docs/scenes.md): the layout
 * picks a point u of the unit cube per light (Halton, hashed, lattice or
 * clusters, as in a preset's volume). u0 and u1 give a direction from the
 * asset's centre, azimuth 2 pi u0 and elevation asin(0.2 + 0.75 u1) (12 to
 * 72 degrees up); the light stands beyond the point where that ray leaves
 * the asset's box, by a gap of (0.15 + 0.35 u2) times its range, and at
 * least 1.5 times its orbit (0.03 R) beyond that face. So every light is
 * outside the box, circling too, and a light of small
 * range (scene.light_radius) hugs the surfaces near it: many small lights
 * still overlap unevenly over the asset, as the many-lights benchmarks
 * need. Each is a glTF point light (or a spot aimed at the centre) of range
 * 5 R ("auto": from its farthest gap, 2.5 R beyond a box inside the sphere
 * of radius R, every point of the asset within reach) and of intensity
 * 30 R^2 / N x (range / 5 R)^2 candela for N lights: at "auto" range, N
 * lights at about 2.5 R give a white surface facing the light about 0.6 of
 * radiance, neither dark nor clipped at exposure 1; a smaller range scales
 * the intensity with its square, so the light its nearby surfaces get stays
 * about the same. */
static bool place_generated(struct scene *s)
{
    const struct asset *a = s->asset;
    float c[3], R = asset_sphere(a, c);
    s->light_volume = (struct scene_box){{0, 0, 0}, {1, 1, 1}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    float orbit = 0.03f * R;
    if (!scene_place_lights(s, orbit))
        return false;
    int n = s->light_count;
    float range = s->spec.light_radius > 0 ? (float)s->spec.light_radius : 5.0f * R;
    float intensity = n ? 30.0f * R * R / (float)n * powf(range / (5.0f * R), 2.0f) : 0.0f;
    struct scene_box box = {{c[0], c[1], c[2]}, {c[0], c[1], c[2]}};
    for (int i = 0; i < n; i++) {
        struct scene_light *l = &s->lights[i];
        double az = 2.0 * PI * l->centre[0], el = asin(0.2 + 0.75 * l->centre[1]);
        double dir[3] = {cos(el) * sin(az), sin(el), cos(el) * cos(az)};
        /* Where the ray from the centre leaves the box, through the face
         * across axis `face`. */
        double exit = INFINITY;
        int face = 1;
        for (int k = 0; k < 3; k++) {
            double half = 0.5 * ((double)a->box_max[k] - a->box_min[k]);
            if (fabs(dir[k]) > 1e-9 && half / fabs(dir[k]) < exit)
                exit = half / fabs(dir[k]), face = k;
        }
        double gap = range * (0.15 + 0.35 * l->centre[2]), p[3];
        for (int k = 0; k < 3; k++)
            p[k] = c[k] + (exit + gap) * dir[k];
        /* At least 1.5 orbits beyond that face, so that circling (which
         * moves a light by at most one orbit) never takes it inside. */
        double beyond = gap * fabs(dir[face]), need = 1.5 * orbit;
        if (beyond < need)
            p[face] += (dir[face] < 0 ? -1.0 : 1.0) * (need - beyond);
        for (int k = 0; k < 3; k++) {
            l->centre[k] = (float)p[k];
            box.min[k] = fminf(box.min[k], l->centre[k]);
            box.max[k] = fmaxf(box.max[k], l->centre[k]);
            if (l->type == SCENE_LIGHT_SPOT)
                l->direction[k] = (float)-dir[k];
        }
        /* Pale hues: the lights vary, the materials' colours still read. */
        float color[3];
        scene_hsv_to_rgb(i * 0.618033988749895, 0.3, 1.0, color);
        set_gltf(s, l, color, intensity);
        l->range = range;
        l->radius = range;
    }
    if (n)
        s->light_volume = box;
    else
        s->light_volume = (struct scene_box){{a->box_min[0], a->box_min[1], a->box_min[2]},
                                             {a->box_max[0], a->box_max[1], a->box_max[2]}};
    return true;
}

static bool place_lights(struct scene *s)
{
    const struct asset *a = s->asset;
    int asset_lights = s->spec.asset_lights ? (int)a->light_count : 0;
    if (s->spec.lights == SCENE_LIGHTS_AUTO)
        s->spec.lights = asset_lights || s->spec.rig_count ? 0 : SCENE_ASSET_DEFAULT_LIGHTS;
    if (!place_generated(s))
        return false;
    s->generated_light_count = s->light_count;
    s->asset_light_count = asset_lights;
    if (!asset_lights)
        return true;
    struct scene_light *l = realloc(s->lights, (size_t)(s->light_count + asset_lights) * sizeof(*l));
    if (!l)
        return false;
    s->lights = l;
    for (int i = 0; i < asset_lights; i++)
        convert_light(s, &a->lights[i], &s->lights[s->light_count + i]);
    s->light_count += asset_lights;
    return true;
}

bool scene_build_asset(struct scene *s, char *err, size_t errlen)
{
    const struct asset *a = s->asset;
    if (!check_asset(a, err, errlen) || !choose_camera(s, &s->asset_camera, err, errlen))
        return false;
    int n = (int)a->mesh_count;
    s->instance_count = n;
    s->instances = calloc((size_t)n, sizeof(*s->instances));
    s->mesh_asset_index = malloc((size_t)s->mesh_count * sizeof(int));
    if (!s->instances || !s->mesh_asset_index)
        goto oom;
    for (int m = 0; m < s->mesh_count; m++)
        s->mesh_asset_index[m] = -1;
    /* Opaque meshes, then masked, then blended; each in the file's order. */
    int next = 0;
    for (int mode = ASSET_ALPHA_OPAQUE; mode <= ASSET_ALPHA_BLEND; mode++) {
        if (mode == ASSET_ALPHA_MASK)
            s->asset_mask_first = SCENE_MESH_PROCEDURAL + next;
        if (mode == ASSET_ALPHA_BLEND)
            s->asset_blend_first = SCENE_MESH_PROCEDURAL + next;
        for (uint32_t am = 0; am < a->mesh_count; am++) {
            if ((int)mesh_alpha(a, am) != mode)
                continue;
            const struct asset_mesh *src = &a->meshes[am];
            int sm = SCENE_MESH_PROCEDURAL + next;
            struct scene_instance *in = &s->instances[next++];
            for (int k = 0; k < 3; k++)
                in->pos[k] = 0.5f * (src->box_min[k] + src->box_max[k]);
            in->scale = 1.0f;
            in->mesh = sm;
            in->asset_material = src->material;
            s->mesh_asset_index[sm] = (int)am;
            /* The constant fallback: the factors (glTF's default material
             * is white, fully rough, not metallic). */
            const struct asset_material *mat = src->material >= 0 ? &a->materials[src->material] : NULL;
            for (int k = 0; k < 3; k++)
                in->albedo[k] = mat ? mat->base_color[k] : 1.0f;
            float rough = mat ? mat->roughness : 1.0f;
            in->material.metallic = mat ? mat->metallic : 1.0f;
            in->material.roughness = rough;
            /* Phong's terms from roughness, as the chart preset does. */
            in->material.shininess = fmaxf(1.0f, 2.0f / fmaxf(rough * rough, 1e-3f) - 2.0f);
            in->material.specular = 0.04f + 0.96f * in->material.metallic;
            if (!build_mesh(&s->meshes[sm], src, in->pos))
                goto oom;
        }
    }
    static_pose(s, s->asset_camera);
    if (!place_lights(s))
        goto oom;
    return true;
oom:
    snprintf(err, errlen, "out of memory building the scene from the asset");
    return false;
}
