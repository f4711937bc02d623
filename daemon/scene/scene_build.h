#ifndef SHADEBENCH_SCENE_BUILD_H
#define SHADEBENCH_SCENE_BUILD_H

/* The steps of scene_init, shared by the files of daemon/scene only (the
 * rest of the daemon reads scene.h). GL-free; a scene being built belongs
 * to the one thread building it. */

#include <stdint.h>

#include "daemon/scene/scene.h"
#include "daemon/scene/scene_math.h"

/* Object-space sizes of the meshes (presets.c), known before the meshes
 * are built (the sphere's tessellation depends on where objects stand). */
extern const float SCENE_SPHERE_RADIUS, SCENE_CUBE_HALF, SCENE_PLANE_HALF;
/* The teapot mesh's half extents at scale 1 (x towards the spout, y up). */
extern const float SCENE_TEAPOT_HALF[3];

/* presets.c: instances (grouped by mesh, materials unset), the light
 * volume, the lights (through scene_place_lights) and the static pose.
 * Returns false when out of memory. */
bool scene_build_preset(struct scene *s, bool *materials_set);

/* scene_asset.c: instances, meshes, light volume, lights and static pose
 * from s->asset (set), as scene_build_preset does for a preset; the meshes
 * are built here too (scene_init builds only the procedural ones). */
bool scene_build_asset(struct scene *s, char *err, size_t errlen);

/* lights.c: allocates and places spec.lights lights in s->light_volume
 * with spec.light_layout, each circling its centre at radius orbit when the
 * scene is dynamic. */
bool scene_place_lights(struct scene *s, float orbit);

/* lights.c: with spec.sun, appends the directional light (after the
 * preset's own, whose colours the presets may have changed). */
bool scene_add_sun(struct scene *s);

/* lights.c: appends scene.light_rig's lights, last, in glTF's falloff
 * (needs the bounds for the cut-off of lights without a range). */
bool scene_add_rig(struct scene *s);

/* lights.c: a glTF light's influence radius: its range, or without one
 * where its radiance off a white surface falls below SCENE_LIGHT_CUTOFF
 * (at least reach, a distance that covers the scene). */
float scene_gltf_light_radius(float intensity, const float color[3], float range, float reach);

/* materials.c: each instance's material from spec.materials and the
 * spec's material values; "preset" keeps what the preset set when it set
 * materials (materials_set), else it is "uniform". */
void scene_assign_materials(struct scene *s, bool preset_set);

/* camera.c: the orbit and flythrough parameters from the bounds and the
 * static pose (needs instances, bounds and rig.eye/target/fovy/near/far). */
void scene_rig_derive(struct scene *s);

/* camera.c: scene.camera's pose, when given, over the static pose (needs
 * the bounds: derived near and far planes reach them). */
void scene_apply_pose(struct scene *s);

/* tessellation.c: s->sphere_segments from the spec, or for "auto" from the
 * largest sphere on screen over the camera path (needs the rig). */
void scene_choose_segments(struct scene *s);

/* mover.c: with spec.mover, inserts the moving sphere after the last
 * sphere instance (instances stay grouped by mesh) and sets its path
 * across s->objects (needs the bounds). Returns false when out of memory. */
bool scene_add_mover(struct scene *s);

/* Column-major 4x4 helpers (camera.c). */
void scene_mat4_mul(float out[16], const float a[16], const float b[16]);
void scene_mat4_transform(const float m[16], const float p[3], float w, float out[4]);

#endif
