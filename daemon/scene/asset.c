#define _POSIX_C_SOURCE 200809L /* mkstemp, fsync, mmap */
/* The imported asset (asset.h): name tables, limits, description, and the
 * cache file. GL-free. The reader treats the file as hostile: every count is
 * checked against the limits and against the bytes left before anything is
 * allocated, every index against what it indexes, every float for being
 * finite, so that a damaged cache is an error naming the damage. */
#include "daemon/scene/asset.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

enum { IGNORED_NAME_MAX = 128 }; /* the longest string the cache holds, with its NUL */

const char *const asset_texture_slot_names[] = {"base_color", "metallic_roughness", "normal",
                                                "occlusion", "emissive"};
const char *const asset_alpha_mode_names[] = {"opaque", "mask", "blend"};
const char *const asset_light_type_names[] = {"point", "spot", "directional"};
const char *const asset_uv1_origin_reasons[] = {
    "", "the file has no TEXCOORD_1", "the file's TEXCOORD_1 leaves [0, 1]",
    "the file's TEXCOORD_1 charts overlap"};

bool asset_uv_transform_used(const struct asset_uv_transform *t)
{
    return t->offset[0] != 0.0f || t->offset[1] != 0.0f || t->rotation != 0.0f ||
           t->scale[0] != 1.0f || t->scale[1] != 1.0f;
}

void asset_uv_transform_matrix(const struct asset_uv_transform *t, float m[6])
{
    /* KHR_texture_transform: translation * rotation * scale, the rotation
     * u' = cos u + sin v, v' = -sin u + cos v as the Khronos sample viewer,
     * three.js and the extension's example (offset [0, 1], rotation pi/2,
     * scale 0.5: the lower left quadrant) have it; the GLSL snippet in the
     * extension's text turns the other way. */
    double c = cos((double)t->rotation), s = sin((double)t->rotation);
    m[0] = (float)(c * t->scale[0]);
    m[1] = (float)(s * t->scale[1]);
    m[2] = t->offset[0];
    m[3] = (float)(-s * t->scale[0]);
    m[4] = (float)(c * t->scale[1]);
    m[5] = t->offset[1];
}

void asset_limits_defaults(struct asset_limits *lim)
{
    lim->max_file_bytes = 256ull << 20;
    lim->max_vertices = 16ull << 20;
    lim->max_indices = 48ull << 20;
    lim->max_texture_pixels = 256ull << 20;
    lim->max_texture_edge = 8192;
    lim->max_meshes = 65536;
    lim->max_materials = 4096;
    lim->max_images = 4096;
    lim->max_lights = 1024;
    lim->max_cameras = 1024;
    /* A million empty nodes (10 MB of GLB) took the converter 2.4 GB in
     * assimp's node tree: 2^18 of them take at most about 630 MB. */
    lim->max_nodes = 1u << 18;
    lim->max_cache_bytes = 2ull << 30;
}

json_t *asset_limits_to_json(const struct asset_limits *lim)
{
    return json_pack("{sI sI sI sI sI sI sI sI sI sI sI sI}",
                     "max_file_bytes", (json_int_t)lim->max_file_bytes,
                     "max_vertices", (json_int_t)lim->max_vertices,
                     "max_indices", (json_int_t)lim->max_indices,
                     "max_texture_pixels", (json_int_t)lim->max_texture_pixels,
                     "max_texture_edge", (json_int_t)lim->max_texture_edge,
                     "max_meshes", (json_int_t)lim->max_meshes,
                     "max_materials", (json_int_t)lim->max_materials,
                     "max_images", (json_int_t)lim->max_images,
                     "max_lights", (json_int_t)lim->max_lights,
                     "max_cameras", (json_int_t)lim->max_cameras,
                     "max_nodes", (json_int_t)lim->max_nodes,
                     "max_cache_bytes", (json_int_t)lim->max_cache_bytes);
}

void asset_finish(struct asset *a)
{
    if (!a)
        return;
    for (uint32_t i = 0; a->meshes && i < a->mesh_count; i++) {
        free(a->meshes[i].vertices);
        free(a->meshes[i].indices);
    }
    for (uint32_t i = 0; a->images && i < a->image_count; i++)
        free(a->images[i].rgba);
    for (uint32_t i = 0; a->ignored && i < a->ignored_count; i++)
        free(a->ignored[i]);
    free(a->meshes);
    free(a->materials);
    free(a->images);
    free(a->lights);
    free(a->cameras);
    free(a->ignored);
    memset(a, 0, sizeof(*a));
}

/* ---- description ---- */

/* A name as a JSON string: names come from the file (or a damaged cache)
 * and may be cut inside a UTF-8 sequence, which jansson refuses; any byte
 * of an invalid sequence becomes '?'. */
static json_t *name_json(const char *s)
{
    json_t *j = json_string(s);
    if (j)
        return j;
    char buf[IGNORED_NAME_MAX];
    size_t n = strnlen(s, sizeof(buf) - 1);
    for (size_t i = 0; i < n; i++)
        buf[i] = (unsigned char)s[i] < 0x80 ? s[i] : '?';
    buf[n] = '\0';
    return json_string(buf);
}

static json_t *vec3(const float v[3])
{
    return json_pack("[fff]", (double)v[0], (double)v[1], (double)v[2]);
}

