#ifndef SHADEBENCH_SCENE_SPEC_H
#define SHADEBENCH_SCENE_SPEC_H

/* The job's "scene" object: presets and their options, defaults, parsing
 * with field-naming errors, and the JSON written back. GL-free; any thread
 * (the name tables are constant). */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"

enum scene_preset {
    SCENE_PRESET_GRID, SCENE_PRESET_LIGHTS,
    SCENE_PRESET_TEAPOTS, /* seed 002: eight teapots, a container, ground and sky */
    SCENE_PRESET_CHART,   /* spheres by metallic (rows) and roughness (columns) */
    SCENE_PRESET_SPHERE,  /* one sphere in the spec's material: the furnace test's */
    SCENE_PRESET_PLANE,   /* one flat ground filling the frame: no edges (MSAA's test) */
    /* A textured glTF-style scene built in memory through the asset path
     * (daemon/scene/asset_synthetic.c): every material feature, one mesh
     * each, so that every technique's textured and blended paths are tested
     * without an uploaded file. */
    SCENE_PRESET_TEXTURED,
};
enum scene_light_layout {
    SCENE_LAYOUT_HALTON,    /* the thesis's low-discrepancy spread (Halton 2, 3, 5) */
    SCENE_LAYOUT_UNIFORM,   /* independent hashed positions, uniform in the volume */
    SCENE_LAYOUT_GRID,      /* a regular lattice filling the volume */
    SCENE_LAYOUT_CLUSTERED, /* tight groups: hot spots where many lights overlap */
};
enum scene_materials {
    SCENE_MATERIALS_UNIFORM, /* every object gets scene.specular, .shininess, ... */
    SCENE_MATERIALS_VARIED,  /* a deterministic per-object spread around them */
    SCENE_MATERIALS_PRESET,  /* the preset's own (teapots, chart); uniform elsewhere */
};
enum scene_camera_path { SCENE_CAMERA_STATIC, SCENE_CAMERA_ORBIT, SCENE_CAMERA_FLYTHROUGH };

/* NULL-terminated, indexed by the enums above; the JSON spelling. */
extern const char *const scene_preset_names[];
extern const char *const scene_layout_names[];
extern const char *const scene_materials_names[];
extern const char *const scene_camera_names[];

enum {
    SCENE_MAX_LIGHTS = 65536,
    SCENE_SEGMENTS_AUTO = 0, /* sphere_segments "auto" */
    SCENE_MAX_CAMERA_PERIOD = 1000000,
    SCENE_TEAPOT_SEGMENTS_AUTO = 0, /* teapot_segments "auto" */
    SCENE_ASSET_NAME_MAX = 128,
    /* scene.lights "auto": an asset scene's default, resolved when the
     * scene is built (0 generated lights when the asset has lights of its
     * own, else SCENE_ASSET_DEFAULT_LIGHTS). */
    SCENE_LIGHTS_AUTO = -1,
    SCENE_ASSET_DEFAULT_LIGHTS = 16,
    SCENE_ASSET_CAMERA_MAX = 64,
    SCENE_MAX_MOVER_PERIOD = 1000000,
    /* scene.light_rig: explicit lights, at most this many. */
    SCENE_RIG_MAX_LIGHTS = 64,
};

/* scene.light_radius "auto" (asset scenes): generated lights reach as far
 * as the asset's size asks (scene_asset.c). */
#define SCENE_LIGHT_RADIUS_AUTO 0.0

/* scene.camera given as a pose (scene_camera_spec.c): eye, target and up,
 * a vertical field of view or orthographic half-extents, optional near and
 * far planes (0: derived from the scene's bounds). Replaces the preset's or
 * the asset's static pose; a perspective pose may still orbit or fly. */
struct scene_camera_spec {
    bool given;
    double eye[3], target[3], up[3];
    double yfov_deg;       /* perspective */
    bool orthographic;
    double xmag, ymag;     /* orthographic half-width and half-height (glTF's); xmag 0:
                            * ymag times the image's aspect */
    double near_z, far_z;  /* 0: derived */
};

/* One explicit light of scene.light_rig, in glTF KHR_lights_punctual's
 * terms and units: intensity in candela (point, spot) or lux
 * (directional), colour linear, range 0 for none (inverse square to the
 * cut-off, scene.h: SCENE_LIGHT_CUTOFF), cone half-angles in degrees. */
struct scene_rig_light {
    int type; /* enum scene_light_type (scene.h) */
    double position[3], direction[3], color[3];
    double intensity, range, inner_cone_deg, outer_cone_deg;
};

