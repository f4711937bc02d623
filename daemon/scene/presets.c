/* The scene presets: what objects stand where, the volume the lights fill
 * and the camera's static pose.
 *  - grid: the thesis scene (chapter 3.1.1), unchanged to the bit;
 *  - lights: the many-lights scene of the tiled and clustered shading
 *    papers: objects on a ground plane, lights spread through the volume
 *    above it, seen from a raised camera that keeps most of them on screen;
 *  - teapots: seed 002's scene: eight Utah teapots of varied materials in a
 *    ring around a container, on a ground plane under a sky, lit by point
 *    lights through the air between them;
 *  - chart: spheres by metallic (rows, 0 at the bottom to 1 at the top)
 *    and roughness (columns, 0 on the left to 1 on the right), the usual
 *    check of a physically based model, lit from above the camera;
 *  - sphere: one white sphere on a white ground, both in the spec's
 *    material, a light straight above: the white furnace's and the shadow
 *    test's scene. */
#include <math.h>
#include <stdlib.h>

#include "daemon/scene/scene_build.h"
#include "daemon/scene/teapot.h"

const float SCENE_SPHERE_RADIUS = 0.8f, SCENE_CUBE_HALF = 0.65f, SCENE_PLANE_HALF = 1.0f;
/* x: the handle (-3) to the spout's lip (3.525), centred; y: 3.15 tall; z:
 * the body's radius 2 (daemon/scene/teapot.c). */
const float SCENE_TEAPOT_HALF[3] = {3.2625f, 1.575f, 2.0f};

/* Thesis layout: 16 columns, 8 rows, 4 layers; rows alternate between
 * spheres and cubes, giving 8x8x4 of each. */
enum { GRID_COLS = 16, GRID_ROWS = 8, GRID_LAYERS = 4 };
static const float GRID_SPACING_X = 2.5f, GRID_SPACING_Z = 3.0f, GRID_SPACING_Y = 2.5f;

/* lights: a 12x12 field of objects 3 units apart on a 48x48 ground. */
enum { FIELD_CELLS = 12 };
static const float FIELD_SPACING = 3.0f, GROUND_HALF = 24.0f;

static bool alloc_instances(struct scene *s, int n)
{
    s->instance_count = n;
    s->instances = calloc((size_t)n, sizeof(*s->instances));
    return s->instances != NULL;
}

static bool build_grid(struct scene *s)
{
    if (!alloc_instances(s, GRID_COLS * GRID_ROWS * GRID_LAYERS))
        return false;
    /* Grouped by mesh (spheres first) so each mesh is one instanced draw. */
    int next = 0;
    for (int mesh = 0; mesh < 2; mesh++)
        for (int layer = 0; layer < GRID_LAYERS; layer++)
            for (int row = 0; row < GRID_ROWS; row++) {
                if (row % 2 != mesh)
                    continue;
                for (int col = 0; col < GRID_COLS; col++) {
                    struct scene_instance *in = &s->instances[next++];
                    in->pos[0] = ((float)col - (GRID_COLS - 1) * 0.5f) * GRID_SPACING_X;
                    in->pos[1] = (float)layer * GRID_SPACING_Y;
                    in->pos[2] = -(float)row * GRID_SPACING_Z;
                    in->scale = 1.0f;
                    in->mesh = (enum scene_mesh)mesh;
                    unsigned cell = (unsigned)((layer * GRID_ROWS + row) * GRID_COLS + col);
                    scene_hsv_to_rgb(scene_radical_inverse(cell + 1, 2), 0.45, 0.85, in->albedo);
                }
            }
    /* Light centres: x in [-20, 20], y in [-0.5, 9.5], z in [-22.5, 1.5]
     * (the thesis spread), circling in the XY plane at radius 3. */
    s->light_volume = (struct scene_box){{-20.0f, -0.5f, -22.5f}, {20.0f, 9.5f, 1.5f}};
    s->light_orbit_plane = SCENE_ORBIT_XY;
    struct scene_rig *r = &s->rig;
    r->eye[0] = 0.0f, r->eye[1] = 28.0f, r->eye[2] = 22.0f;
    r->target[0] = 0.0f, r->target[1] = 1.0f, r->target[2] = -10.0f;
    r->fovy_deg = 55.0f;
    r->near_z = 0.5f;
    r->far_z = 200.0f;
    return scene_place_lights(s, 3.0f);
}