json_t *asset_describe(const struct asset *a)
{
    json_t *root = json_object();
    json_t *meshes = json_array(), *mats = json_array(), *texs = json_array(),
           *cams = json_array(), *ign = json_array();
    json_t *lights = json_pack("{s[] s[] s[]}", "point", "spot", "directional");
    if (!root || !meshes || !mats || !texs || !cams || !ign || !lights)
        goto oom;
    uint64_t tris = 0, verts = 0, pixels = 0;
    uint32_t from_file = 0, colored = 0, why[ASSET_UV1_GENERATED_OVERLAP + 1] = {0};
    double waste_weighted = 0;
    for (uint32_t i = 0; i < a->mesh_count; i++) {
        const struct asset_mesh *m = &a->meshes[i];
        tris += m->index_count / 3;
        verts += m->vertex_count;
        from_file += m->uv1_origin == ASSET_UV1_FILE;
        colored += m->has_color;
        why[m->uv1_origin <= ASSET_UV1_GENERATED_OVERLAP ? m->uv1_origin : 0]++;
        waste_weighted += (double)m->uv1_waste * (m->index_count / 3);
        if (i >= ASSET_DESCRIBE_LIST_MAX)
            continue; /* counted above, listed no further */
        json_t *attrs = json_pack("[s]", "POSITION");
        json_t *o = json_pack("{so si sI sI ss sf ss}", "name", name_json(m->name),
                "material", (int)m->material, "vertices", (json_int_t)m->vertex_count,
                "triangles", (json_int_t)(m->index_count / 3),
                "uv1", m->uv1_origin == ASSET_UV1_FILE ? "file" : "generated",
                "uv1_waste", (double)m->uv1_waste,
                "tangents", m->tangents_from_file ? "file" : "generated");
        if (!o || !attrs || json_array_append_new(meshes, o)) {
            json_decref(attrs);
            goto oom;
        }
        if (m->uv1_origin != ASSET_UV1_FILE && m->uv1_origin <= ASSET_UV1_GENERATED_OVERLAP)
            json_object_set_new(o, "uv1_reason", json_string(asset_uv1_origin_reasons[m->uv1_origin]));
        if (m->has_texcoord1 && m->uv1_origin != ASSET_UV1_GENERATED_OUTSIDE)
            json_object_set_new(o, "texcoord1_overlap", json_real(m->texcoord1_overlap));
        if (m->has_uv0)
            json_array_append_new(attrs, json_string("TEXCOORD_0"));
        if (m->has_texcoord1)
            json_array_append_new(attrs, json_string("TEXCOORD_1"));
        if (m->has_color)
            json_array_append_new(attrs, json_string("COLOR_0"));
        json_object_set_new(o, "attributes", attrs);
    }
    for (uint32_t i = 0; i < a->material_count && i < ASSET_DESCRIBE_LIST_MAX; i++) {
        const struct asset_material *m = &a->materials[i];
        json_t *slots = json_array();
        if (!slots)
            goto oom;
        json_t *sets = json_object(), *xforms = json_object();
        if (!sets || !xforms) {
            json_decref(slots);
            json_decref(sets);
            json_decref(xforms);
            goto oom;
        }
        for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
            const struct asset_texture_ref *t = &m->tex[s];
            if (t->image < 0)
                continue;
            json_array_append_new(slots, json_string(asset_texture_slot_names[s]));
            json_object_set_new(sets, asset_texture_slot_names[s], json_integer(t->uv_set));
            if (asset_uv_transform_used(&t->transform))
                json_object_set_new(xforms, asset_texture_slot_names[s],
                                    json_pack("{s[ff] sf s[ff]}", "offset",
                                              (double)t->transform.offset[0],
                                              (double)t->transform.offset[1], "rotation",
                                              (double)t->transform.rotation, "scale",
                                              (double)t->transform.scale[0],
                                              (double)t->transform.scale[1]));
        }
        json_t *o = json_pack("{so ss sb so so}", "name", name_json(m->name),
                              "alpha_mode", asset_alpha_mode_names[m->alpha_mode],
                              "double_sided", m->double_sided, "textures", slots,
                              "texcoord", sets);
        if (!o || json_array_append_new(mats, o)) {
            json_decref(xforms);
            goto oom;
        }
        if (json_object_size(xforms))
            json_object_set_new(o, "texture_transforms", xforms);
        else
            json_decref(xforms);
        if (m->alpha_mode == ASSET_ALPHA_MASK)
            json_object_set_new(o, "alpha_cutoff", json_real(m->alpha_cutoff));
    }
    for (uint32_t i = 0; i < a->image_count; i++) {
        const struct asset_image *im = &a->images[i];
        pixels += (uint64_t)im->width * im->height;
        if (i < ASSET_DESCRIBE_LIST_MAX &&
            json_array_append_new(texs, json_pack("{so sI sI}", "name", name_json(im->name),
                                                  "width", (json_int_t)im->width,
                                                  "height", (json_int_t)im->height)))
            goto oom;
    }
    for (uint32_t i = 0; i < a->light_count; i++)
        json_array_append_new(json_object_get(lights, asset_light_type_names[a->lights[i].type]),
                              name_json(a->lights[i].name));
    for (uint32_t i = 0; i < a->camera_count; i++) {
        const struct asset_camera *c = &a->cameras[i];
        json_t *cj = c->perspective
                         ? json_pack("{so ss sf}", "name", name_json(c->name), "type",
                                     "perspective", "yfov", (double)c->yfov)
                         : json_pack("{so ss sf sf}", "name", name_json(c->name), "type",
                                     "orthographic", "xmag", (double)(c->yfov * c->aspect),
                                     "ymag", (double)c->yfov);
        if (json_array_append_new(cams, cj))
            goto oom;
    }
    for (uint32_t i = 0; i < a->ignored_count; i++)
        json_array_append_new(ign, name_json(a->ignored[i]));
    double waste = tris ? waste_weighted / (double)tris : 0.0;
    const char *origin = a->mesh_count == 0 ? "none"
                         : from_file == a->mesh_count ? "file"
                         : from_file == 0 ? "generated" : "mixed";
    json_t *bounds = json_pack("{so so}", "min", vec3(a->box_min), "max", vec3(a->box_max));
    json_t *uv1 = json_pack("{ss si si sf s{si si si}}", "origin", origin, "from_file",
                            (int)from_file, "generated", (int)(a->mesh_count - from_file),
                            "waste", waste, "generated_because", "no_texcoord1",
                            (int)why[ASSET_UV1_GENERATED_NO_SET], "texcoord1_outside",
                            (int)why[ASSET_UV1_GENERATED_OUTSIDE], "texcoord1_overlap",
                            (int)why[ASSET_UV1_GENERATED_OVERLAP]);
    if (!bounds || !uv1)
        goto oom;
    if (json_object_set_new(root, "meshes", json_integer(a->mesh_count)) ||
        json_object_set_new(root, "triangles", json_integer((json_int_t)tris)) ||
        json_object_set_new(root, "vertices", json_integer((json_int_t)verts)) ||
        json_object_set_new(root, "mesh_list", meshes) ||
        json_object_set_new(root, "materials", mats) ||
        json_object_set_new(root, "textures", texs) ||
        json_object_set_new(root, "texture_pixels", json_integer((json_int_t)pixels)) ||
        json_object_set_new(root, "lights", lights) ||
        json_object_set_new(root, "cameras", cams) ||
        json_object_set_new(root, "bounds", bounds) ||
        json_object_set_new(root, "uv1", uv1) ||
        json_object_set_new(root, "vertex_colors", json_integer(colored)) ||
        json_object_set_new(root, "ignored", ign))
        goto oom_after;
    /* What the lists leave out (counted in the totals above). */
    if (a->mesh_count > ASSET_DESCRIBE_LIST_MAX)
        json_object_set_new(root, "mesh_list_omitted",
                            json_integer(a->mesh_count - ASSET_DESCRIBE_LIST_MAX));
    if (a->material_count > ASSET_DESCRIBE_LIST_MAX)
        json_object_set_new(root, "materials_omitted",
                            json_integer(a->material_count - ASSET_DESCRIBE_LIST_MAX));
    if (a->image_count > ASSET_DESCRIBE_LIST_MAX)
        json_object_set_new(root, "textures_omitted",
                            json_integer(a->image_count - ASSET_DESCRIBE_LIST_MAX));
    return root;
