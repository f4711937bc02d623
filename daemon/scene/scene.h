#ifndef SHADEBENCH_SCENE_H
#define SHADEBENCH_SCENE_H

/* The procedural scene (GL-free): instances, materials, lights and camera
 * as pure functions of the scene spec and the frame index, never of the
 * clock. A built scene is read-only: any number of threads may query it at
 * once; scene_init and scene_finish need the scene to themselves. */

#include <jansson.h>
#include <stdbool.h>
#include <stdint.h>

#include "daemon/scene/scene_spec.h"
#include "daemon/scene/mesh.h"
#include "daemon/scene/scene_math.h"

struct asset;

/* Instances are grouped by mesh in index order, one instanced draw each.
 * The procedural meshes come first, at these indices (empty when unused);
 * an asset's meshes follow, from SCENE_MESH_PROCEDURAL on, one instance
 * each. */
enum scene_mesh {
    SCENE_MESH_SPHERE, SCENE_MESH_CUBE, SCENE_MESH_PLANE, SCENE_MESH_TEAPOT, SCENE_MESH_PROCEDURAL
};
extern const char *const scene_mesh_names[]; /* "sphere", "cube", "plane", "teapot" */

/* Per-instance material, uploaded beside the albedo (shaders/common/
 * scene_data.glsl: instance_material()). metallic and roughness are carried
 * for the lighting models to come; Phong reads specular and shininess. */
struct scene_material {
    float specular, shininess, metallic, roughness;
};

struct scene_instance {
    float pos[3];
    float scale; /* uniform: object-space normals stay world-space normals */
    float albedo[3];
    int mesh; /* index into scene.meshes: enum scene_mesh, or an asset's mesh */
    /* The constant fallback (albedo above: the base colour factor; metallic
     * and roughness the factors) for code that reads no textures. */
    struct scene_material material;
    /* Index into the scene's asset's materials; -1 for the procedural
     * instances and for an asset mesh with glTF's default material. */
    int asset_material;
};

/* The plane a dynamic light circles in around its centre. */
enum scene_orbit_plane { SCENE_ORBIT_XY, SCENE_ORBIT_XZ };

/* Point lights light every direction; a spot light only its cone (full
 * inside cos_inner, fading to 0 at cos_outer, glTF's smooth falloff); a
 * directional light has no position and reaches everything (radius is
 * unused, and the culling techniques bin it into every cell). */
enum scene_light_type { SCENE_LIGHT_POINT, SCENE_LIGHT_SPOT, SCENE_LIGHT_DIRECTIONAL };
extern const char *const scene_light_type_names[]; /* "point", "spot", "directional" */

/* Generated lights (scene.light_type "spot", scene.sun; lights.c): a
 * generated spot's inner half-angle is this share of its outer one, and the
 * sun shines along SCENE_SUN_DIRECTION (unit: down, a little towards -x and
 * -z, so that the objects' sides facing the camera are lit) with
 * SCENE_SUN_COLOR times scene.light_intensity. */
#define SCENE_SPOT_INNER_RATIO 0.75
extern const float SCENE_SUN_DIRECTION[3];
extern const float SCENE_SUN_COLOR[3];

/* How a point or spot light's strength falls with distance d:
 *  - WINDOW, the presets' (the thesis's): (1 - d^2 / radius^2)^2, colour
 *    the irradiance of a surface facing it up close;
 *  - GLTF, KHR_lights_punctual's: 1 / d^2 times, with a range, the window
 *    clamp(1 - (d / range)^4, 0, 1); colour in candela (lux for a
 *    directional light) over pi. Asset scenes' lights and scene.light_rig
 *    use it, so that a glTF viewer given the same lights draws the same
 *    image. Without a range the light is cut at radius, where its
 *    radiance off a white surface falls below SCENE_LIGHT_CUTOFF. */
enum scene_light_falloff { SCENE_FALLOFF_WINDOW, SCENE_FALLOFF_GLTF };
#define SCENE_LIGHT_CUTOFF (1.0 / 1024.0)

struct scene_light {
    float centre[3];
    float orbit;  /* circle radius around centre, in the scene's orbit plane */
    float radius; /* influence ends here: attenuation is exactly 0 beyond */
    float color[3];
    int period;   /* frames per revolution */
    int phase;    /* frames */
    enum scene_light_type type; /* zero: point, what every preset places */
    float direction[3];         /* spot and directional: unit, the way the light shines */
    float cos_inner, cos_outer; /* spot: cosines of the cone's inner and outer angles */
    enum scene_light_falloff falloff;
    float range;     /* GLTF: the file's or rig's range, 0 for none (radius is then the cut-off) */
    /* GLTF: what the light is in glTF's terms (colour 0..1 and intensity
     * in candela or lux; colour above is their product over pi times
     * scene.light_intensity), for the result's light list. */
    float gltf_color[3], gltf_intensity;
};

