/* The scene presets: what objects stand where, the volume the lights fill
 * and the camera's static pose.
 *  - grid: the thesis scene (chapter 3.1.1), unchanged to the bit;
 *  - lights: the many-lights scene of the tiled and clustered shading
 *    papers: objects on a ground plane, lights spread through the volume
 *    above it, seen from a raised camera that keeps most of them on screen. */
#include <math.h>
#include <stdlib.h>

#include "daemon/scene/scene_build.h"

const float SCENE_SPHERE_RADIUS = 0.8f, SCENE_CUBE_HALF = 0.65f, SCENE_PLANE_HALF = 1.0f;

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

bool scene_build_preset(struct scene *s)
{
    switch (s->spec.preset) {
    case SCENE_PRESET_GRID:
        return build_grid(s);
    case SCENE_PRESET_LIGHTS:
        return build_lights(s);
    }
    return false;
}