oom:
    json_decref(meshes);
    json_decref(mats);
    json_decref(texs);
    json_decref(cams);
    json_decref(ign);
    json_decref(lights);
oom_after:
    json_decref(root);
    return NULL;
}

/* ---- the cache file ----
 *
 * Little-endian throughout (the reader refuses to run on a big-endian
 * host rather than byte-swap). Layout, version 2 (1 had no TEXCOORD_1,
 * COLOR_0 or texture transforms: a version 1 file is refused, and the
 * daemon converts the upload again, docs/assets.md):
 *   header   "SBASSET\0", u32 version, u32 header bytes (HEADER_SIZE),
 *            u32 counts: meshes, materials, images, lights, cameras, ignored,
 *            f32 box_min[3], box_max[3]
 *   ignored  IGNORED_SIZE bytes each, NUL-terminated
 *   materials, lights, cameras: fixed-size records (MATERIAL_SIZE...); a
 *            material's texture slot: i32 image, i32 uv set, u32 wrap s and t,
 *            min and mag filter, f32 scale, f32 offset[2], rotation, scale[2]
 *   images   name[64], u32 width, u32 height, width*height*4 bytes
 *   meshes   name[64], i32 material, u32 vertex_count, u32 index_count,
 *            u32 flags (1 tangents from file, 2 TEXCOORD_0, 4 TEXCOORD_1,
 *            8 COLOR_0), u32 uv1 origin (enum asset_uv1_origin),
 *            f32 box_min[3], box_max[3], f32 uv1_waste, f32 texcoord1_overlap,
 *            vertex_count * 20 f32 (struct asset_vertex), index_count * u32
 *   trailer  "SBEND\0\0\0" (a file cut at a record boundary is still refused)
 * Strings are fixed-size and must hold their NUL. */

#define MAGIC "SBASSET"
#define TRAILER "SBEND\0\0"
enum {
    VERSION = 2,
    HEADER_SIZE = 8 + 4 + 4 + 6 * 4 + 6 * 4,
    IGNORED_SIZE = 128,
    TEXREF_SIZE = 12 * 4,
    MATERIAL_SIZE = ASSET_NAME_MAX + 4 * 4 + 2 * 4 + 3 * 4 + 4 + 4 + 4 + ASSET_TEX_SLOTS * TEXREF_SIZE,
    LIGHT_SIZE = ASSET_NAME_MAX + 4 + 3 * 4 + 4 * 4 + 6 * 4,
    CAMERA_SIZE = ASSET_NAME_MAX + 4 + 4 * 4 + 9 * 4,
    IMAGE_HEAD_SIZE = ASSET_NAME_MAX + 8,
    MESH_HEAD_SIZE = ASSET_NAME_MAX + 5 * 4 + 6 * 4 + 2 * 4,
    VERTEX_FLOATS = 20,
    VERTEX_SIZE = VERTEX_FLOATS * 4,
    TRAILER_SIZE = 8,
};
_Static_assert(sizeof(struct asset_vertex) == VERTEX_SIZE, "asset_vertex is 20 packed floats");
enum { MESH_FLAGS_ALL = 15 };

