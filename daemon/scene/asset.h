#ifndef SHADEBENCH_ASSET_H
#define SHADEBENCH_ASSET_H

/* An imported glTF 2.0 asset as the renderer needs it, GL-free, and the
 * cache file it lives in between the upload and the jobs that render it.
 *
 * The glTF file itself is never parsed inside the daemon: at upload the
 * converter (shadebench-asset, daemon/assets/, linking assimp, libpng and
 * libjpeg) runs as a child process under memory and time limits, checks the
 * file, imports it and writes this cache file, STATE/assets/SHA256.sbasset.
 * A job's scene reads only the cache (asset_file_read), whose reader checks
 * every count and offset against the file's length and the limits, so a
 * damaged cache is an error, never a crash.
 *
 * What the cache holds is flat and ready to draw:
 *  - every mesh primitive instanced by a node, its vertices transformed to
 *    world space by the node's matrix (normals by its inverse transpose,
 *    tangents by the matrix; handedness kept in tangent w): an asset mesh is
 *    one object drawn once, at the origin, scale 1;
 *  - uv0 the material's texture coordinates (TEXCOORD_0), uv1 a unique
 *    parametrisation in [0, 1] for object-space shading: the file's
 *    TEXCOORD_1 when it has one, else charts the converter packed;
 *  - images decoded to 8-bit RGBA, the colour space chosen by the slot that
 *    samples them (base colour and emissive sRGB, the rest linear);
 *  - KHR_lights_punctual lights and the cameras in world space.
 * GL-free; an asset belongs to the thread that read it, and reading a
 * finished asset is safe from any number of threads. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum asset_alpha_mode { ASSET_ALPHA_OPAQUE, ASSET_ALPHA_MASK, ASSET_ALPHA_BLEND };
enum asset_light_type { ASSET_LIGHT_POINT, ASSET_LIGHT_SPOT, ASSET_LIGHT_DIRECTIONAL };
enum asset_texture_slot {
    ASSET_TEX_BASE_COLOR,         /* sRGB; rgb x base_color, a x base_color[3] */
    ASSET_TEX_METALLIC_ROUGHNESS, /* linear; roughness in g, metallic in b */
    ASSET_TEX_NORMAL,             /* linear; tangent space, scaled by scale */
    ASSET_TEX_OCCLUSION,          /* linear; r, mixed by scale (strength) */
    ASSET_TEX_EMISSIVE,           /* sRGB; rgb x emissive */
    ASSET_TEX_SLOTS
};
extern const char *const asset_texture_slot_names[]; /* "base_color", ... */
extern const char *const asset_alpha_mode_names[];   /* "opaque", "mask", "blend" */
extern const char *const asset_light_type_names[];   /* "point", "spot", "directional" */

enum { ASSET_NAME_MAX = 64 };

struct asset_vertex {
    float pos[3];     /* world space */
    float normal[3];  /* world space, unit */
    float tangent[4]; /* world space xyz, handedness w (+-1) */
    float uv0[2];     /* TEXCOORD_0: the material's */
    float uv1[2];     /* the unique parametrisation, in [0, 1] */
};

/* glTF sampler values (GL enums): wrap 33071 clamp, 33648 mirrored, 10497
 * repeat; filters 9728 nearest, 9729 linear, 9984..9987 mipmap ones. */
struct asset_texture_ref {
    int32_t image;   /* index into images, -1 when the slot has no texture */
    int32_t uv_set;  /* 0 or 1: which vertex uv the slot reads */
    uint32_t wrap_s, wrap_t, min_filter, mag_filter;
    float scale;     /* normal: normalTexture.scale; occlusion: strength; else 1 */
};

struct asset_material {
    char name[ASSET_NAME_MAX];
    float base_color[4]; /* linear RGBA factor */
    float metallic, roughness;
    float emissive[3];   /* linear factor */
    enum asset_alpha_mode alpha_mode;
    float alpha_cutoff;  /* mask only; glTF's default 0.5 */
    bool double_sided;
    struct asset_texture_ref tex[ASSET_TEX_SLOTS];
};

struct asset_image {
    char name[ASSET_NAME_MAX];
    uint32_t width, height;
    uint8_t *rgba; /* width * height * 4 bytes, rows top to bottom as stored in the file */
};