struct scene_box {
    float min[3], max[3];
};

/* One frame's camera. Matrices are column-major with GL conventions (a
 * right-handed view looking down -z, clip z in [-w, w]). */
struct scene_camera {
    float eye[3], target[3], up[3], fovy_deg, near_z, far_z;
    bool orthographic;  /* then xmag and ymag, the view's half-extents, replace fovy_deg */
    float xmag, ymag;
    float view[16], proj[16], view_proj[16], inv_view[16], inv_proj[16];
};

/* What the camera paths are derived from (scene_init fills it). */
struct scene_rig {
    float eye[3], target[3];   /* the static pose: the preset's own, the asset's or scene.camera's */
    float up[3];               /* the static pose's up ({0, 0, 0}: +y) */
    float fovy_deg, near_z, far_z;
    bool orthographic;         /* the static pose is orthographic (never moves): */
    float xmag, ymag;          /* its half-extents */
    float centre[3];           /* orbit: circles this, the bounds' centre... */
    float orbit_distance;      /* ...at a distance that keeps the bounds in view, */
    float orbit_elevation;     /* the static pose's elevation (radians), */
    float orbit_azimuth;       /* starting from its azimuth (radians) */
    float orbit_far;           /* far plane that reaches past the bounds */
    float fly_radius[2];       /* flythrough: ellipse semi-axes in x and z, */
    float fly_height[2];       /* eye height band above the objects, */
    float fly_look_y;          /* and the height it looks down to */
};

struct scene {
    struct scene_spec spec;
    struct mesh *meshes;           /* mesh_count: the procedural ones, then an asset's */
    int mesh_count;
    struct scene_instance *instances;
    int instance_count;
    int *mesh_instance_count;      /* per mesh */
    struct scene_light *lights;
    int light_count;
    enum scene_orbit_plane light_orbit_plane;
    struct scene_box bounds;       /* every instance's bounding sphere */
    struct scene_box objects;      /* the same without the ground plane */
    struct scene_box light_volume; /* where the layout puts light centres */
    struct scene_rig rig;
    int sphere_segments;           /* in use: the spec's, or the one "auto" chose */
    int teapot_segments;           /* per patch edge, likewise (0 without teapots) */
    float teapot_px_per_unit;      /* largest teapot scale on screen, pixels per unit */
    float teapot_error_px;         /* the chosen tessellation's error there */
    /* The preset draws a sky behind its objects (the harness's sky pass,
     * which shows the look's environment: seed 002's skybox). */
    bool sky;
    float sphere_radius_px;        /* largest sphere radius on screen over the camera path */
    float sphere_error_px;         /* the chosen tessellation's silhouette error there */
    /* The frame-0 camera, flat, for the code that reads one fixed camera. */
    float eye[3], target[3], fovy_deg, near_z, far_z;
    float view[16], proj[16], view_proj[16]; /* column-major */
    /* Asset scenes (scene_spec_is_asset): the asset, borrowed from the
     * caller of scene_build (or owned, for the textured preset's synthetic
     * one), and what the scene made of it. NULL for the presets. Instances
     * of asset meshes are ordered opaque, masked, blended (each a run of
     * meshes: asset_mask_first and asset_blend_first are mesh indices), so
     * that a pass can draw the opaque and masked ones and leave the blended
     * for the transparent pass. */
    const struct asset *asset;
    struct asset *owned_asset;
    int asset_mask_first, asset_blend_first;
    int *mesh_asset_index;     /* per scene mesh: the asset's mesh index, -1 procedural */
    int asset_light_count;     /* lights[generated..]: the asset's, after the generated ones */
    int generated_light_count;
    int rig_light_count;       /* scene.light_rig's, the last lights */
    int asset_camera;          /* the asset camera of the static pose, -1: framed from the bounds */
    /* scene.mover (mover.c): the moving sphere's instance (the last of the
     * spheres), -1 without one, and the ends of the segment its centre
     * slides along, there and back every spec.mover_period frames. Its
     * instance's pos is where it stands at frame 0. */
    int mover;
    float mover_from[3], mover_to[3];
};

