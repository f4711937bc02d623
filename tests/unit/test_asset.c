#define _POSIX_C_SOURCE 200809L /* mkdtemp */
/* The asset cache file (daemon/scene/asset.c), GL-free: a write and read
 * round trip keeps every field; every damage the reader can meet (cut at
 * every length, each count, size, index and enum out of range, NaNs,
 * unterminated names, trailing bytes, every single byte flipped) is refused
 * with a message and nothing leaks; the limits are enforced on read; the
 * description and the limits' JSON carry what they promise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "daemon/scene/asset.h"
#include "tests/unit/check.h"

static char dir[] = "/tmp/test_asset.XXXXXX";

/* A small asset with one of everything (two meshes, one textured). */
static void make_asset(struct asset *a)
{
    memset(a, 0, sizeof(*a));
    a->material_count = 1;
    a->materials = calloc(1, sizeof(*a->materials));
    struct asset_material *m = &a->materials[0];
    snprintf(m->name, sizeof(m->name), "paint");
    for (int k = 0; k < 4; k++)
        m->base_color[k] = 0.25f * (float)(k + 1);
    m->metallic = 0.5f;
    m->roughness = 0.75f;
    m->emissive[2] = 2.0f;
    m->alpha_mode = ASSET_ALPHA_MASK;
    m->alpha_cutoff = 0.3f;
    m->double_sided = true;
    for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
        m->tex[s].image = s == ASSET_TEX_BASE_COLOR ? 0 : -1;
        m->tex[s].uv_set = s == ASSET_TEX_OCCLUSION ? 1 : 0;
        m->tex[s].wrap_s = 33071;
        m->tex[s].wrap_t = 10497;
        m->tex[s].min_filter = 9987;
        m->tex[s].mag_filter = 9729;
        m->tex[s].scale = 1.0f;
        m->tex[s].transform = (struct asset_uv_transform)ASSET_UV_IDENTITY;
    }
    m->tex[ASSET_TEX_BASE_COLOR].transform.offset[0] = 0.25f;
    m->tex[ASSET_TEX_BASE_COLOR].transform.rotation = 0.5f;
    m->tex[ASSET_TEX_BASE_COLOR].transform.scale[1] = -2.0f;
    a->image_count = 1;
    a->images = calloc(1, sizeof(*a->images));
    snprintf(a->images[0].name, ASSET_NAME_MAX, "base");
    a->images[0].width = 3;
    a->images[0].height = 2;
    a->images[0].rgba = malloc(3 * 2 * 4);
    for (int i = 0; i < 24; i++)
        a->images[0].rgba[i] = (uint8_t)(i * 10);
    a->light_count = 2;
    a->lights = calloc(2, sizeof(*a->lights));
    snprintf(a->lights[0].name, ASSET_NAME_MAX, "bulb");
    a->lights[0].type = ASSET_LIGHT_POINT;
    a->lights[0].intensity = 20;
    a->lights[0].range = 10;
    snprintf(a->lights[1].name, ASSET_NAME_MAX, "torch");
    a->lights[1].type = ASSET_LIGHT_SPOT;
    a->lights[1].outer_cone = 0.5f;
    a->lights[1].direction[2] = -1;
    a->camera_count = 1;
    a->cameras = calloc(1, sizeof(*a->cameras));
    snprintf(a->cameras[0].name, ASSET_NAME_MAX, "main");
    a->cameras[0].perspective = true;
    a->cameras[0].yfov = 0.9f;
    a->cameras[0].eye[2] = 5;
    a->cameras[0].forward[2] = -1;
    a->cameras[0].up[1] = 1;
    a->mesh_count = 2;
    a->meshes = calloc(2, sizeof(*a->meshes));
    for (int k = 0; k < 2; k++) {
        struct asset_mesh *me = &a->meshes[k];
        snprintf(me->name, ASSET_NAME_MAX, "mesh%d", k);
        me->material = k == 0 ? 0 : -1;
        me->vertex_count = 4;
        me->index_count = 6;
        me->vertices = calloc(4, sizeof(*me->vertices));
        me->indices = malloc(6 * sizeof(uint32_t));
        static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
        memcpy(me->indices, idx, sizeof(idx));
        for (int v = 0; v < 4; v++) {
            me->vertices[v].pos[0] = (float)(v & 1) + (float)k;
            me->vertices[v].pos[1] = (float)(v >> 1);
            me->vertices[v].normal[2] = 1;
            me->vertices[v].tangent[0] = 1;
            me->vertices[v].tangent[3] = -1;
            me->vertices[v].uv0[0] = (float)v * 0.5f;
            me->vertices[v].uv1[0] = (float)(v & 1);
            me->vertices[v].uv1[1] = (float)(v >> 1);
            me->vertices[v].texcoord1[0] = (float)v * 2.0f; /* outside [0, 1] is the file's */
            for (int c = 0; c < 4; c++)
                me->vertices[v].color[c] = k == 1 ? 0.25f * (float)c : 1.0f;
        }
        me->uv1_origin = k == 0 ? ASSET_UV1_FILE : ASSET_UV1_GENERATED_OVERLAP;
        me->texcoord1_overlap = k == 0 ? 0.0f : 0.25f;
        me->has_uv0 = me->has_texcoord1 = true;
        me->has_color = k == 1;
        me->tangents_from_file = k == 1;
        me->box_max[0] = 1.0f + (float)k;
        me->box_max[1] = 1;
        me->uv1_waste = 0.5f;
    }
    a->box_max[0] = 2;
    a->box_max[1] = 1;
    a->ignored_count = 1;
    a->ignored = calloc(1, sizeof(char *));
    a->ignored[0] = strdup("animations");
}

