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
 *  - the file's texture coordinate sets as it gives them, uv0 (TEXCOORD_0)
 *    and texcoord1 (TEXCOORD_1), each texture slot naming the set it reads
 *    (its texCoord, KHR_texture_transform's override applied) and its
 *    KHR_texture_transform; apart from them uv1, a unique parametrisation
 *    in [0, 1] for object-space shading that no material reads: the file's
 *    TEXCOORD_1 where its charts stay inside [0, 1] and do not overlap,
 *    else charts the converter packed (uv1_origin says which, and why);
 *  - COLOR_0 as linear RGBA (1 where the file has none), multiplying the
 *    base colour;
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
    float pos[3];       /* world space */
    float normal[3];    /* world space, unit */
    float tangent[4];   /* world space xyz, handedness w (+-1) */
    float uv0[2];       /* TEXCOORD_0 as the file gives it (0 where absent) */
    float uv1[2];       /* the unique parametrisation, in [0, 1]: object-space shading's */
    float texcoord1[2]; /* TEXCOORD_1 as the file gives it (0 where absent) */
    float color[4];     /* COLOR_0, linear RGBA (1 where absent) */
};

/* KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, the
 * identity where a texture has none. */
struct asset_uv_transform {
    float offset[2];
    float rotation; /* radians, counter-clockwise in uv */
    float scale[2];
};
#define ASSET_UV_IDENTITY {{0.0f, 0.0f}, 0.0f, {1.0f, 1.0f}} /* an initialiser */

/* glTF sampler values (GL enums): wrap 33071 clamp, 33648 mirrored, 10497
 * repeat; filters 9728 nearest, 9729 linear, 9984..9987 mipmap ones. */
struct asset_texture_ref {
    int32_t image;   /* index into images, -1 when the slot has no texture */
    int32_t uv_set;  /* 0 or 1: the file's set the slot reads (uv0 or texcoord1) */
    uint32_t wrap_s, wrap_t, min_filter, mag_filter;
    float scale;     /* normal: normalTexture.scale; occlusion: strength; else 1 */
    struct asset_uv_transform transform;
};

/* True where t is not the identity. */
bool asset_uv_transform_used(const struct asset_uv_transform *t);
/* The transform as the 2x3 matrix uv' = (m[0] u + m[1] v + m[2],
 * m[3] u + m[4] v + m[5]), as KHR_texture_transform composes it. */
void asset_uv_transform_matrix(const struct asset_uv_transform *t, float m[6]);

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

/* Where a mesh's uv1 comes from: the file's TEXCOORD_1, or charts the
 * converter generated because the file has no TEXCOORD_1, or its
 * TEXCOORD_1 leaves [0, 1], or its charts overlap (two triangles on the
 * same texels: object-space shading would light both with one texel). */
enum asset_uv1_origin {
    ASSET_UV1_FILE,
    ASSET_UV1_GENERATED_NO_SET,
    ASSET_UV1_GENERATED_OUTSIDE,
    ASSET_UV1_GENERATED_OVERLAP,
};
extern const char *const asset_uv1_origin_reasons[]; /* a phrase each, "" for the file's */

struct asset_mesh {
    char name[ASSET_NAME_MAX];
    int32_t material; /* index into materials; -1: glTF's default material */
    uint32_t vertex_count, index_count;
    struct asset_vertex *vertices;
    uint32_t *indices; /* triangles; every index < vertex_count */
    enum asset_uv1_origin uv1_origin;
    bool tangents_from_file; /* else generated (assimp's CalcTangentSpace from uv0, the
                              * converter's from TEXCOORD_1 where the normal texture reads
                              * set 1, or any unit tangent perpendicular to the normal where
                              * there is no uv set) */
    bool has_uv0, has_texcoord1, has_color; /* the file gives TEXCOORD_0, TEXCOORD_1, COLOR_0 */
    float box_min[3], box_max[3];
    /* uv1's share of [0, 1]^2 that no triangle covers (gutters, chart
     * packing): the texels object-space shading allocates and never uses. */
    float uv1_waste;
    /* The file's TEXCOORD_1, where it has one inside [0, 1]: the share of
     * the texels its triangles cover that more than one covers (0 where it
     * was not measured). */
    float texcoord1_overlap;
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
    uint32_t max_nodes; /* the file's nodes (assimp takes about 2.4 KB for each) */
    uint64_t max_cache_bytes; /* the cache file the conversion writes (and a job reads whole) */
};

/* The daemon's defaults: 256 MiB files, 16 M vertices and 48 M indices,
 * 256 M texture pixels (1 GiB decoded), 8192-texel edges, 65,536 meshes,
 * 4,096 materials and images, 1,024 lights and cameras. */
void asset_limits_defaults(struct asset_limits *lim);
json_t *asset_limits_to_json(const struct asset_limits *lim);

/* The cache file: writes a into path (through a temporary and a rename, so
 * a reader never sees half a file). */
bool asset_file_write(const struct asset *a, const char *path, char *err, size_t errlen);
/* The bytes asset_file_write would write, counted without writing: the
 * converter checks them against its limit and the disk's room first. */
uint64_t asset_file_size(const struct asset *a);
/* Reads a cache file, checking it against lim; out is finished on failure. */
bool asset_file_read(struct asset *out, const char *path, const struct asset_limits *lim,
                     char *err, size_t errlen);
/* False when path is missing or was written in another layout than this
 * reader's (an older shadebench's cache: its upload is converted again). */
bool asset_file_is_current(const char *path);
/* The same from memory (the fuzz target's entry). */
bool asset_file_parse(struct asset *out, const void *data, size_t len,
                      const struct asset_limits *lim, char *err, size_t errlen);
/* Frees what a read or the converter allocated; takes a zeroed or finished
 * asset. */
void asset_finish(struct asset *a);

/* What the loader found, for PUT and GET /v1/assets/NAME: meshes,
 * triangles, vertices, materials (alpha modes, which slots have textures),
 * textures and their sizes, lights by type, cameras by name, bounds, uv1
 * (from the file or generated, and the texel waste), ignored features. The
 * per-mesh, per-material and per-texture lists hold the first
 * ASSET_DESCRIBE_LIST_MAX (the rest counted in the totals and in
 * mesh_list_omitted, materials_omitted, textures_omitted), so that the
 * description of an asset within the limits stays small (60,000 meshes
 * made 11 MB, past what the daemon reads of the converter's answer). New
 * reference, or NULL when out of memory. */
#define ASSET_DESCRIBE_LIST_MAX 1024
json_t *asset_describe(const struct asset *a);

#endif