static bool build_lights(struct scene *s)
{
    if (!alloc_instances(s, FIELD_CELLS * FIELD_CELLS + 1))
        return false;
    int next = 0;
    for (int mesh = 0; mesh < 2; mesh++)
        for (int row = 0; row < FIELD_CELLS; row++)
            for (int col = 0; col < FIELD_CELLS; col++) {
                /* A checkerboard of spheres and cubes, each jittered within
                 * its cell, sized 0.7 to 1.5 and resting on the ground. */
                if ((row + col) % 2 != mesh)
                    continue;
                uint32_t cell = (uint32_t)(row * FIELD_CELLS + col);
                struct scene_instance *in = &s->instances[next++];
                float scale = (float)(0.7 + 0.8 * scene_hash01(cell, 1));
                in->mesh = (enum scene_mesh)mesh;
                in->scale = scale;
                in->pos[0] = ((float)col - (FIELD_CELLS - 1) * 0.5f) * FIELD_SPACING +
                             (float)(scene_hash01(cell, 2) - 0.5);
                in->pos[1] = (mesh == SCENE_MESH_SPHERE ? SCENE_SPHERE_RADIUS : SCENE_CUBE_HALF) *
                             scale;
                in->pos[2] = ((float)row - (FIELD_CELLS - 1) * 0.5f) * FIELD_SPACING +
                             (float)(scene_hash01(cell, 3) - 0.5);
                scene_hsv_to_rgb(scene_hash01(cell, 4), 0.55, 0.9, in->albedo);
            }
    struct scene_instance *ground = &s->instances[next];
    ground->mesh = SCENE_MESH_PLANE;
    ground->scale = GROUND_HALF / SCENE_PLANE_HALF;
    ground->albedo[0] = ground->albedo[1] = ground->albedo[2] = 0.6f;

    /* Lights fill the field from just above the ground to twice the height
     * of the tallest object, circling horizontally so they never dip into
     * the ground. */
    s->light_volume = (struct scene_box){{-18.0f, 0.3f, -18.0f}, {18.0f, 6.0f, 18.0f}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    struct scene_rig *r = &s->rig;
    r->eye[0] = 0.0f, r->eye[1] = 22.0f, r->eye[2] = 28.0f;
    r->target[0] = 0.0f, r->target[1] = 0.0f, r->target[2] = -2.0f;
    r->fovy_deg = 55.0f;
    r->near_z = 0.5f;
    r->far_z = 200.0f;
    return scene_place_lights(s, 1.5f);
}

/* A material for the physically based model with Phong's two terms made to
 * match it: shininess from roughness by Beckmann's relation (alpha^2 =
 * 2 / (n + 2)), specular as strong as the metal is. */
static struct scene_material pbr_material(float metallic, float roughness)
{
    double alpha = fmax(roughness * roughness, 0.02);
    return (struct scene_material){
        .specular = 0.5f + 0.5f * metallic,
        .shininess = (float)fmin(4096.0, fmax(1.0, 2.0 / (alpha * alpha) - 2.0)),
        .metallic = metallic,
        .roughness = roughness,
    };
}

/* White lights of the given brightness times scene.light_intensity. */
static void white_lights(struct scene *s, float brightness)
{
    for (int i = 0; i < s->light_count; i++)
        for (int k = 0; k < 3; k++)
            s->lights[i].color[k] = brightness * (float)s->spec.light_intensity;
}

static void set_pose(struct scene *s, float ex, float ey, float ez, float tx, float ty, float tz,
                     float fovy)
{
    struct scene_rig *r = &s->rig;
    r->eye[0] = ex, r->eye[1] = ey, r->eye[2] = ez;
    r->target[0] = tx, r->target[1] = ty, r->target[2] = tz;
    r->fovy_deg = fovy;
    r->near_z = 0.1f;
    r->far_z = 100.0f;
}

/* Seed 002's teapots: named materials, metals first (measured F0 as the
 * albedo: gold, copper, silver, aluminium), then dielectrics from glossy to
 * rough; the porcelain's roughness 0.05 is below the model's clamp on
 * purpose, so that the clamp is exercised and counted. */
static const struct {
    float albedo[3], metallic, roughness;
} TEAPOT_MATERIALS[8] = {
    {{1.000f, 0.766f, 0.336f}, 1.0f, 0.25f}, /* gold */
    {{0.955f, 0.638f, 0.538f}, 1.0f, 0.45f}, /* copper */
    {{0.972f, 0.960f, 0.915f}, 1.0f, 0.10f}, /* silver */
    {{0.913f, 0.922f, 0.924f}, 1.0f, 0.65f}, /* aluminium, brushed */
    {{0.800f, 0.080f, 0.060f}, 0.0f, 0.30f}, /* red plastic */
    {{0.080f, 0.220f, 0.750f}, 0.0f, 0.15f}, /* blue glaze */
    {{0.180f, 0.550f, 0.220f}, 0.0f, 0.90f}, /* green rubber */
    {{0.900f, 0.890f, 0.860f}, 0.0f, 0.05f}, /* porcelain */
};
enum { TEAPOTS = 8 };
static const float TEAPOT_RING = 3.0f, TEAPOT_TALL = 1.1f, CONTAINER_HALF = 0.6f,
                   TEAPOTS_GROUND_HALF = 10.0f;

static bool build_teapots(struct scene *s)
{
    /* By mesh: the container (cube), the ground (plane), the teapots. */
    if (!alloc_instances(s, TEAPOTS + 2))
        return false;
    struct scene_instance *box = &s->instances[0], *ground = &s->instances[1];
    box->mesh = SCENE_MESH_CUBE;
    box->scale = CONTAINER_HALF / SCENE_CUBE_HALF;
    box->pos[1] = CONTAINER_HALF;
    box->albedo[0] = 0.55f, box->albedo[1] = 0.38f, box->albedo[2] = 0.22f; /* a wooden crate */
    box->material = pbr_material(0.0f, 0.6f);
    ground->mesh = SCENE_MESH_PLANE;
    ground->scale = TEAPOTS_GROUND_HALF / SCENE_PLANE_HALF;
    ground->albedo[0] = ground->albedo[1] = ground->albedo[2] = 0.5f;
    ground->material = pbr_material(0.0f, 0.8f);
    float scale = (float)(TEAPOT_TALL / TEAPOT_HEIGHT);
    for (int k = 0; k < TEAPOTS; k++) {
        struct scene_instance *t = &s->instances[2 + k];
        double a = (k + 0.5) * 2.0 * 3.14159265358979323846 / TEAPOTS;
        t->mesh = SCENE_MESH_TEAPOT;
        t->scale = scale;
        t->pos[0] = (float)(TEAPOT_RING * cos(a));
        t->pos[1] = SCENE_TEAPOT_HALF[1] * scale;
        t->pos[2] = (float)(TEAPOT_RING * sin(a));
        for (int c = 0; c < 3; c++)
            t->albedo[c] = TEAPOT_MATERIALS[k].albedo[c];
        t->material = pbr_material(TEAPOT_MATERIALS[k].metallic, TEAPOT_MATERIALS[k].roughness);
    }
    /* Lights between and above the teapots, circling horizontally. */
    s->light_volume = (struct scene_box){{-5.0f, 0.3f, -5.0f}, {5.0f, 2.8f, 5.0f}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    s->sky = true;
    set_pose(s, 0.0f, 3.4f, 8.5f, 0.0f, 0.5f, 0.0f, 50.0f);
    if (!scene_place_lights(s, 1.0f))
        return false;
    /* Many overlapping lights: each at half the other presets' brightness. */
    for (int i = 0; i < s->light_count; i++)
        for (int k = 0; k < 3; k++)
            s->lights[i].color[k] *= 0.5f;
    return true;
}

enum { CHART_ROWS = 5, CHART_COLS = 7 };
static const float CHART_SPACING = 2.0f;

static bool build_chart(struct scene *s)
{
    if (!alloc_instances(s, CHART_ROWS * CHART_COLS))
        return false;
    for (int row = 0; row < CHART_ROWS; row++)
        for (int col = 0; col < CHART_COLS; col++) {
            struct scene_instance *in = &s->instances[row * CHART_COLS + col];
            in->mesh = SCENE_MESH_SPHERE;
            in->scale = 1.0f;
            in->pos[0] = ((float)col - (CHART_COLS - 1) * 0.5f) * CHART_SPACING;
            in->pos[1] = ((float)row - (CHART_ROWS - 1) * 0.5f) * CHART_SPACING;
            in->albedo[0] = 0.91f, in->albedo[1] = 0.55f, in->albedo[2] = 0.32f;
            in->material = pbr_material((float)row / (CHART_ROWS - 1),
                                        (float)col / (CHART_COLS - 1));
        }
    /* Lights in a row above and in front of the chart. */
    s->light_volume = (struct scene_box){{-6.0f, 2.0f, 8.0f}, {6.0f, 4.0f, 9.0f}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    s->sky = true;
    set_pose(s, 0.0f, 0.0f, 17.0f, 0.0f, 0.0f, 0.0f, 40.0f);
    if (!scene_place_lights(s, 0.5f))
        return false;
    white_lights(s, 0.35f);
    return true;
}

static bool build_sphere(struct scene *s)
{
    /* By mesh: the sphere, then the ground it rests on; both white, both in
     * the spec's material. */
    if (!alloc_instances(s, 2))
        return false;
    struct scene_instance *in = &s->instances[0], *ground = &s->instances[1];
    in->mesh = SCENE_MESH_SPHERE;
    in->scale = 1.0f;
    ground->mesh = SCENE_MESH_PLANE;
    ground->scale = 6.0f / SCENE_PLANE_HALF;
    ground->pos[1] = -SCENE_SPHERE_RADIUS;
    for (int k = 0; k < 3; k++)
        in->albedo[k] = ground->albedo[k] = 1.0f;
    /* The light straight above the sphere: its shadow falls around the
     * point where the sphere touches the ground. */
    s->light_volume = (struct scene_box){{0.0f, 3.0f, 0.0f}, {0.0f, 3.0f, 0.0f}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    s->sky = true;
    set_pose(s, 0.0f, 2.6f, 4.2f, 0.0f, -0.3f, 0.0f, 40.0f);
    if (!scene_place_lights(s, 0.0f))
        return false;
    white_lights(s, 1.0f);
    return true;
}

/* plane: one flat ground that fills the frame, seen from above at a slant:
 * every pixel holds the same surface, so an MSAA edge pass finds no edge
 * (tests/e2e/e2e_msaa.py), while lights close over it vary its shading. */
static bool build_plane(struct scene *s)
{
    if (!alloc_instances(s, 1))
        return false;
    struct scene_instance *ground = &s->instances[0];
    ground->mesh = SCENE_MESH_PLANE;
    ground->scale = 40.0f / SCENE_PLANE_HALF;
    ground->albedo[0] = ground->albedo[1] = ground->albedo[2] = 0.7f;
    s->light_volume = (struct scene_box){{-3.0f, 0.6f, -3.0f}, {3.0f, 1.2f, 3.0f}};
    s->light_orbit_plane = SCENE_ORBIT_XZ;
    set_pose(s, 0.0f, 6.0f, 2.0f, 0.0f, 0.0f, 0.0f, 40.0f);
    return scene_place_lights(s, 0.5f);
}

bool scene_build_preset(struct scene *s, bool *materials_set)
{
    *materials_set = false;
    switch (s->spec.preset) {
    case SCENE_PRESET_GRID:
        return build_grid(s);
    case SCENE_PRESET_LIGHTS:
        return build_lights(s);
    case SCENE_PRESET_TEAPOTS:
        *materials_set = true;
        return build_teapots(s);
    case SCENE_PRESET_CHART:
        *materials_set = true;
        return build_chart(s);
    case SCENE_PRESET_SPHERE:
        return build_sphere(s);
    case SCENE_PRESET_PLANE:
        return build_plane(s);
    case SCENE_PRESET_TEXTURED:
        return false; /* built through the asset path (scene_asset.c) */
    }
    return false;
}