static bool refused(const unsigned char *buf, size_t len, const char *needle)
{
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    struct asset a;
    char err[256] = "";
    bool ok = asset_file_parse(&a, buf, len, &lim, err, sizeof(err));
    bool named = err[0] != '\0' && (!needle || strstr(err, needle));
    if (!ok && !named)
        fprintf(stderr, "refusal without the expected message (%s): %s\n", needle ? needle : "", err);
    if (ok)
        asset_finish(&a);
    /* A refusal leaves a finished (zeroed) asset behind. */
    if (!ok && (a.meshes || a.images || a.mesh_count))
        return false;
    return !ok && named;
}

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

/* Offsets in make_asset's file (the layout in asset.c). */
enum {
    HDR = 64, IGN = 128, MAT = 352, LIGHT = 120, CAM = 120, MESH_HEAD = 116, VERTEX = 80,
    OFF_MESH_COUNT = 16, OFF_MAT_COUNT = 20, OFF_IMG_COUNT = 24, OFF_IGN_COUNT = 36,
    OFF_MAT = HDR + IGN,
    OFF_IMG = OFF_MAT + MAT + 2 * LIGHT + CAM,
    OFF_MESH = OFF_IMG + 64 + 8 + 24,
};

int main(void)
{
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char path[256];
    snprintf(path, sizeof(path), "%s/a.sbasset", dir);
    struct asset a, b;
    char err[256];
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    CHECK(lim.max_file_bytes == 256ull << 20 && lim.max_vertices == 16ull << 20 &&
          lim.max_indices == 48ull << 20 && lim.max_texture_pixels == 256ull << 20 &&
          lim.max_texture_edge == 8192 && lim.max_meshes == 65536 && lim.max_materials == 4096 &&
          lim.max_images == 4096 && lim.max_lights == 1024 && lim.max_cameras == 1024);
    json_t *lj = asset_limits_to_json(&lim);
    CHECK(lj && json_integer_value(json_object_get(lj, "max_texture_edge")) == 8192 &&
          json_object_size(lj) == 12);
    json_decref(lj);
    CHECK(strcmp(asset_texture_slot_names[ASSET_TEX_EMISSIVE], "emissive") == 0);
    CHECK(strcmp(asset_alpha_mode_names[ASSET_ALPHA_BLEND], "blend") == 0);
    CHECK(strcmp(asset_light_type_names[ASSET_LIGHT_DIRECTIONAL], "directional") == 0);

    /* Round trip. */
    make_asset(&a);
    CHECK(asset_file_write(&a, path, err, sizeof(err)));
    CHECK(asset_file_read(&b, path, &lim, err, sizeof(err)));
    CHECK(b.mesh_count == 2 && b.material_count == 1 && b.image_count == 1 && b.light_count == 2 &&
          b.camera_count == 1 && b.ignored_count == 1);
    if (b.mesh_count == 2 && b.image_count == 1 && b.material_count == 1 && b.ignored_count == 1) {
        CHECK(memcmp(b.materials, a.materials, sizeof(*a.materials)) == 0);
        CHECK(memcmp(b.lights, a.lights, 2 * sizeof(*a.lights)) == 0);
        CHECK(memcmp(b.cameras, a.cameras, sizeof(*a.cameras)) == 0);
        CHECK(memcmp(b.images[0].rgba, a.images[0].rgba, 24) == 0 && b.images[0].width == 3);
        CHECK(strcmp(b.images[0].name, "base") == 0);
        for (int k = 0; k < 2; k++) {
            CHECK(memcmp(b.meshes[k].vertices, a.meshes[k].vertices, 4 * sizeof(struct asset_vertex)) == 0);
            CHECK(memcmp(b.meshes[k].indices, a.meshes[k].indices, 6 * 4) == 0);
            CHECK(b.meshes[k].material == a.meshes[k].material);
            CHECK(b.meshes[k].uv1_origin == a.meshes[k].uv1_origin &&
                  b.meshes[k].tangents_from_file == (k == 1));
            CHECK(b.meshes[k].has_uv0 && b.meshes[k].has_texcoord1 && b.meshes[k].has_color == (k == 1));
            CHECK(b.meshes[k].texcoord1_overlap == a.meshes[k].texcoord1_overlap);
            CHECK(b.meshes[k].uv1_waste == 0.5f && b.meshes[k].box_max[0] == a.meshes[k].box_max[0]);
        }
        CHECK(strcmp(b.ignored[0], "animations") == 0);
        CHECK(b.box_max[0] == 2);
    }
    /* The description. */
    json_t *d = asset_describe(&b);
    CHECK(d != NULL);
    CHECK(json_integer_value(json_object_get(d, "meshes")) == 2);
    CHECK(json_integer_value(json_object_get(d, "triangles")) == 4);
    CHECK(json_integer_value(json_object_get(d, "vertices")) == 8);
    json_t *mat0 = json_array_get(json_object_get(d, "materials"), 0);
    CHECK(strcmp(json_string_value(json_object_get(mat0, "alpha_mode")), "mask") == 0);
    CHECK(json_array_size(json_object_get(mat0, "textures")) == 1);
    CHECK(json_integer_value(json_object_get(json_array_get(json_object_get(d, "textures"), 0), "width")) == 3);
    json_t *lights = json_object_get(d, "lights");
    CHECK(json_array_size(json_object_get(lights, "point")) == 1 &&
          json_array_size(json_object_get(lights, "spot")) == 1 &&
          json_array_size(json_object_get(lights, "directional")) == 0);
    CHECK(strcmp(json_string_value(json_object_get(json_array_get(json_object_get(d, "cameras"), 0), "name")), "main") == 0);
    json_t *uv1 = json_object_get(d, "uv1");
    CHECK(strcmp(json_string_value(json_object_get(uv1, "origin")), "mixed") == 0);
    json_t *because = json_object_get(uv1, "generated_because");
    CHECK(json_integer_value(json_object_get(because, "texcoord1_overlap")) == 1 &&
          json_integer_value(json_object_get(because, "no_texcoord1")) == 0);
    json_t *mesh1 = json_array_get(json_object_get(d, "mesh_list"), 1);
    CHECK(strstr(json_string_value(json_object_get(mesh1, "uv1_reason")), "overlap") != NULL);
    CHECK(fabs(json_real_value(json_object_get(mesh1, "texcoord1_overlap")) - 0.25) < 1e-6);
    CHECK(json_array_size(json_object_get(mesh1, "attributes")) == 4);
    CHECK(json_integer_value(json_object_get(d, "vertex_colors")) == 1);
    CHECK(json_integer_value(json_object_get(json_object_get(mat0, "texcoord"), "base_color")) == 0);
    json_t *xf = json_object_get(json_object_get(mat0, "texture_transforms"), "base_color");
    CHECK(xf && fabs(json_real_value(json_object_get(xf, "rotation")) - 0.5) < 1e-6 &&
          json_object_size(json_object_get(mat0, "texture_transforms")) == 1);
    /* The transform's matrix: T R S as the sample viewer composes it. */
    float mx[6];
    asset_uv_transform_matrix(&a.materials[0].tex[ASSET_TEX_BASE_COLOR].transform, mx);
    CHECK_NEAR(mx[0], cosf(0.5f), 1e-6);
    CHECK_NEAR(mx[1], sinf(0.5f) * -2.0f, 1e-6);
    CHECK_NEAR(mx[2], 0.25f, 1e-7);
    CHECK_NEAR(mx[3], -sinf(0.5f), 1e-6);
    CHECK_NEAR(mx[4], cosf(0.5f) * -2.0f, 1e-6);
    CHECK(mx[5] == 0.0f);
    CHECK(asset_uv_transform_used(&a.materials[0].tex[0].transform) &&
          !asset_uv_transform_used(&a.materials[0].tex[1].transform));
    /* The extension's example: offset (0, 1), a quarter turn, half scale
     * maps the unit square onto the lower left quadrant. */
    struct asset_uv_transform ex = {{0.0f, 1.0f}, 1.5707963f, {0.5f, 0.5f}};
    asset_uv_transform_matrix(&ex, mx);
    for (int corner = 0; corner < 4; corner++) {
        float u = (float)(corner & 1), v = (float)(corner >> 1);
        float u2 = mx[0] * u + mx[1] * v + mx[2], v2 = mx[3] * u + mx[4] * v + mx[5];
        CHECK(u2 > -1e-6f && u2 < 0.5f + 1e-6f && v2 > 0.5f - 1e-6f && v2 < 1.0f + 1e-6f);
    }
    CHECK(fabs(json_real_value(json_object_get(uv1, "waste")) - 0.5) < 1e-6);
    CHECK(json_array_size(json_object_get(d, "ignored")) == 1);
    json_decref(d);
    asset_finish(&b);
    asset_finish(&b); /* twice is harmless */

    /* Damage. */
    size_t len = 0;
    unsigned char *good = check_slurp(path, &len);
    CHECK(good && len == (size_t)OFF_MESH + 2 * (MESH_HEAD + 4 * VERTEX + 24) + 8);
    unsigned char *buf = malloc(len + 16);
    /* Every cut, from empty to one byte short. */
    int cuts_refused = 0;
    for (size_t n = 0; n < len; n++)
        cuts_refused += refused(good, n, NULL);
    CHECK(cuts_refused == (int)len);
    /* Every single byte flipped: refused or read, never a crash (the
     * sanitizer build checks), and what is read passes its own checks. */
    for (size_t i = 0; i < len; i++) {
        memcpy(buf, good, len);
        buf[i] ^= 0xA5;
        struct asset x;
        if (asset_file_parse(&x, buf, len, &lim, err, sizeof(err)))
            asset_finish(&x);
    }
#define DAMAGE(off, value, needle)                    \
    do {                                              \
        memcpy(buf, good, len);                       \
        put_u32(buf + (off), (uint32_t)(value));      \
        CHECK(refused(buf, len, needle));             \
    } while (0)
    DAMAGE(0, 0x12345678, "magic");
    DAMAGE(8, 1, "version");                                             /* the old layout */
    DAMAGE(12, 60, "header size");
    DAMAGE(OFF_MESH_COUNT, 0xFFFFFFFF, "meshes");
    DAMAGE(OFF_MESH_COUNT, 65536, "truncated");
    DAMAGE(OFF_MAT_COUNT, 4097, "materials");
    DAMAGE(OFF_IMG_COUNT, 2, NULL);
    DAMAGE(OFF_IGN_COUNT, 5000, "ignored");
    DAMAGE(OFF_MAT + 64 + 36, 3, "alpha mode");                          /* alpha mode */
    DAMAGE(OFF_MAT + 64 + 48, 7, "image");                               /* slot 0 image 7 */
    DAMAGE(OFF_MAT + 64 + 48, 0xFFFFFFFE, "image");                      /* slot 0 image -2 */
    DAMAGE(OFF_MAT + 64 + 52, 2, "uv set");                              /* slot 0 uv set */
    DAMAGE(OFF_MAT + 64, 0x7FC00000, "finite");                          /* base colour NaN */
    DAMAGE(OFF_MAT + MAT + 64, 9, "type");                               /* light type */
    DAMAGE(OFF_MAT + MAT + 2 * LIGHT + 64, 2, "perspective");            /* camera flag */
    DAMAGE(OFF_IMG + 64, 0, "edges");                                    /* width 0 */
    DAMAGE(OFF_IMG + 64, 9000, "edges");                                 /* width over the edge */
    DAMAGE(OFF_IMG + 68, 8000, NULL);                                    /* height: truncated */
    DAMAGE(OFF_MESH + 64, 5, "material");                                /* mesh material */
    DAMAGE(OFF_MESH + 68, 0xFFFFFFF0, "vertices");                       /* vertex count */
    DAMAGE(OFF_MESH + 72, 7, "triangles");                               /* index count % 3 */
    DAMAGE(OFF_MESH + 72, 0xFFFFFFF0, NULL);                             /* index count */
    DAMAGE(OFF_MESH + 76, 16, "flags");
    DAMAGE(OFF_MESH + 76, 3, "TEXCOORD_1");                              /* uv1 from a set it lacks */
    DAMAGE(OFF_MESH + 80, 4, "origin");
    DAMAGE(OFF_MESH + 108, 0x40000000, "waste");                         /* waste 2.0 */
    DAMAGE(OFF_MESH + 112, 0xBF800000, "overlap");                       /* overlap -1 */
    DAMAGE(OFF_MESH + MESH_HEAD + 4 * VERTEX + 8, 4, "index");           /* index 2 = 4 */
    DAMAGE(OFF_MESH + MESH_HEAD, 0x7F800000, "non-finite");              /* pos inf */
    DAMAGE(OFF_MESH + MESH_HEAD + 48, 0x40000000, "uv1");                /* uv1 x 2.0 */
    DAMAGE(OFF_MESH + MESH_HEAD + 64, 0x7FC00000, "non-finite");         /* colour NaN */
    DAMAGE(OFF_MAT + 64 + 48 + 28, 0x7FC00000, "finite");                /* transform offset NaN */
    DAMAGE(len - 8, 0, "trailer");
    /* Unterminated name. */
    memcpy(buf, good, len);
    memset(buf + OFF_MAT, 'x', 64);
    CHECK(refused(buf, len, "NUL"));
    memcpy(buf, good, len);
    memset(buf + HDR, 'y', 128);
    CHECK(refused(buf, len, "NUL"));
    /* Trailing bytes. */
    memcpy(buf, good, len);
    memset(buf + len, 0, 4);
    CHECK(refused(buf, len + 4, "after the trailer"));
    /* Limits on read. */
    struct asset_limits tight = lim;
    tight.max_vertices = 7;
    struct asset x;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "vertices"));
    tight = lim;
    tight.max_indices = 6;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "indices"));
    tight = lim;
    tight.max_texture_pixels = 5;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "texture pixels"));
    tight = lim;
    tight.max_texture_edge = 2;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "edges"));
    tight = lim;
    tight.max_lights = 1;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "lights"));
    tight = lim;
    tight.max_meshes = 1;
    CHECK(!asset_file_parse(&x, good, len, &tight, err, sizeof(err)) && strstr(err, "meshes"));
    /* Files: missing, empty, a folder. */
    char other[300];
    snprintf(other, sizeof(other), "%s/missing", dir);
    CHECK(!asset_file_read(&x, other, &lim, err, sizeof(err)) && strstr(err, "cannot open"));
    snprintf(other, sizeof(other), "%s/empty", dir);
    FILE *f = fopen(other, "wb");
    fclose(f);
    CHECK(!asset_file_read(&x, other, &lim, err, sizeof(err)) && strstr(err, "truncated"));
    CHECK(!asset_file_read(&x, dir, &lim, err, sizeof(err)) && strstr(err, "regular"));
    unlink(other);
    /* A write into a missing folder fails cleanly and leaves no temporary. */
    snprintf(other, sizeof(other), "%s/nope/a.sbasset", dir);
    CHECK(!asset_file_write(&a, other, err, sizeof(err)) && strstr(err, "temporary"));

    free(buf);
    free(good);
    asset_finish(&a);
    unlink(path);
    rmdir(dir);
    return check_finish("test_asset");
}
