#ifndef SHADEBENCH_CONVERT_INTERNAL_H
#define SHADEBENCH_CONVERT_INTERNAL_H

/* What the converter's stages share (asset_convert.h is the outside's
 * view): the conversion's context, the checked accessor and primitive
 * records, the JSON readers that name the field they refuse, and each
 * stage's entry points. Stage 1 (the checks) is convert_checks.c, the world
 * matrices convert_matrices.c, the images convert_images.c, the asset built
 * from assimp's meshes and the checked JSON convert_build.c; asset_convert.c
 * runs them in order. Converter process only, single-threaded. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/assets/asset_convert.h"

struct aiScene;

enum {
    MAX_NODE_DEPTH = 256,
    MAX_IGNORED = 64,
    /* Caps on arrays no limit of asset_limits covers, far above real files:
     * they bound the checker's own per-entry tables. */
    MAX_ENTRIES = 1 << 20,
};

struct span {
    const uint8_t *data;
    uint64_t len;
};

struct ctx {
    const struct asset_limits *lim;
    struct asset_convert_error *err;
    json_t *root;
    struct span bin;      /* the GLB BIN chunk, if any */
    bool glb;
    struct span *buffers; /* each buffer's bytes (the BIN chunk or a decoded data URI) */
    uint8_t **owned;      /* decoded data URIs, freed at the end */
    size_t nowned;
    struct span *images;  /* each image's encoded bytes */
    size_t nbuffers, nimages;
    json_t *accessors, *views, *meshes, *nodes, *materials, *textures, *samplers, *lights,
        *cameras, *imgs;
    int *parent;          /* per node, -1 for none */
    int *level, *top;     /* per node: 1 for a root, its root (check_graph) */
    bool *in_scene;       /* per node (and one more): drawn by the scene (check_graph) */
    int64_t *index_max;   /* per accessor: its largest index once read, else -1 */
    char *ignored[MAX_IGNORED];
    uint32_t nignored;
};

struct accessor {
    struct span view; /* the bufferView's bytes */
    uint64_t offset, count, stride;
    int64_t ctype;
    int ncomp;
};


struct prim_info {
    uint64_t vertices, indices; /* as the file has them */
    uint64_t triangles;
    bool has_uv1, has_tangent, has_normal, triangles_mode;
    int64_t uv_accessor[2]; /* TEXCOORD_0 and _1's accessors, -1 for none */
    int64_t color_accessor; /* COLOR_0's, -1 for none */
};

/* ---- the context and JSON helpers (convert_ctx.c) ---- */

/* Records the first failure (status, field, message); always false. */
bool fail(struct ctx *c, int status, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Adds a line to what the asset reports as ignored (once each). */
void ignore(struct ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
bool opt_array(struct ctx *c, json_t *obj, const char *key, const char *field, json_t **out);
bool get_int(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
             int64_t min, int64_t max, int64_t def, int64_t *out);
bool get_index(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
               size_t n, int64_t *out);
double num_or(json_t *obj, const char *key, double def);
bool get_floats(struct ctx *c, json_t *obj, const char *key, const char *field, size_t n,
                double *out);
void utf8_trim(char *s);
void copy_name(char *dst, json_t *obj, const char *fallback);

/* ---- stage 1: the checks (convert_checks.c) ---- */

bool check_container(struct ctx *c, const uint8_t *data, size_t len);
bool check_asset_and_extensions(struct ctx *c);
bool check_buffers(struct ctx *c);
bool check_accessors(struct ctx *c);
/* Accessor i checked against its bufferView, described in a. */
bool check_accessor(struct ctx *c, size_t i, struct accessor *a);
/* The node forest, its depth, and which nodes the scene draws (in_scene),
 * in time linear in the nodes. */
bool check_graph(struct ctx *c, int64_t *scene_index);
bool check_images(struct ctx *c);
bool check_textures_materials(struct ctx *c);
bool check_lights_cameras(struct ctx *c);
/* Counts what the scene instances against the limits; infos[m][p] per
 * primitive, allocated here, freed by the caller. */
bool check_meshes(struct ctx *c, struct prim_info ***infos);

/* ---- world matrices, column-major as glTF stores them (convert_matrices.c) ---- */

void node_world(struct ctx *c, int i, double m[16]);
void xform_point(const double m[16], const float in[3], float out[3]);
void xform_dir(const double m[16], const double in[3], double out[3]);
void normalize3(double v[3]);
/* |det| M^-T of m's upper 3x3, column-major (normals), and m's determinant. */
double normal_matrix(const double m[16], double n[9]);
/* n (normal_matrix's) times in: a normal to world space, not renormalised. */
void xform_normal(const double n[9], const double in[3], double out[3]);

/* ---- images (convert_images.c) ---- */

bool is_png(struct span s);
bool is_jpeg(struct span s);
bool image_size(struct span s, uint32_t *w, uint32_t *h);
/* Whether s's bytes can honestly hold a w x h image (a lower bound on its
 * compressed size: deflate's best ratio, a bit per JPEG block) and its JPEG
 * frame type is one we read; else why, for a 400. */
bool image_size_honest(struct span s, uint32_t w, uint32_t h, char *why, size_t cap);
/* Decodes every image the checks passed into a->images. */
bool build_images(struct ctx *c, struct asset *a);

/* ---- building the asset (convert_build.c) ---- */

bool build_materials(struct ctx *c, struct asset *a);
bool build_lights_cameras(struct ctx *c, struct asset *a, const bool *in_scene);
bool build_meshes(struct ctx *c, const struct aiScene *sc, struct prim_info **infos,
                  const bool *in_scene, int64_t scene_index, struct asset *a);

#endif