static bool host_is_little_endian(void)
{
    const uint16_t one = 1;
    uint8_t b;
    memcpy(&b, &one, 1);
    return b == 1;
}

/* -- writing: a FILE with a sticky error -- */

struct writer {
    FILE *f; /* NULL: count the bytes only (asset_file_size) */
    bool failed;
    uint64_t bytes;
};

static void w_bytes(struct writer *w, const void *p, size_t n)
{
    w->bytes += n;
    if (w->f && !w->failed && n && fwrite(p, 1, n, w->f) != n)
        w->failed = true;
}
static void w_u32(struct writer *w, uint32_t v)
{
    uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    w_bytes(w, b, 4);
}
static void w_i32(struct writer *w, int32_t v) { w_u32(w, (uint32_t)v); }
static void w_f32(struct writer *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    w_u32(w, v);
}
static void w_fs(struct writer *w, const float *f, int n)
{
    for (int i = 0; i < n; i++)
        w_f32(w, f[i]);
}
static void w_str(struct writer *w, const char *s, size_t size)
{
    char buf[IGNORED_SIZE + ASSET_NAME_MAX] = {0}; /* the larger of the two sizes, and some */
    size_t n = strnlen(s, size - 1);
    memcpy(buf, s, n);
    w_bytes(w, buf, size);
}

static void write_body(struct writer *w, const struct asset *a)
{
    w_bytes(w, MAGIC, 8);
    w_u32(w, VERSION);
    w_u32(w, HEADER_SIZE);
    w_u32(w, a->mesh_count);
    w_u32(w, a->material_count);
    w_u32(w, a->image_count);
    w_u32(w, a->light_count);
    w_u32(w, a->camera_count);
    w_u32(w, a->ignored_count);
    w_fs(w, a->box_min, 3);
    w_fs(w, a->box_max, 3);
    for (uint32_t i = 0; i < a->ignored_count; i++)
        w_str(w, a->ignored[i], IGNORED_SIZE);
    for (uint32_t i = 0; i < a->material_count; i++) {
        const struct asset_material *m = &a->materials[i];
        w_str(w, m->name, ASSET_NAME_MAX);
        w_fs(w, m->base_color, 4);
        w_f32(w, m->metallic);
        w_f32(w, m->roughness);
        w_fs(w, m->emissive, 3);
        w_u32(w, (uint32_t)m->alpha_mode);
        w_f32(w, m->alpha_cutoff);
        w_u32(w, m->double_sided);
        for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
            const struct asset_texture_ref *t = &m->tex[s];
            w_i32(w, t->image);
            w_i32(w, t->uv_set);
            w_u32(w, t->wrap_s);
            w_u32(w, t->wrap_t);
            w_u32(w, t->min_filter);
            w_u32(w, t->mag_filter);
            w_f32(w, t->scale);
            w_fs(w, t->transform.offset, 2);
            w_f32(w, t->transform.rotation);
            w_fs(w, t->transform.scale, 2);
        }
    }
    for (uint32_t i = 0; i < a->light_count; i++) {
        const struct asset_light *l = &a->lights[i];
        w_str(w, l->name, ASSET_NAME_MAX);
        w_u32(w, (uint32_t)l->type);
        w_fs(w, l->color, 3);
        w_f32(w, l->intensity);
        w_f32(w, l->range);
        w_f32(w, l->inner_cone);
        w_f32(w, l->outer_cone);
        w_fs(w, l->position, 3);
        w_fs(w, l->direction, 3);
    }
    for (uint32_t i = 0; i < a->camera_count; i++) {
        const struct asset_camera *c = &a->cameras[i];
        w_str(w, c->name, ASSET_NAME_MAX);
        w_u32(w, c->perspective);
        w_f32(w, c->yfov);
        w_f32(w, c->znear);
        w_f32(w, c->zfar);
        w_f32(w, c->aspect);
        w_fs(w, c->eye, 3);
        w_fs(w, c->forward, 3);
        w_fs(w, c->up, 3);
    }
    for (uint32_t i = 0; i < a->image_count; i++) {
        const struct asset_image *im = &a->images[i];
        w_str(w, im->name, ASSET_NAME_MAX);
        w_u32(w, im->width);
        w_u32(w, im->height);
        w_bytes(w, im->rgba, (size_t)im->width * im->height * 4);
    }
    for (uint32_t i = 0; i < a->mesh_count; i++) {
        const struct asset_mesh *m = &a->meshes[i];
        w_str(w, m->name, ASSET_NAME_MAX);
        w_i32(w, m->material);
        w_u32(w, m->vertex_count);
        w_u32(w, m->index_count);
        w_u32(w, (m->tangents_from_file ? 1u : 0u) | (m->has_uv0 ? 2u : 0u) |
                     (m->has_texcoord1 ? 4u : 0u) | (m->has_color ? 8u : 0u));
        w_u32(w, (uint32_t)m->uv1_origin);
        w_fs(w, m->box_min, 3);
        w_fs(w, m->box_max, 3);
        w_f32(w, m->uv1_waste);
        w_f32(w, m->texcoord1_overlap);
        /* Little-endian host (checked): the arrays go out as they are. */
        w_bytes(w, m->vertices, (size_t)m->vertex_count * VERTEX_SIZE);
        w_bytes(w, m->indices, (size_t)m->index_count * 4);
    }
    w_bytes(w, TRAILER, TRAILER_SIZE);
}