struct asset_mesh {
    char name[ASSET_NAME_MAX];
    int32_t material; /* index into materials; -1: glTF's default material */
    uint32_t vertex_count, index_count;
    struct asset_vertex *vertices;
    uint32_t *indices; /* triangles; every index < vertex_count */
    bool uv1_from_file;      /* else the converter's charts */
    bool tangents_from_file; /* else generated (assimp's CalcTangentSpace from uv0, or any
                              * unit tangent perpendicular to the normal where there is no uv0) */
    float box_min[3], box_max[3];
    /* uv1's share of [0, 1]^2 that no triangle covers (gutters, chart
     * packing): the texels object-space shading allocates and never uses. */
    float uv1_waste;
};

struct asset_light {
    char name[ASSET_NAME_MAX];
    enum asset_light_type type;
    float color[3];  /* linear, as the file gives it */
    float intensity; /* candela (point, spot) or lux (directional), as the file gives it */
    float range;     /* 0: the file gives none (infinite) */
    float inner_cone, outer_cone; /* spot, radians */
    float position[3], direction[3]; /* world space; direction unit, the way the light shines */
};

struct asset_camera {
    char name[ASSET_NAME_MAX];
    bool perspective; /* else orthographic: */
    /* Perspective: yfov (radians) and aspect (0: the file gives none).
     * Orthographic: yfov holds ymag (the half-height) and aspect xmag /
     * ymag, so that the cache's records stay as they were. zfar 0:
     * infinite. */
    float yfov, znear, zfar, aspect;
    float eye[3], forward[3], up[3]; /* world space, unit forward and up */
};

struct asset {
    struct asset_mesh *meshes;
    struct asset_material *materials;
    struct asset_image *images;
    struct asset_light *lights;
    struct asset_camera *cameras;
    uint32_t mesh_count, material_count, image_count, light_count, camera_count;
    float box_min[3], box_max[3]; /* every mesh, world space */
    /* What the converter met and does not render (skins, morph targets,
     * animations, extensions it does not know, texture transforms...): one
     * short phrase each, NUL-terminated strings. */
    char **ignored;
    uint32_t ignored_count;
};

/* What an asset may take; the converter refuses an asset over any of them
 * (naming the limit), and the cache reader too. Shown in /v1/info. */
struct asset_limits {
    uint64_t max_file_bytes;           /* the uploaded file */
    uint64_t max_vertices;             /* all meshes together */
    uint64_t max_indices;              /* all meshes together */
    uint64_t max_texture_pixels;       /* all images together */
    uint32_t max_texture_edge;         /* one image's width or height */
    uint32_t max_meshes, max_materials, max_images, max_lights, max_cameras;
};

/* The daemon's defaults: 256 MiB files, 16 M vertices and 48 M indices,
 * 256 M texture pixels (1 GiB decoded), 8192-texel edges, 65,536 meshes,
 * 4,096 materials and images, 1,024 lights and cameras. */
void asset_limits_defaults(struct asset_limits *lim);
json_t *asset_limits_to_json(const struct asset_limits *lim);

/* The cache file: writes a into path (through a temporary and a rename, so
 * a reader never sees half a file). */
bool asset_file_write(const struct asset *a, const char *path, char *err, size_t errlen);
/* Reads a cache file, checking it against lim; out is finished on failure. */
bool asset_file_read(struct asset *out, const char *path, const struct asset_limits *lim,
                     char *err, size_t errlen);
/* The same from memory (the fuzz target's entry). */
bool asset_file_parse(struct asset *out, const void *data, size_t len,
                      const struct asset_limits *lim, char *err, size_t errlen);
/* Frees what a read or the converter allocated; takes a zeroed or finished
 * asset. */
void asset_finish(struct asset *a);

/* What the loader found, for PUT and GET /v1/assets/NAME: meshes,
 * triangles, vertices, materials (alpha modes, which slots have textures),
 * textures and their sizes, lights by type, cameras by name, bounds, uv1
 * (from the file or generated, and the texel waste), ignored features. New
 * reference, or NULL when out of memory. */
json_t *asset_describe(const struct asset *a);

#endif