struct scene_spec {
    enum scene_preset preset;
    int lights;
    bool dynamic;
    int width, height;
    int sphere_segments;          /* even 8..256 (rings = segments / 2), or SCENE_SEGMENTS_AUTO */
    double tessellation_error_px; /* silhouette error "auto" keeps under, in pixels */
    int teapot_segments;          /* per Bezier patch edge, 1..64, or SCENE_TEAPOT_SEGMENTS_AUTO */
    double light_speed;           /* scales how fast dynamic lights circle (1 = default) */
    double light_radius;          /* influence radius of every light */
    double light_intensity;       /* scales every light's colour */
    enum scene_light_layout light_layout;
    /* What the generated lights are (enum scene_light_type, scene.h; the
     * presets place point lights unless "light_type" says "spot": each a
     * spot pointing straight down, with outer half-angle spot_angle_deg and
     * inner SCENE_SPOT_INNER_RATIO of it). sun adds one directional light
     * after them (scene.h: SCENE_SUN_DIRECTION, SCENE_SUN_COLOR). */
    int light_type;
    double spot_angle_deg;
    bool sun;
    enum scene_materials materials;
    double specular, shininess, metallic, roughness;
    enum scene_camera_path camera;
    int camera_period; /* frames per loop of a moving camera */
    /* "asset": a stored glTF asset's name (daemon/scene/asset.h); empty for
     * the presets. Its SHA-256 is filled in when the job is accepted (the
     * HTTP side looks the name up), so that the result names the exact file
     * and a gate never compares two different scenes. */
    char asset[SCENE_ASSET_NAME_MAX + 1];
    char asset_sha256[65];
    /* What the asset takes in memory while a job renders it (its cache read
     * in, its textures and geometry uploaded), filled in with the hash when
     * the job is accepted, for the job's cost (daemon/spec/job_cost.h); 0
     * until then. Not part of the spec's JSON. */
    double asset_bytes;
    /* Asset scenes (scene.asset or the textured preset): which of the
     * asset's cameras the static pose is ("" its first; digits an index,
     * else a name), whether its KHR_lights_punctual lights are used, and
     * whether normal textures are read (false: every material's normal
     * texture is ignored, to show what they cost and change). */
    char asset_camera[SCENE_ASSET_CAMERA_MAX + 1];
    bool asset_lights;
    bool normal_maps;
    /* "mover": a sphere that slides to and fro across the objects, once
     * there and back every mover_period frames (daemon/scene/mover.c):
     * object motion, for motion vectors and TAA's ghosting. Procedural
     * presets only. */
    bool mover;
    int mover_period;
    /* scene.camera as a pose, when given (else the preset's or asset's). */
    struct scene_camera_spec view;
    /* scene.light_rig: lit after the generated lights, the sun and the
     * asset's (docs/scenes.md, "Light rigs"). */
    int rig_count;
    struct scene_rig_light rig[SCENE_RIG_MAX_LIGHTS];
};

/* True when the scene is built through the asset path (scene.asset, or
 * the textured preset's synthetic asset). */
bool scene_spec_is_asset(const struct scene_spec *s);

/* An asset name: 1 to SCENE_ASSET_NAME_MAX bytes of letters, digits, '.',
 * '_' and '-', not starting with '.'. Safe as a file name. */
bool scene_asset_name_valid(const char *name);

/* The grid preset with every option at its default. */
void scene_spec_defaults(struct scene_spec *s);

/* Sets the options a preset chooses (lights, light_layout, light_radius,
 * materials) to that preset's defaults; the rest are left alone. */
void scene_spec_preset_defaults(struct scene_spec *s, enum scene_preset preset);

/* Applies the "scene" object over the current values (defaults first). A
 * "preset" key is applied first, with its defaults, so that the other keys
 * override them whatever their order. */
bool scene_spec_parse(const json_t *scene, struct scene_spec *s, struct job_error *err);

/* The scene as understood, every option filled in; parsing it gives the
 * same spec back. New reference. */
json_t *scene_spec_to_json(const struct scene_spec *s);

/* scene_camera_spec.c: "camera" as a pose (an object with "eye"), and
 * "light_rig"; their JSON. Called by scene_spec_parse and _to_json. */
bool scene_camera_pose_parse(const json_t *camera, struct scene_spec *s, struct job_error *err);
json_t *scene_camera_pose_to_json(const struct scene_camera_spec *v);
bool scene_light_rig_parse(const json_t *rig, struct scene_spec *s, struct job_error *err);
json_t *scene_light_rig_to_json(const struct scene_spec *s);

#endif