/* An asset's KHR_lights_punctual lights in the daemon's colour scale
 * (scene_asset.c; docs/scenes.md): SCENE_ASSET_LIGHT_UNIT candela (at 1 m)
 * or lux make colour 1; a point or spot light without a range reaches as
 * far as its inverse-square irradiance stays above
 * SCENE_ASSET_LIGHT_FLOOR_LUX. */
#define SCENE_ASSET_LIGHT_UNIT 100.0
#define SCENE_ASSET_LIGHT_FLOOR_LUX 1.0

/* Builds the scene of spec into caller-owned memory. On failure (out of
 * memory) the scene is left finished. Not for scene.asset specs (they need
 * the asset: scene_build). */
bool scene_init(struct scene *out, const struct scene_spec *spec);
/* The same for any spec: asset is the cache's asset for scene.asset (the
 * caller keeps it alive until scene_finish), NULL otherwise. False with err
 * naming what is wrong (an asset field, scene.asset_camera, memory); the
 * scene is then left finished. */
bool scene_build(struct scene *out, const struct scene_spec *spec, const struct asset *asset,
                 char *err, size_t errlen);
/* True when the scene has blended (glTF "BLEND") materials: the harness's
 * transparent pass draws them. */
bool scene_has_blended(const struct scene *s);
/* Frees what scene_init allocated; takes a zeroed or finished scene. */
void scene_finish(struct scene *s);

/* World-space light position at frame (any integer, negatives included). */
void scene_light_position(const struct scene *s, int light, int64_t frame,
                          float out[3]);

/* The camera at frame (any integer): a pure function of the frame index,
 * periodic with spec.camera_period for moving paths. */
void scene_camera_at(const struct scene *s, int64_t frame, struct scene_camera *out);
/* True when the camera path moves (every frame needs its own camera). */
bool scene_camera_moves(const struct scene *s);

/* Instance i's world position (xyz) and scale (w) at frame (any integer):
 * its pos and scale, but for the mover, which slides (mover.c). */
void scene_instance_at(const struct scene *s, int i, int64_t frame, float out[4]);
/* Where the mover (scene.mover) stands on a width x height image seen by
 * camera c at frame: its centre in window pixels (x, y from the bottom
 * left) and the semi-major axis of its silhouette (scene_sphere_radius_px);
 * false without a mover or when it lies behind the camera. */
bool scene_mover_disc(const struct scene *s, int64_t frame, const struct scene_camera *c,
                      int width, int height, float out[3]);

/* Bounding sphere of instance i in world space. */
float scene_instance_bound(const struct scene *s, int i);
/* Distance from the frame-0 eye to instance i's centre. */
float scene_instance_distance(const struct scene *s, int i);

/* Diameter in pixels of instance i's bounding sphere on screen (frame 0). */
float scene_projected_diameter(const struct scene *s, int i);


/* Semi-major axis in pixels of the sphere's projected silhouette (an
 * ellipse) for camera c on a width x height image, exact for a perspective
 * projection; capped at the image diagonal, which a sphere reaching behind
 * the eye counts as. */
float scene_sphere_radius_px(const struct scene_camera *c, int width, int height,
                             const float centre[3], float radius);

/* "auto" teapot tessellation (tessellation.c): s->teapot_segments from the
 * largest teapot on screen over the camera path. */

/* Silhouette error of a sphere tessellated with segments (lat-long, rings
 * = segments / 2), as a fraction of its radius: see tessellation.c. */
double scene_sphere_error(int segments);
/* The coarsest even tessellation from 8 to 256 whose silhouette error at
 * radius_px stays within bound_px (256 when none does). */
int scene_auto_segments(double radius_px, double bound_px);

/* Triangles submitted per drawn frame. */
uint64_t scene_triangles(const struct scene *s);

/* True when instance i's axis-aligned box lies entirely inside camera c's
 * frustum; scene_instances_in_view counts such instances. */
bool scene_instance_in_view(const struct scene *s, int i, const struct scene_camera *c);
int scene_instances_in_view(const struct scene *s, const struct scene_camera *c);
/* True when every instance's bounding sphere lies inside the frame-0 frustum. */
bool scene_all_in_view(const struct scene *s);

/* The scene as built, for the job's result: instances (by mesh), lights
 * (count, layout, radius, volume, how many reach each object, how many are
 * on screen), triangles per frame, the sphere tessellation ("auto": its
 * choice, radius and error), the camera path and the bounds. New reference,
 * or NULL when out of memory. Costs instances x lights distance tests. */
json_t *scene_describe(const struct scene *s);

#endif
