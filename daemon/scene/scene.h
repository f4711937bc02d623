#ifndef SHADEBENCH_SCENE_H
#define SHADEBENCH_SCENE_H

/* The procedural scene (GL-free): instances, lights and camera as pure
 * functions of the scene spec and the frame index. Never wall-clock time. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/scene/scene_spec.h"
#include "daemon/scene/mesh.h"

enum scene_mesh { SCENE_MESH_SPHERE, SCENE_MESH_CUBE, SCENE_MESH_COUNT };

struct scene_instance {
    float pos[3];
    float scale;
    float albedo[3];
    enum scene_mesh mesh;
};

struct scene_light {
    float centre[3];
    float orbit;  /* circle radius in the XY plane around centre */
    float radius; /* influence ends here: attenuation is exactly 0 beyond */
    float color[3];
    int period;   /* frames per revolution */
    int phase;    /* frames */
};

struct scene {
    struct scene_spec spec;
    struct mesh meshes[SCENE_MESH_COUNT];
    struct scene_instance *instances;
    int instance_count;
    int mesh_instance_count[SCENE_MESH_COUNT]; /* instances are grouped by mesh */
    struct scene_light *lights;
    int light_count;
    float eye[3], target[3], fovy_deg, near_z, far_z;
    float view[16], proj[16], view_proj[16]; /* column-major */
};

bool scene_create(struct scene *out, const struct scene_spec *spec);
void scene_finish(struct scene *s);

/* World-space light position at frame (any integer, negatives included). */
void scene_light_position(const struct scene *s, int light, int64_t frame,
                          float out[3]);

/* Bounding sphere of instance i in world space. */
float scene_instance_bound(const struct scene *s, int i);
float scene_instance_distance(const struct scene *s, int i);

/* Diameter in pixels of instance i's bounding sphere on screen. */
float scene_projected_diameter(const struct scene *s, int i);

/* Triangles submitted per drawn frame. */
uint64_t scene_triangles(const struct scene *s);

/* True when every instance's bounding sphere lies inside the view frustum. */
bool scene_all_in_view(const struct scene *s);

#endif