uint64_t asset_file_size(const struct asset *a)
{
    struct writer w = {NULL, false, 0};
    write_body(&w, a);
    return w.bytes;
}

bool asset_file_write(const struct asset *a, const char *path, char *err, size_t errlen)
{
    if (!host_is_little_endian()) {
        snprintf(err, errlen, "asset cache: big-endian hosts are not supported");
        return false;
    }
    size_t plen = strlen(path);
    char *tmp = malloc(plen + 8);
    if (!tmp) {
        snprintf(err, errlen, "asset cache: out of memory");
        return false;
    }
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".XXXXXX", 8);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        snprintf(err, errlen, "asset cache: cannot create a temporary beside %s: %s", path,
                 strerror(errno));
        free(tmp);
        return false;
    }
    /* Readable like the files beside it (mkstemp makes 0600). */
    if (fchmod(fd, 0644) != 0) {
        snprintf(err, errlen, "asset cache: %s: %s", tmp, strerror(errno));
        close(fd);
        goto fail;
    }
    struct writer w = {fdopen(fd, "wb"), false, 0};
    if (!w.f) {
        snprintf(err, errlen, "asset cache: %s: %s", tmp, strerror(errno));
        close(fd);
        goto fail;
    }
    write_body(&w, a);
    if (w.failed || fflush(w.f) != 0 || fsync(fileno(w.f)) != 0) {
        snprintf(err, errlen, "asset cache: cannot write %s: %s", tmp, strerror(errno));
        fclose(w.f);
        goto fail;
    }
    if (fclose(w.f) != 0) {
        snprintf(err, errlen, "asset cache: cannot write %s: %s", tmp, strerror(errno));
        goto fail;
    }
    if (rename(tmp, path) != 0) {
        snprintf(err, errlen, "asset cache: cannot rename to %s: %s", path, strerror(errno));
        goto fail;
    }
    /* The rename itself made durable: fsync the folder (best effort; a
     * folder that cannot be opened still holds the whole file). */
    char *slash = strrchr(tmp, '/');
    if (slash) {
        *slash = '\0';
        int dfd = open(slash == tmp ? "/" : tmp, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (dfd >= 0) {
            fsync(dfd);
            close(dfd);
        }
    }
    free(tmp);
    return true;
fail:;
    int saved = errno; /* the writer's, for the caller (ENOSPC: no room) */
    unlink(tmp);
    free(tmp);
    errno = saved;
    return false;
}

/* -- reading: a cursor over the bytes; every take checks what is left -- */

struct reader {
    const uint8_t *p;
    size_t left;
    char *err;
    size_t errlen;
    bool failed;
};

static bool r_fail(struct reader *r, const char *fmt, ...)
{
    if (!r->failed) {
        va_list ap;
        va_start(ap, fmt);
        int n = snprintf(r->err, r->errlen, "asset cache: ");
        if (n >= 0 && (size_t)n < r->errlen)
            vsnprintf(r->err + n, r->errlen - (size_t)n, fmt, ap);
        va_end(ap);
        r->failed = true;
    }
    return false;
}

static const uint8_t *r_take(struct reader *r, size_t n, const char *what)
{
    if (r->failed)
        return NULL;
    if (n > r->left) {
        r_fail(r, "truncated: %s needs %zu bytes, %zu left", what, n, r->left);
        return NULL;
    }
    const uint8_t *p = r->p;
    r->p += n;
    r->left -= n;
    return p;
}

static uint32_t r_u32(struct reader *r, const char *what)
{
    const uint8_t *b = r_take(r, 4, what);
    if (!b)
        return 0;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float r_f32(struct reader *r, const char *what)
{
    uint32_t v = r_u32(r, what);
    float f;
    memcpy(&f, &v, 4);
    if (!r->failed && !isfinite(f)) {
        r_fail(r, "%s is not a finite number", what);
        return 0;
    }
    return f;
}

static void r_fs(struct reader *r, float *out, int n, const char *what)
{
    for (int i = 0; i < n; i++)
        out[i] = r_f32(r, what);
}

static void r_str(struct reader *r, char *out, size_t size, const char *what)
{
    const uint8_t *b = r_take(r, size, what);
    if (!b)
        return;
    if (!memchr(b, '\0', size)) {
        r_fail(r, "%s is not NUL-terminated", what);
        return;
    }
    memcpy(out, b, size);
}

/* n records of rec bytes each must fit in what is left: checked before the
 * array for them is allocated, so that a huge count is refused, not
 * allocated. */
static bool r_room(struct reader *r, uint64_t n, uint64_t rec, const char *what)
{
    if (r->failed)
        return false;
    if (rec && n > r->left / rec)
        return r_fail(r, "%" PRIu64 " %s do not fit in the %zu bytes left", n, what, r->left);
    return true;
}

static bool in_unit(float x) { return x >= 0.0f && x <= 1.0f; }

bool asset_file_parse(struct asset *out, const void *data, size_t len,
                      const struct asset_limits *lim, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    struct reader r = {data, len, err, errlen, false};
    char what[96];
    if (!host_is_little_endian())
        return r_fail(&r, "big-endian hosts are not supported");
    const uint8_t *magic = r_take(&r, 8, "magic");
    if (!magic)
        goto fail;
    if (memcmp(magic, MAGIC, 8) != 0) {
        r_fail(&r, "not an asset cache (bad magic)");
        goto fail;
    }
    uint32_t version = r_u32(&r, "version");
    if (!r.failed && version != VERSION) {
        r_fail(&r, "version %u, this reader knows %d (a cache from another shadebench: upload the "
               "asset again to convert it anew)", version, VERSION);
        goto fail;
    }
    uint32_t hsize = r_u32(&r, "header size");
    if (!r.failed && hsize != HEADER_SIZE) {
        r_fail(&r, "header size %u, expected %d", hsize, HEADER_SIZE);
        goto fail;
    }
    uint32_t nmesh = r_u32(&r, "mesh count"), nmat = r_u32(&r, "material count"),
             nimg = r_u32(&r, "image count"), nlight = r_u32(&r, "light count"),
             ncam = r_u32(&r, "camera count"), nign = r_u32(&r, "ignored count");
    r_fs(&r, out->box_min, 3, "box_min");
    r_fs(&r, out->box_max, 3, "box_max");
    if (r.failed)
        goto fail;
    if (nmesh > lim->max_meshes) {
        r_fail(&r, "%u meshes, over the limit of %u", nmesh, lim->max_meshes);
        goto fail;
    }
    if (nmat > lim->max_materials) {
        r_fail(&r, "%u materials, over the limit of %u", nmat, lim->max_materials);
        goto fail;
    }
    if (nimg > lim->max_images) {
        r_fail(&r, "%u images, over the limit of %u", nimg, lim->max_images);
        goto fail;
    }
    if (nlight > lim->max_lights) {
        r_fail(&r, "%u lights, over the limit of %u", nlight, lim->max_lights);
        goto fail;
    }
    if (ncam > lim->max_cameras) {
        r_fail(&r, "%u cameras, over the limit of %u", ncam, lim->max_cameras);
        goto fail;
    }
    if (nign > 1024) {
        r_fail(&r, "%u ignored entries, over the limit of 1024", nign);
        goto fail;
    }
    /* Every record at its smallest must fit before anything is allocated. */
    uint64_t least = (uint64_t)nign * IGNORED_SIZE + (uint64_t)nmat * MATERIAL_SIZE +
                     (uint64_t)nlight * LIGHT_SIZE + (uint64_t)ncam * CAMERA_SIZE +
                     (uint64_t)nimg * IMAGE_HEAD_SIZE + (uint64_t)nmesh * MESH_HEAD_SIZE + TRAILER_SIZE;
    if (least > r.left) {
        r_fail(&r, "truncated: the counts need at least %" PRIu64 " bytes, %zu left", least, r.left);
        goto fail;
    }

    if (nign) {
        out->ignored = calloc(nign, sizeof(char *));
        if (!out->ignored) {
            r_fail(&r, "out of memory");
            goto fail;
        }
    }
    for (uint32_t i = 0; i < nign; i++) {
        char buf[IGNORED_SIZE];
        snprintf(what, sizeof(what), "ignored[%u]", i);
        r_str(&r, buf, IGNORED_SIZE, what);
        if (r.failed)
            goto fail;
        out->ignored[i] = strdup(buf);
        if (!out->ignored[i]) {
            r_fail(&r, "out of memory");
            goto fail;
        }
        out->ignored_count = i + 1;
    }

    if (nmat && !(out->materials = calloc(nmat, sizeof(*out->materials)))) {
        r_fail(&r, "out of memory");
        goto fail;
    }
    out->material_count = nmat;
    for (uint32_t i = 0; i < nmat && !r.failed; i++) {
        struct asset_material *m = &out->materials[i];
        snprintf(what, sizeof(what), "materials[%u]", i);
        r_str(&r, m->name, ASSET_NAME_MAX, what);
        r_fs(&r, m->base_color, 4, what);
        m->metallic = r_f32(&r, what);
        m->roughness = r_f32(&r, what);
        r_fs(&r, m->emissive, 3, what);
        uint32_t mode = r_u32(&r, what);
        m->alpha_cutoff = r_f32(&r, what);
        uint32_t ds = r_u32(&r, what);
        if (r.failed)
            break;
        if (mode > ASSET_ALPHA_BLEND || ds > 1) {
            r_fail(&r, "materials[%u]: alpha mode %u or double_sided %u out of range", i, mode, ds);
            break;
        }
        m->alpha_mode = (enum asset_alpha_mode)mode;
        m->double_sided = ds;
        for (int s = 0; s < ASSET_TEX_SLOTS && !r.failed; s++) {
            struct asset_texture_ref *t = &m->tex[s];
            snprintf(what, sizeof(what), "materials[%u].%s", i, asset_texture_slot_names[s]);
            t->image = (int32_t)r_u32(&r, what);
            t->uv_set = (int32_t)r_u32(&r, what);
            t->wrap_s = r_u32(&r, what);
            t->wrap_t = r_u32(&r, what);
            t->min_filter = r_u32(&r, what);
            t->mag_filter = r_u32(&r, what);
            t->scale = r_f32(&r, what);
            r_fs(&r, t->transform.offset, 2, what);
            t->transform.rotation = r_f32(&r, what);
            r_fs(&r, t->transform.scale, 2, what);
            if (r.failed)
                break;
            if (t->image < -1 || (t->image >= 0 && (uint32_t)t->image >= nimg))
                r_fail(&r, "%s: image %d out of range (%u images)", what, t->image, nimg);
            else if (t->uv_set != 0 && t->uv_set != 1)
                r_fail(&r, "%s: uv set %d is not 0 or 1", what, t->uv_set);
        }
    }
    if (r.failed)
        goto fail;

    if (nlight && !(out->lights = calloc(nlight, sizeof(*out->lights)))) {
        r_fail(&r, "out of memory");
        goto fail;
    }
    out->light_count = nlight;
    for (uint32_t i = 0; i < nlight && !r.failed; i++) {
        struct asset_light *l = &out->lights[i];
        snprintf(what, sizeof(what), "lights[%u]", i);
        r_str(&r, l->name, ASSET_NAME_MAX, what);
        uint32_t type = r_u32(&r, what);
        r_fs(&r, l->color, 3, what);
        l->intensity = r_f32(&r, what);
        l->range = r_f32(&r, what);
        l->inner_cone = r_f32(&r, what);
        l->outer_cone = r_f32(&r, what);
        r_fs(&r, l->position, 3, what);
        r_fs(&r, l->direction, 3, what);
        if (!r.failed && type > ASSET_LIGHT_DIRECTIONAL)
            r_fail(&r, "lights[%u]: type %u out of range", i, type);
        l->type = (enum asset_light_type)type;
    }
    if (r.failed)
        goto fail;

    if (ncam && !(out->cameras = calloc(ncam, sizeof(*out->cameras)))) {
        r_fail(&r, "out of memory");
        goto fail;
    }
    out->camera_count = ncam;
    for (uint32_t i = 0; i < ncam && !r.failed; i++) {
        struct asset_camera *c = &out->cameras[i];
        snprintf(what, sizeof(what), "cameras[%u]", i);
        r_str(&r, c->name, ASSET_NAME_MAX, what);
        uint32_t persp = r_u32(&r, what);
        c->yfov = r_f32(&r, what);
        c->znear = r_f32(&r, what);
        c->zfar = r_f32(&r, what);
        c->aspect = r_f32(&r, what);
        r_fs(&r, c->eye, 3, what);
        r_fs(&r, c->forward, 3, what);
        r_fs(&r, c->up, 3, what);
        if (!r.failed && persp > 1)
            r_fail(&r, "cameras[%u]: perspective flag %u is not 0 or 1", i, persp);
        c->perspective = persp;
    }
    if (r.failed)
        goto fail;

    if (nimg && !(out->images = calloc(nimg, sizeof(*out->images)))) {
        r_fail(&r, "out of memory");
        goto fail;
    }
    uint64_t pixels = 0;
    for (uint32_t i = 0; i < nimg; i++) {
        struct asset_image *im = &out->images[i];
        snprintf(what, sizeof(what), "images[%u]", i);
        r_str(&r, im->name, ASSET_NAME_MAX, what);
        uint32_t w = r_u32(&r, what), h = r_u32(&r, what);
        if (r.failed)
            goto fail;
        if (w == 0 || h == 0 || w > lim->max_texture_edge || h > lim->max_texture_edge) {
            r_fail(&r, "images[%u]: %ux%u, edges must be 1 to %u", i, w, h, lim->max_texture_edge);
            goto fail;
        }
        pixels += (uint64_t)w * h; /* each under 2^26: no overflow over 4096 images */
        if (pixels > lim->max_texture_pixels) {
            r_fail(&r, "images[%u]: %" PRIu64 " texture pixels in all, over the limit of %" PRIu64,
                   i, pixels, lim->max_texture_pixels);
            goto fail;
        }
        if (!r_room(&r, (uint64_t)w * h, 4, "pixels"))
            goto fail;
        size_t bytes = (size_t)w * h * 4;
        const uint8_t *px = r_take(&r, bytes, what);
        if (!px || !(im->rgba = malloc(bytes))) {
            r_fail(&r, "out of memory");
            goto fail;
        }
        memcpy(im->rgba, px, bytes);
        im->width = w;
        im->height = h;
        out->image_count = i + 1;
    }

    if (nmesh && !(out->meshes = calloc(nmesh, sizeof(*out->meshes)))) {
        r_fail(&r, "out of memory");
        goto fail;
    }
    uint64_t total_v = 0, total_i = 0;
    for (uint32_t i = 0; i < nmesh; i++) {
        struct asset_mesh *m = &out->meshes[i];
        snprintf(what, sizeof(what), "meshes[%u]", i);
        r_str(&r, m->name, ASSET_NAME_MAX, what);
        int32_t mat = (int32_t)r_u32(&r, what);
        uint32_t nv = r_u32(&r, what), ni = r_u32(&r, what), flags = r_u32(&r, what),
                 origin = r_u32(&r, what);
        r_fs(&r, m->box_min, 3, what);
        r_fs(&r, m->box_max, 3, what);
        m->uv1_waste = r_f32(&r, what);
        m->texcoord1_overlap = r_f32(&r, what);
        if (r.failed)
            goto fail;
        if (mat < -1 || (mat >= 0 && (uint32_t)mat >= nmat)) {
            r_fail(&r, "meshes[%u]: material %d out of range (%u materials)", i, mat, nmat);
            goto fail;
        }
        if (flags > MESH_FLAGS_ALL || !in_unit(m->uv1_waste) || !in_unit(m->texcoord1_overlap)) {
            r_fail(&r, "meshes[%u]: flags %u, uv1 waste or overlap out of range", i, flags);
            goto fail;
        }
        if (origin > ASSET_UV1_GENERATED_OVERLAP || ((origin == ASSET_UV1_FILE) && !(flags & 4))) {
            r_fail(&r, "meshes[%u]: uv1 origin %u out of range (or from a TEXCOORD_1 it lacks)", i,
                   origin);
            goto fail;
        }
        if (nv == 0 || ni == 0 || ni % 3) {
            r_fail(&r, "meshes[%u]: %u vertices and %u indices do not make triangles", i, nv, ni);
            goto fail;
        }
        total_v += nv;
        total_i += ni;
        if (total_v > lim->max_vertices) {
            r_fail(&r, "meshes[%u]: %" PRIu64 " vertices in all, over the limit of %" PRIu64, i,
                   total_v, lim->max_vertices);
            goto fail;
        }
        if (total_i > lim->max_indices) {
            r_fail(&r, "meshes[%u]: %" PRIu64 " indices in all, over the limit of %" PRIu64, i,
                   total_i, lim->max_indices);
            goto fail;
        }
        if (!r_room(&r, nv, VERTEX_SIZE, "vertices"))
            goto fail;
        const uint8_t *vb = r_take(&r, (size_t)nv * VERTEX_SIZE, what);
        if (!r_room(&r, ni, 4, "indices"))
            goto fail;
        const uint8_t *ib = r_take(&r, (size_t)ni * 4, what);
        if (!vb || !ib)
            goto fail;
        m->vertices = malloc((size_t)nv * VERTEX_SIZE);
        m->indices = malloc((size_t)ni * 4);
        if (!m->vertices || !m->indices) {
            free(m->vertices);
            free(m->indices);
            m->vertices = NULL;
            m->indices = NULL;
            r_fail(&r, "out of memory");
            goto fail;
        }
        out->mesh_count = i + 1;
        memcpy(m->vertices, vb, (size_t)nv * VERTEX_SIZE);
        memcpy(m->indices, ib, (size_t)ni * 4);
        m->material = mat;
        m->vertex_count = nv;
        m->index_count = ni;
        m->uv1_origin = (enum asset_uv1_origin)origin;
        m->tangents_from_file = flags & 1;
        m->has_uv0 = flags & 2;
        m->has_texcoord1 = flags & 4;
        m->has_color = flags & 8;
        for (uint32_t k = 0; k < ni; k++)
            if (m->indices[k] >= nv) {
                r_fail(&r, "meshes[%u]: index %u is %u, not below the %u vertices", i, k,
                       m->indices[k], nv);
                goto fail;
            }
        for (uint32_t k = 0; k < nv; k++) {
            const struct asset_vertex *v = &m->vertices[k];
            const float *f = v->pos;
            for (int c = 0; c < VERTEX_FLOATS; c++)
                if (!isfinite(f[c])) {
                    r_fail(&r, "meshes[%u]: vertex %u has a non-finite value", i, k);
                    goto fail;
                }
            if (!in_unit(v->uv1[0]) || !in_unit(v->uv1[1])) {
                r_fail(&r, "meshes[%u]: vertex %u's uv1 is outside [0, 1]", i, k);
                goto fail;
            }
        }
    }
    const uint8_t *end = r_take(&r, TRAILER_SIZE, "trailer");
    if (!end)
        goto fail;
    if (memcmp(end, TRAILER, TRAILER_SIZE) != 0) {
        r_fail(&r, "bad trailer");
        goto fail;
    }
    if (r.left) {
        r_fail(&r, "%zu bytes after the trailer", r.left);
        goto fail;
    }
    return true;
fail:
    if (!r.failed)
        r_fail(&r, "malformed");
    asset_finish(out);
    return false;
}

bool asset_file_is_current(const char *path)
{
    uint8_t head[12];
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return false;
    bool ok = read(fd, head, sizeof(head)) == (ssize_t)sizeof(head) && memcmp(head, MAGIC, 8) == 0 &&
              (head[8] | head[9] << 8 | head[10] << 16 | (uint32_t)head[11] << 24) == VERSION;
    close(fd);
    return ok;
}

bool asset_file_read(struct asset *out, const char *path, const struct asset_limits *lim,
                     char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        snprintf(err, errlen, "asset cache: cannot open %s: %s", path, strerror(errno));
        return false;
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "asset cache: %s is not a regular file", path);
        close(fd);
        return false;
    }
    if (st.st_size == 0) {
        close(fd);
        return asset_file_parse(out, "", 0, lim, err, errlen);
    }
    /* Mapped, not read: the parser copies each array once into its own
     * allocation, so the file's bytes are never held twice in the heap. */
    void *map = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE, fd, 0);
    close(fd);
    if (map == MAP_FAILED) {
        snprintf(err, errlen, "asset cache: cannot map %s: %s", path, strerror(errno));
        return false;
    }
    bool ok = asset_file_parse(out, map, (size_t)st.st_size, lim, err, errlen);
    munmap(map, (size_t)st.st_size);
    return ok;
}
