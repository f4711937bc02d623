#define _POSIX_C_SOURCE 200809L
/* The converter's core (asset_convert.h). Three stages:
 *
 * 1. Checks, with jansson, before anything else reads the file: the GLB
 *    container, the JSON, every buffer, bufferView and accessor range, the
 *    index values, the node graph (a forest, bounded depth), the images'
 *    signatures and sizes, the URIs (data: only), and the declared counts
 *    against the limits. assimp trusts what it reads; these checks are what
 *    keeps malformed input away from it, and they allocate nothing in
 *    proportion to a declared count.
 * 2. assimp imports the geometry from memory: accessors of every type,
 *    strips and fans triangulated, normals generated where absent, tangents
 *    where the file has none. Its meshes are one per glTF primitive, in
 *    order (glTF2Importer's meshOffsets), so primitive p of mesh m is
 *    mMeshes[offset(m) + p].
 * 3. The rest comes from the checked JSON, where assimp loses it: the node
 *    tree and its world matrices (assimp keeps them, but folds lights and
 *    cameras into nodes by name), materials with each slot's TEXCOORD set
 *    and sampler filters, KHR_lights_punctual's intensity and range, the
 *    cameras' yfov, and the images, decoded here with libpng and libjpeg
 *    from the bytes stage 1 checked. */
#include "daemon/assets/asset_convert.h"
#include "daemon/assets/uv_charts.h"

#include <assimp/cimport.h>
#include <assimp/mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <inttypes.h>
#include <jpeglib.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    char *ignored[MAX_IGNORED];
    uint32_t nignored;
};

static bool fail(struct ctx *c, int status, const char *field, const char *fmt, ...)
{
    if (c->err->status == 0) {
        c->err->status = status;
        snprintf(c->err->field, sizeof(c->err->field), "%s", field);
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->err->message, sizeof(c->err->message), fmt, ap);
        va_end(ap);
    }
    return false;
}

static void ignore(struct ctx *c, const char *fmt, ...)
{
    char buf[128];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    for (uint32_t i = 0; i < c->nignored; i++)
        if (strcmp(c->ignored[i], buf) == 0)
            return;
    if (c->nignored < MAX_IGNORED) {
        char *s = strdup(buf);
        if (s)
            c->ignored[c->nignored++] = s;
    }
}

/* ---- JSON helpers: each names the field it refuses ---- */

/* The array at key (NULL when absent); anything else there is an error. */
static bool opt_array(struct ctx *c, json_t *obj, const char *key, const char *field, json_t **out)
{
    json_t *v = json_object_get(obj, key);
    *out = NULL;
    if (!v)
        return true;
    if (!json_is_array(v))
        return fail(c, 400, field, "must be an array");
    if (json_array_size(v) > MAX_ENTRIES)
        return fail(c, 422, field, "%zu entries, more than the converter takes (%d)",
                    json_array_size(v), MAX_ENTRIES);
    *out = v;
    return true;
}

/* An integer in [min, max] at key; def when absent and not required. */
static bool get_int(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
                    int64_t min, int64_t max, int64_t def, int64_t *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v) {
        if (required)
            return fail(c, 400, field, "%s is missing", key);
        *out = def;
        return true;
    }
    if (!json_is_integer(v))
        return fail(c, 400, field, "%s must be an integer", key);
    json_int_t x = json_integer_value(v);
    if (x < min || x > max)
        return fail(c, 400, field, "%s is %lld, must be %lld to %lld", key, (long long)x,
                    (long long)min, (long long)max);
    *out = x;
    return true;
}

/* An index into an array of n entries. */
static bool get_index(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
                      size_t n, int64_t *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v && !required) {
        *out = -1;
        return true;
    }
    if (!get_int(c, obj, key, field, required, 0, INT32_MAX, -1, out))
        return false;
    if ((uint64_t)*out >= n)
        return fail(c, 400, field, "%s %lld is out of range (%zu entries)", key, (long long)*out, n);
    return true;
}

static double num_or(json_t *obj, const char *key, double def)
{
    /* Bounded so that every float the asset holds is finite. */
    json_t *v = json_object_get(obj, key);
    double x = json_is_number(v) ? json_number_value(v) : def;
    return isfinite(x) && fabs(x) <= 1e30 ? x : def;
}

/* n numbers at key into out (left as they are when absent). */
static bool get_floats(struct ctx *c, json_t *obj, const char *key, const char *field, size_t n,
                       double *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_array(v) || json_array_size(v) != n)
        return fail(c, 400, field, "%s must be an array of %zu numbers", key, n);
    for (size_t i = 0; i < n; i++) {
        json_t *x = json_array_get(v, i);
        if (!json_is_number(x) || !(fabs(json_number_value(x)) <= 1e30))
            return fail(c, 400, field, "%s must be an array of %zu finite numbers", key, n);
        out[i] = json_number_value(x);
    }
    return true;
}

/* A name cut at ASSET_NAME_MAX - 1 bytes may end inside a UTF-8
 * sequence: drop the partial sequence, so that the name stays text. */
static void utf8_trim(char *s)
{
    size_t n = strlen(s), i = n;
    while (i > 0 && ((unsigned char)s[i - 1] & 0xC0) == 0x80)
        i--;
    if (i > 0 && (unsigned char)s[i - 1] >= 0xC0) {
        unsigned char lead = (unsigned char)s[i - 1];
        size_t want = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : 2;
        if (n - (i - 1) < want)
            s[i - 1] = '\0';
    }
}

static void copy_name(char *dst, json_t *obj, const char *fallback)
{
    const char *s = json_string_value(json_object_get(obj, "name"));
    snprintf(dst, ASSET_NAME_MAX, "%s", s && s[0] ? s : fallback);
    utf8_trim(dst);
}

/* ---- data URIs ---- */

static int b64_value(uint8_t ch)
{
    if (ch >= 'A' && ch <= 'Z')
        return ch - 'A';
    if (ch >= 'a' && ch <= 'z')
        return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9')
        return ch - '0' + 52;
    if (ch == '+' || ch == '-')
        return 62;
    if (ch == '/' || ch == '_')
        return 63;
    return -1;
}

/* Decodes a "data:...;base64,..." URI into an owned buffer; false (with the
 * error set) for any other URI: a relative path or file: URL would make the
 * converter read outside the uploaded file. */
static bool decode_uri(struct ctx *c, const char *uri, const char *field, struct span *out)
{
    if (strncmp(uri, "data:", 5) != 0)
        return fail(c, 400, field,
                    "only data: URIs and the GLB buffer are accepted (URIs pointing outside the "
                    "file are refused)");
    const char *comma = strchr(uri, ',');
    if (!comma)
        return fail(c, 400, field, "data: URI without a comma");
    size_t hlen = (size_t)(comma - uri);
    if (hlen < 7 || strncmp(comma - 7, ";base64", 7) != 0)
        return fail(c, 400, field, "data: URI is not base64");
    /* The media type as type/subtype of plain characters: assimp parses it
     * too, and 5.2 reads past a missing slash. */
    const char *mt = uri + 5, *mt_end = comma - 7;
    int slashes = 0;
    for (const char *q = mt; q < mt_end; q++) {
        bool plain = (*q >= 'a' && *q <= 'z') || (*q >= 'A' && *q <= 'Z') || (*q >= '0' && *q <= '9') ||
                     *q == '.' || *q == '+' || *q == '-' || *q == '/';
        if (!plain)
            return fail(c, 400, field, "data: URI has a malformed media type");
        slashes += *q == '/';
    }
    if (slashes != 1 || mt[0] == '/' || mt_end[-1] == '/')
        return fail(c, 400, field, "data: URI has no type/subtype media type");
    const uint8_t *p = (const uint8_t *)comma + 1;
    size_t n = strlen((const char *)p);
    uint8_t *buf = malloc(n / 4 * 3 + 3);
    if (!buf)
        return fail(c, 500, field, "out of memory");
    size_t o = 0;
    uint32_t acc = 0;
    int bits = 0;
    for (size_t i = 0; i < n; i++) {
        if (p[i] == '=')
            break;
        int v = b64_value(p[i]);
        if (v < 0) {
            free(buf);
            return fail(c, 400, field, "data: URI has a byte that is not base64 at %zu", i);
        }
        acc = (acc << 6) | (uint32_t)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            buf[o++] = (uint8_t)(acc >> bits);
        }
    }
    uint8_t **owned = realloc(c->owned, (c->nowned + 1) * sizeof(*owned));
    if (!owned) {
        free(buf);
        return fail(c, 500, field, "out of memory");
    }
    c->owned = owned;
    c->owned[c->nowned++] = buf;
    out->data = buf;
    out->len = o;
    return true;
}

/* ---- images: signatures and sizes from the header, before decoding ---- */

static bool is_png(struct span s)
{
    return s.len >= 24 && memcmp(s.data, "\x89PNG\r\n\x1a\n", 8) == 0;
}

static bool is_jpeg(struct span s)
{
    return s.len >= 4 && s.data[0] == 0xFF && s.data[1] == 0xD8 && s.data[2] == 0xFF;
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Width and height from the PNG IHDR or the first JPEG SOF marker. */
static bool image_size(struct span s, uint32_t *w, uint32_t *h)
{
    if (is_png(s)) {
        if (memcmp(s.data + 12, "IHDR", 4) != 0)
            return false;
        *w = be32(s.data + 16);
        *h = be32(s.data + 20);
        return true;
    }
    size_t i = 2;
    while (i + 4 <= s.len) {
        if (s.data[i] != 0xFF)
            return false;
        uint8_t m = s.data[i + 1];
        if (m == 0xFF) {
            i++;
            continue;
        }
        if (m == 0xD8 || (m >= 0xD0 && m <= 0xD7) || m == 0x01) {
            i += 2;
            continue;
        }
        size_t seg = (size_t)s.data[i + 2] << 8 | s.data[i + 3];
        if (seg < 2)
            return false;
        bool sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
        if (sof) {
            if (i + 9 > s.len)
                return false;
            *h = (uint32_t)s.data[i + 5] << 8 | s.data[i + 6];
            *w = (uint32_t)s.data[i + 7] << 8 | s.data[i + 8];
            return true;
        }
        i += 2 + seg;
    }
    return false;
}

/* ---- stage 1: the checks ---- */

static bool check_container(struct ctx *c, const uint8_t *data, size_t len)
{
    if (len >= 4 && memcmp(data, "glTF", 4) == 0) {
        c->glb = true;
        if (len < 20)
            return fail(c, 400, "file", "truncated GLB: %zu bytes, the header needs 20", len);
        uint32_t version = data[4] | data[5] << 8 | data[6] << 16 | (uint32_t)data[7] << 24;
        uint32_t total = data[8] | data[9] << 8 | data[10] << 16 | (uint32_t)data[11] << 24;
        if (version != 2)
            return fail(c, 422, "file", "GLB version %u, only 2 is supported", version);
        if (total != len)
            return fail(c, 400, "file", "GLB header says %u bytes, the file has %zu%s", total, len,
                        total > len ? " (truncated)" : "");
        size_t off = 12;
        const uint8_t *json = NULL;
        size_t json_len = 0;
        int chunk = 0;
        while (off < len) {
            if (len - off < 8)
                return fail(c, 400, "file", "truncated GLB chunk header at byte %zu", off);
            uint32_t clen = data[off] | data[off + 1] << 8 | data[off + 2] << 16 |
                            (uint32_t)data[off + 3] << 24;
            uint32_t type = data[off + 4] | data[off + 5] << 8 | data[off + 6] << 16 |
                            (uint32_t)data[off + 7] << 24;
            off += 8;
            if (clen > len - off)
                return fail(c, 400, "file", "GLB chunk %d claims %u bytes, %zu left", chunk, clen,
                            len - off);
            if (chunk == 0) {
                if (type != 0x4E4F534Au)
                    return fail(c, 400, "file", "the first GLB chunk is not JSON");
                json = data + off;
                json_len = clen;
            } else if (type == 0x004E4942u) {
                if (c->bin.data)
                    return fail(c, 400, "file", "more than one BIN chunk");
                c->bin.data = data + off;
                c->bin.len = clen;
            }
            off += clen;
            chunk++;
        }
        if (!json)
            return fail(c, 400, "file", "GLB without a JSON chunk");
        data = json;
        len = json_len;
    } else {
        size_t i = 0;
        if (len >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0)
            i = 3;
        while (i < len && (data[i] == ' ' || data[i] == '\n' || data[i] == '\r' || data[i] == '\t'))
            i++;
        if (i >= len || data[i] != '{')
            return fail(c, 400, "file", "not a glTF file: neither the GLB magic nor a JSON object");
    }
    json_error_t je;
    c->root = json_loadb((const char *)data, len, JSON_REJECT_DUPLICATES, &je);
    if (!c->root && json_error_code(&je) == json_error_out_of_memory)
        return fail(c, 500, "file", "out of memory parsing the JSON");
    if (!c->root)
        return fail(c, 400, "file", "bad JSON at line %d, column %d: %s", je.line, je.column, je.text);
    if (!json_is_object(c->root))
        return fail(c, 400, "file", "the JSON is not an object");
    return true;
}

static bool check_asset_and_extensions(struct ctx *c)
{
    json_t *asset = json_object_get(c->root, "asset");
    const char *version = json_string_value(json_object_get(asset, "version"));
    if (!version)
        return fail(c, 400, "asset.version", "missing");
    if (version[0] != '2')
        return fail(c, 422, "asset.version", "glTF %s, only 2.x is supported", version);
    static const char *const handled[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength"};
    json_t *req = json_object_get(c->root, "extensionsRequired");
    size_t i;
    json_t *v;
    json_array_foreach(req, i, v) {
        const char *name = json_string_value(v);
        bool ok = name && (strcmp(name, handled[0]) == 0 || strcmp(name, handled[1]) == 0 ||
                           strcmp(name, "KHR_texture_transform") == 0 ||
                           strcmp(name, "KHR_materials_unlit") == 0);
        if (!ok) {
            char field[64];
            snprintf(field, sizeof(field), "extensionsRequired[%zu]", i);
            return fail(c, 422, field, "required extension %s is not supported", name ? name : "?");
        }
    }
    json_array_foreach(json_object_get(c->root, "extensionsUsed"), i, v) {
        const char *name = json_string_value(v);
        if (name && strcmp(name, handled[0]) != 0 && strcmp(name, handled[1]) != 0)
            ignore(c, "extension %s", name);
    }
    if (json_array_size(json_object_get(c->root, "animations")))
        ignore(c, "animations");
    if (json_array_size(json_object_get(c->root, "skins")))
        ignore(c, "skins");
    return true;
}

static bool check_buffers(struct ctx *c)
{
    json_t *buffers;
    if (!opt_array(c, c->root, "buffers", "buffers", &buffers))
        return false;
    c->nbuffers = json_array_size(buffers);
    if (c->nbuffers && !(c->buffers = calloc(c->nbuffers, sizeof(*c->buffers))))
        return fail(c, 500, "buffers", "out of memory");
    for (size_t i = 0; i < c->nbuffers; i++) {
        json_t *b = json_array_get(buffers, i);
        char field[64];
        snprintf(field, sizeof(field), "buffers[%zu]", i);
        int64_t blen;
        if (!json_is_object(b))
            return fail(c, 400, field, "must be an object");
        if (!get_int(c, b, "byteLength", field, true, 1, INT64_C(1) << 40, 0, &blen))
            return false;
        json_t *uri = json_object_get(b, "uri");
        struct span s;
        if (uri) {
            snprintf(field, sizeof(field), "buffers[%zu].uri", i);
            if (!json_is_string(uri))
                return fail(c, 400, field, "must be a string");
            if (!decode_uri(c, json_string_value(uri), field, &s))
                return false;
        } else {
            if (!c->glb || i != 0 || !c->bin.data)
                return fail(c, 400, field, "no uri and no GLB BIN chunk to take its bytes from");
            s = c->bin;
        }
        if ((uint64_t)blen > s.len) {
            snprintf(field, sizeof(field), "buffers[%zu].byteLength", i);
            return fail(c, 400, field, "byteLength %" PRId64 " but only %" PRIu64 " bytes of data",
                        blen, s.len);
        }
        s.len = (uint64_t)blen;
        c->buffers[i] = s;
    }
    return true;
}

/* A bufferView's bytes, checked against its buffer. */
static bool view_span(struct ctx *c, size_t v, struct span *out, int64_t *stride)
{
    json_t *bv = json_array_get(c->views, v);
    char field[64];
    snprintf(field, sizeof(field), "bufferViews[%zu]", v);
    int64_t buf, off, len;
    if (!json_is_object(bv))
        return fail(c, 400, field, "must be an object");
    if (!get_index(c, bv, "buffer", field, true, c->nbuffers, &buf) ||
        !get_int(c, bv, "byteOffset", field, false, 0, INT64_C(1) << 40, 0, &off) ||
        !get_int(c, bv, "byteLength", field, true, 1, INT64_C(1) << 40, 0, &len) ||
        !get_int(c, bv, "byteStride", field, false, 4, 252, 0, stride))
        return false;
    if (*stride % 4)
        return fail(c, 400, field, "byteStride %" PRId64 " is not a multiple of 4", *stride);
    struct span b = c->buffers[buf];
    if ((uint64_t)off > b.len || (uint64_t)len > b.len - (uint64_t)off)
        return fail(c, 400, field, "bytes %" PRId64 " to %" PRId64 " run past buffer %" PRId64
                    " (%" PRIu64 " bytes)", off, off + len, buf, b.len);
    out->data = b.data + off;
    out->len = (uint64_t)len;
    return true;
}

static int component_size(int64_t t)
{
    switch (t) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
    }
}

static int type_components(const char *t)
{
    static const char *const names[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
    static const int n[] = {1, 2, 3, 4, 4, 9, 16};
    for (int i = 0; t && i < 7; i++)
        if (strcmp(t, names[i]) == 0)
            return n[i];
    return 0;
}

struct accessor {
    struct span view; /* the bufferView's bytes */
    uint64_t offset, count, stride;
    int64_t ctype;
    int ncomp;
};

static bool check_accessor(struct ctx *c, size_t i, struct accessor *a)
{
    json_t *acc = json_array_get(c->accessors, i);
    char field[64];
    snprintf(field, sizeof(field), "accessors[%zu]", i);
    if (!json_is_object(acc))
        return fail(c, 400, field, "must be an object");
    int64_t view, off, count, ctype;
    if (!get_int(c, acc, "componentType", field, true, 0, 1 << 20, 0, &ctype) ||
        !get_int(c, acc, "count", field, true, 1, INT64_C(1) << 40, 0, &count) ||
        !get_int(c, acc, "byteOffset", field, false, 0, INT64_C(1) << 40, 0, &off))
        return false;
    int csize = component_size(ctype);
    int ncomp = type_components(json_string_value(json_object_get(acc, "type")));
    if (!csize)
        return fail(c, 400, field, "componentType %" PRId64 " is not a glTF component type", ctype);
    if (!ncomp)
        return fail(c, 400, field, "type is not SCALAR, VECn or MATn");
    /* A declared count is checked before anything is sized by it. */
    uint64_t most = c->lim->max_vertices > c->lim->max_indices ? c->lim->max_vertices
                                                               : c->lim->max_indices;
    if ((uint64_t)count > most)
        return fail(c, 422, field, "count %" PRId64 " is over the vertex and index limits (%" PRIu64
                    ")", count, most);
    if (json_object_get(acc, "sparse"))
        return fail(c, 422, field, "sparse accessors are not supported");
    if (!json_object_get(acc, "bufferView"))
        return fail(c, 422, field, "an accessor without a bufferView (all zeros) is not supported");
    if (!get_index(c, acc, "bufferView", field, true, json_array_size(c->views), &view))
        return false;
    int64_t stride;
    if (!view_span(c, (size_t)view, &a->view, &stride))
        return false;
    uint64_t elem = (uint64_t)csize * (uint64_t)ncomp;
    if (stride && (uint64_t)stride < elem)
        return fail(c, 400, field, "byteStride %" PRId64 " is smaller than an element (%" PRIu64 ")",
                    stride, elem);
    if (off % csize)
        return fail(c, 400, field, "byteOffset %" PRId64 " is not a multiple of the component size",
                    off);
    a->stride = stride ? (uint64_t)stride : elem;
    /* count <= 2^40 and stride <= 252: no overflow in 64 bits. */
    uint64_t need = (uint64_t)off + a->stride * ((uint64_t)count - 1) + elem;
    if (need > a->view.len)
        return fail(c, 400, field, "%" PRId64 " elements need %" PRIu64 " bytes, bufferView %" PRId64
                    " has %" PRIu64, count, need, view, a->view.len);
    a->offset = (uint64_t)off;
    a->count = (uint64_t)count;
    a->ctype = ctype;
    a->ncomp = ncomp;
    return true;
}

static bool check_accessors(struct ctx *c)
{
    if (!opt_array(c, c->root, "accessors", "accessors", &c->accessors) ||
        !opt_array(c, c->root, "bufferViews", "bufferViews", &c->views))
        return false;
    for (size_t v = 0; v < json_array_size(c->views); v++) {
        struct span s;
        int64_t stride;
        if (!view_span(c, v, &s, &stride))
            return false;
    }
    for (size_t i = 0; i < json_array_size(c->accessors); i++) {
        struct accessor a;
        if (!check_accessor(c, i, &a))
            return false;
    }
    return true;
}

static uint32_t read_index(const struct accessor *a, uint64_t k)
{
    const uint8_t *p = a->view.data + a->offset + a->stride * k;
    switch (a->ctype) {
    case 5121: return p[0];
    case 5123: return (uint32_t)p[0] | (uint32_t)p[1] << 8;
    default: return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    }
}

struct prim_info {
    uint64_t vertices, indices; /* as the file has them */
    uint64_t triangles;
    bool has_uv1, has_tangent, triangles_mode;
    int64_t uv_accessor[2]; /* TEXCOORD_0 and _1's accessors, -1 for none */
};

static bool check_attribute(struct ctx *c, json_t *attrs, const char *name, const char *field,
                            uint64_t vcount, const int64_t *ctypes, int ncomp, bool *present)
{
    json_t *v = json_object_get(attrs, name);
    *present = v != NULL;
    if (!v)
        return true;
    char f[128];
    snprintf(f, sizeof(f), "%s.%s", field, name);
    int64_t idx;
    if (!get_index(c, attrs, name, f, true, json_array_size(c->accessors), &idx))
        return false;
    struct accessor a;
    if (!check_accessor(c, (size_t)idx, &a))
        return false;
    bool ok = false;
    for (int k = 0; ctypes[k]; k++)
        ok |= a.ctype == ctypes[k];
    if (!ok || a.ncomp != ncomp)
        return fail(c, 400, f, "accessor %" PRId64 " has the wrong type for %s", idx, name);
    if (vcount && a.count != vcount)
        return fail(c, 400, f, "accessor %" PRId64 " has %" PRIu64 " elements, POSITION has %" PRIu64,
                    idx, a.count, vcount);
    return true;
}

static bool check_primitive(struct ctx *c, size_t m, size_t p, json_t *prim, struct prim_info *pi)
{
    char field[96];
    snprintf(field, sizeof(field), "meshes[%zu].primitives[%zu]", m, p);
    memset(pi, 0, sizeof(*pi));
    if (!json_is_object(prim))
        return fail(c, 400, field, "must be an object");
    json_t *attrs = json_object_get(prim, "attributes");
    if (!json_is_object(attrs))
        return fail(c, 400, field, "attributes must be an object");
    int64_t mode, mat;
    if (!get_int(c, prim, "mode", field, false, 0, INT32_MAX, 4, &mode))
        return false;
    if (mode > 6)
        return fail(c, 422, field, "primitive mode %" PRId64 " is not supported", mode);
    if (!get_index(c, prim, "material", field, false, json_array_size(c->materials), &mat))
        return false;
    if (json_array_size(json_object_get(prim, "targets")))
        ignore(c, "morph targets");
    char f[128];
    snprintf(f, sizeof(f), "%s.attributes.POSITION", field);
    int64_t pos;
    if (!json_object_get(attrs, "POSITION"))
        return fail(c, 422, f, "a primitive without POSITION is not supported");
    if (!get_index(c, attrs, "POSITION", f, true, json_array_size(c->accessors), &pos))
        return false;
    struct accessor pa;
    if (!check_accessor(c, (size_t)pos, &pa))
        return false;
    if (pa.ctype != 5126 || pa.ncomp != 3)
        return fail(c, 400, f, "POSITION must be a float VEC3 accessor");
    pi->vertices = pa.count;
    static const int64_t FLOAT[] = {5126, 0};
    static const int64_t UV[] = {5126, 5121, 5123, 0};
    static const int64_t ANY[] = {5120, 5121, 5122, 5123, 5125, 5126, 0};
    bool present;
    snprintf(f, sizeof(f), "%s.attributes", field);
    if (!check_attribute(c, attrs, "NORMAL", f, pa.count, FLOAT, 3, &present) ||
        !check_attribute(c, attrs, "TANGENT", f, pa.count, FLOAT, 4, &pi->has_tangent) ||
        !check_attribute(c, attrs, "TEXCOORD_0", f, pa.count, UV, 2, &present) ||
        !check_attribute(c, attrs, "TEXCOORD_1", f, pa.count, UV, 2, &pi->has_uv1))
        return false;
    for (int set = 0; set < 2; set++) {
        json_t *uv = json_object_get(attrs, set ? "TEXCOORD_1" : "TEXCOORD_0");
        pi->uv_accessor[set] = uv ? json_integer_value(uv) : -1;
    }
    /* The rest are checked for range (assimp reads colours, joints and
     * weights too), whatever their type. */
    const char *key;
    json_t *v;
    json_object_foreach(attrs, key, v) {
        snprintf(f, sizeof(f), "%s.attributes.%s", field, key);
        int64_t idx;
        if (!get_index(c, attrs, key, f, true, json_array_size(c->accessors), &idx))
            return false;
        struct accessor a;
        if (!check_accessor(c, (size_t)idx, &a))
            return false;
        if (a.count != pa.count)
            return fail(c, 400, f, "accessor %" PRId64 " has %" PRIu64 " elements, POSITION has %"
                        PRIu64, idx, a.count, pa.count);
        (void)ANY;
    }
    uint64_t n = pa.count;
    if (json_object_get(prim, "indices")) {
        snprintf(f, sizeof(f), "%s.indices", field);
        int64_t idx;
        if (!get_index(c, prim, "indices", f, true, json_array_size(c->accessors), &idx))
            return false;
        struct accessor ia;
        if (!check_accessor(c, (size_t)idx, &ia))
            return false;
        if (ia.ncomp != 1 || (ia.ctype != 5121 && ia.ctype != 5123 && ia.ctype != 5125))
            return fail(c, 400, f, "indices must be an unsigned SCALAR accessor");
        if (ia.stride != (uint64_t)component_size(ia.ctype))
            return fail(c, 400, f, "an index accessor's bufferView must not have a byteStride");
        for (uint64_t k = 0; k < ia.count; k++) {
            uint32_t x = read_index(&ia, k);
            if (x >= pa.count)
                return fail(c, 400, f, "index %" PRIu64 " is %u, POSITION has %" PRIu64 " vertices",
                            k, x, pa.count);
        }
        n = ia.count;
        pi->indices = ia.count;
    }
    pi->triangles_mode = mode >= 4;
    if (mode == 4)
        pi->triangles = n / 3;
    else if (mode >= 5)
        pi->triangles = n >= 3 ? n - 2 : 0;
    else
        ignore(c, "points and lines primitives");
    return true;
}

static bool check_graph(struct ctx *c, int64_t *scene_index)
{
    json_t *scenes;
    if (!opt_array(c, c->root, "nodes", "nodes", &c->nodes) ||
        !opt_array(c, c->root, "scenes", "scenes", &scenes))
        return false;
    size_t n = json_array_size(c->nodes);
    if (n && !(c->parent = malloc(n * sizeof(int))))
        return fail(c, 500, "nodes", "out of memory");
    for (size_t i = 0; i < n; i++)
        c->parent[i] = -1;
    for (size_t i = 0; i < n; i++) {
        json_t *node = json_array_get(c->nodes, i);
        char field[64];
        snprintf(field, sizeof(field), "nodes[%zu]", i);
        if (!json_is_object(node))
            return fail(c, 400, field, "must be an object");
        json_t *children;
        if (!opt_array(c, node, "children", field, &children))
            return false;
        size_t k;
        json_t *ch;
        json_array_foreach(children, k, ch) {
            if (!json_is_integer(ch) || json_integer_value(ch) < 0 ||
                (uint64_t)json_integer_value(ch) >= n)
                return fail(c, 400, field, "children[%zu] is not a node index", k);
            size_t child = (size_t)json_integer_value(ch);
            if (c->parent[child] != -1 || child == i)
                return fail(c, 400, field, "node %zu has more than one parent (or is its own)", child);
            c->parent[child] = (int)i;
        }
        int64_t idx;
        double m16[16], v[4];
        if (!get_index(c, node, "mesh", field, false, json_array_size(c->meshes), &idx) ||
            !get_index(c, node, "camera", field, false, json_array_size(c->cameras), &idx) ||
            !get_floats(c, node, "matrix", field, 16, m16) ||
            !get_floats(c, node, "translation", field, 3, v) ||
            !get_floats(c, node, "rotation", field, 4, v) ||
            !get_floats(c, node, "scale", field, 3, v))
            return false;
        if (json_object_get(node, "skin"))
            ignore(c, "skins");
        json_t *lp = json_object_get(json_object_get(node, "extensions"), "KHR_lights_punctual");
        if (lp && !get_index(c, lp, "light", field, true, json_array_size(c->lights), &idx))
            return false;
    }
    /* Depth bounded and no cycle: walk up from each node. A cycle has no
     * root, so its walk runs past MAX_NODE_DEPTH too. */
    for (size_t i = 0; i < n; i++) {
        int depth = 0;
        for (int p = c->parent[i]; p != -1; p = c->parent[p])
            if (++depth > MAX_NODE_DEPTH) {
                char field[64];
                snprintf(field, sizeof(field), "nodes[%zu]", i);
                return fail(c, 422, field, "the node hierarchy is deeper than %d levels (or a cycle)",
                            MAX_NODE_DEPTH);
            }
    }
    if (!json_array_size(scenes))
        return fail(c, 422, "scenes", "no scene");
    if (!get_index(c, c->root, "scene", "scene", false, json_array_size(scenes), scene_index))
        return false;
    if (*scene_index < 0)
        *scene_index = 0;
    json_t *roots;
    json_t *scene = json_array_get(scenes, (size_t)*scene_index);
    char field[64];
    snprintf(field, sizeof(field), "scenes[%" PRId64 "]", *scene_index);
    if (!json_is_object(scene) || !opt_array(c, scene, "nodes", field, &roots))
        return fail(c, 400, field, "must be an object with a nodes array");
    size_t k;
    json_t *r;
    json_array_foreach(roots, k, r) {
        if (!json_is_integer(r) || json_integer_value(r) < 0 || (uint64_t)json_integer_value(r) >= n)
            return fail(c, 400, field, "nodes[%zu] is not a node index", k);
        if (c->parent[json_integer_value(r)] != -1)
            return fail(c, 400, field, "nodes[%zu] is not a root node", k);
    }
    return true;
}

/* Counts what the scene instances against the limits, before any import. */
static bool check_meshes(struct ctx *c, int64_t scene_index, struct prim_info ***infos)
{
    size_t nm = json_array_size(c->meshes);
    *infos = nm ? calloc(nm, sizeof(**infos)) : NULL;
    if (nm && !*infos)
        return fail(c, 500, "meshes", "out of memory");
    for (size_t m = 0; m < nm; m++) {
        json_t *mesh = json_array_get(c->meshes, m);
        char field[64];
        snprintf(field, sizeof(field), "meshes[%zu]", m);
        json_t *prims;
        if (!json_is_object(mesh) || !opt_array(c, mesh, "primitives", field, &prims) ||
            !json_array_size(prims))
            return fail(c, 400, field, "must be an object with primitives");
        (*infos)[m] = calloc(json_array_size(prims), sizeof(struct prim_info));
        if (!(*infos)[m])
            return fail(c, 500, field, "out of memory");
        for (size_t p = 0; p < json_array_size(prims); p++)
            if (!check_primitive(c, m, p, json_array_get(prims, p), &(*infos)[m][p]))
                return false;
    }
    /* Every node of the scene: instances of each mesh. */
    json_t *roots = json_object_get(json_array_get(json_object_get(c->root, "scenes"),
                                                   (size_t)scene_index), "nodes");
    uint64_t vertices = 0, indices = 0, meshes = 0, triangles = 0;
    for (size_t i = 0; i < json_array_size(c->nodes); i++) {
        int top = (int)i;
        while (c->parent[top] != -1)
            top = c->parent[top];
        bool in_scene = false;
        for (size_t k = 0; k < json_array_size(roots); k++)
            in_scene |= json_integer_value(json_array_get(roots, k)) == top;
        json_t *mi = json_object_get(json_array_get(c->nodes, i), "mesh");
        if (!in_scene || !mi)
            continue;
        size_t m = (size_t)json_integer_value(mi);
        json_t *prims = json_object_get(json_array_get(c->meshes, m), "primitives");
        for (size_t p = 0; p < json_array_size(prims); p++) {
            struct prim_info *pi = &(*infos)[m][p];
            if (!pi->triangles)
                continue;
            meshes++;
            triangles += pi->triangles;
            /* Generated uv1 gives each triangle its own three vertices. */
            vertices += pi->has_uv1 ? pi->vertices : 3 * pi->triangles;
            indices += 3 * pi->triangles;
        }
    }
    if (meshes > c->lim->max_meshes)
        return fail(c, 422, "limits.max_meshes", "%" PRIu64 " mesh instances, the limit is %u",
                    meshes, c->lim->max_meshes);
    if (vertices > c->lim->max_vertices)
        return fail(c, 422, "limits.max_vertices", "%" PRIu64 " vertices, the limit is %" PRIu64,
                    vertices, c->lim->max_vertices);
    if (indices > c->lim->max_indices)
        return fail(c, 422, "limits.max_indices", "%" PRIu64 " indices, the limit is %" PRIu64,
                    indices, c->lim->max_indices);
    if (!triangles)
        return fail(c, 422, "meshes", "the scene has no triangles");
    return true;
}

static bool check_images(struct ctx *c)
{
    c->nimages = json_array_size(c->imgs);
    if (c->nimages > c->lim->max_images)
        return fail(c, 422, "limits.max_images", "%zu images, the limit is %u", c->nimages,
                    c->lim->max_images);
    if (c->nimages && !(c->images = calloc(c->nimages, sizeof(*c->images))))
        return fail(c, 500, "images", "out of memory");
    uint64_t pixels = 0;
    for (size_t i = 0; i < c->nimages; i++) {
        json_t *im = json_array_get(c->imgs, i);
        char field[64];
        snprintf(field, sizeof(field), "images[%zu]", i);
        if (!json_is_object(im))
            return fail(c, 400, field, "must be an object");
        json_t *uri = json_object_get(im, "uri");
        if (uri) {
            char f[80];
            snprintf(f, sizeof(f), "images[%zu].uri", i);
            if (!json_is_string(uri))
                return fail(c, 400, f, "must be a string");
            if (!decode_uri(c, json_string_value(uri), f, &c->images[i]))
                return false;
        } else {
            int64_t view, stride;
            /* Required with a bufferView, and one of the two glTF allows
             * (assimp 5.2 reads past a mimeType without a slash). */
            const char *mime = json_string_value(json_object_get(im, "mimeType"));
            if (!mime || (strcmp(mime, "image/png") != 0 && strcmp(mime, "image/jpeg") != 0)) {
                char f[80];
                snprintf(f, sizeof(f), "images[%zu].mimeType", i);
                return fail(c, 400, f, "must be image/png or image/jpeg");
            }
            if (!get_index(c, im, "bufferView", field, true, json_array_size(c->views), &view) ||
                !view_span(c, (size_t)view, &c->images[i], &stride))
                return false;
        }
        uint32_t w = 0, h = 0;
        if (!is_png(c->images[i]) && !is_jpeg(c->images[i]))
            return fail(c, 400, field, "not a PNG or JPEG image");
        if (!image_size(c->images[i], &w, &h) || w == 0 || h == 0)
            return fail(c, 400, field, "cannot read the image's size from its header");
        if (w > c->lim->max_texture_edge || h > c->lim->max_texture_edge)
            return fail(c, 422, "limits.max_texture_edge", "images[%zu] is %ux%u, the limit is %u",
                        i, w, h, c->lim->max_texture_edge);
        pixels += (uint64_t)w * h;
        if (pixels > c->lim->max_texture_pixels)
            return fail(c, 422, "limits.max_texture_pixels",
                        "%" PRIu64 " texture pixels up to images[%zu], the limit is %" PRIu64,
                        pixels, i, c->lim->max_texture_pixels);
    }
    return true;
}

static bool check_textures_materials(struct ctx *c)
{
    if (json_array_size(c->materials) > c->lim->max_materials)
        return fail(c, 422, "limits.max_materials", "%zu materials, the limit is %u",
                    json_array_size(c->materials), c->lim->max_materials);
    for (size_t i = 0; i < json_array_size(c->textures); i++) {
        json_t *t = json_array_get(c->textures, i);
        char field[64];
        snprintf(field, sizeof(field), "textures[%zu]", i);
        int64_t source, sampler;
        if (!json_is_object(t))
            return fail(c, 400, field, "must be an object");
        if (!get_index(c, t, "source", field, false, c->nimages, &source) ||
            !get_index(c, t, "sampler", field, false, json_array_size(c->samplers), &sampler))
            return false;
        if (source < 0 && json_object_get(t, "extensions"))
            ignore(c, "textures in extension formats");
    }
    for (size_t i = 0; i < json_array_size(c->samplers); i++) {
        json_t *smp = json_array_get(c->samplers, i);
        char field[64];
        snprintf(field, sizeof(field), "samplers[%zu]", i);
        int64_t ws, wt, mn, mg;
        if (!json_is_object(smp) ||
            !get_int(c, smp, "wrapS", field, false, 0, 65535, 10497, &ws) ||
            !get_int(c, smp, "wrapT", field, false, 0, 65535, 10497, &wt) ||
            !get_int(c, smp, "minFilter", field, false, 0, 65535, 9987, &mn) ||
            !get_int(c, smp, "magFilter", field, false, 0, 65535, 9729, &mg))
            return fail(c, 400, field, "must be an object of GL wrap and filter values");
        bool wrap_ok = (ws == 33071 || ws == 33648 || ws == 10497) &&
                       (wt == 33071 || wt == 33648 || wt == 10497);
        bool filt_ok = (mg == 9728 || mg == 9729) && (mn == 9728 || mn == 9729 || (mn >= 9984 && mn <= 9987));
        if (!wrap_ok || !filt_ok)
            return fail(c, 400, field, "wrap or filter is not a glTF sampler value");
    }
    static const char *const slots[] = {"baseColorTexture", "metallicRoughnessTexture",
                                        "normalTexture", "occlusionTexture", "emissiveTexture"};
    for (size_t i = 0; i < json_array_size(c->materials); i++) {
        json_t *m = json_array_get(c->materials, i);
        char field[96];
        snprintf(field, sizeof(field), "materials[%zu]", i);
        if (!json_is_object(m))
            return fail(c, 400, field, "must be an object");
        json_t *pbr = json_object_get(m, "pbrMetallicRoughness");
        for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
            json_t *ti = json_object_get(s < 2 ? pbr : m, slots[s]);
            if (!ti)
                continue;
            snprintf(field, sizeof(field), "materials[%zu].%s", i, slots[s]);
            int64_t idx, set;
            if (!json_is_object(ti) ||
                !get_index(c, ti, "index", field, true, json_array_size(c->textures), &idx) ||
                !get_int(c, ti, "texCoord", field, false, 0, 1 << 20, 0, &set))
                return false;
            if (json_object_get(json_object_get(ti, "extensions"), "KHR_texture_transform"))
                ignore(c, "KHR_texture_transform");
        }
        const char *mode = json_string_value(json_object_get(m, "alphaMode"));
        if (json_object_get(m, "alphaMode") &&
            (!mode || (strcmp(mode, "OPAQUE") && strcmp(mode, "MASK") && strcmp(mode, "BLEND")))) {
            snprintf(field, sizeof(field), "materials[%zu].alphaMode", i);
            return fail(c, 400, field, "must be OPAQUE, MASK or BLEND");
        }
    }
    return true;
}

static bool check_lights_cameras(struct ctx *c)
{
    if (json_array_size(c->lights) > c->lim->max_lights)
        return fail(c, 422, "limits.max_lights", "%zu lights, the limit is %u",
                    json_array_size(c->lights), c->lim->max_lights);
    if (json_array_size(c->cameras) > c->lim->max_cameras)
        return fail(c, 422, "limits.max_cameras", "%zu cameras, the limit is %u",
                    json_array_size(c->cameras), c->lim->max_cameras);
    for (size_t i = 0; i < json_array_size(c->lights); i++) {
        json_t *l = json_array_get(c->lights, i);
        char field[96];
        snprintf(field, sizeof(field), "extensions.KHR_lights_punctual.lights[%zu]", i);
        const char *type = json_string_value(json_object_get(l, "type"));
        if (!type || (strcmp(type, "point") && strcmp(type, "spot") && strcmp(type, "directional")))
            return fail(c, 400, field, "type must be point, spot or directional");
        double col[3] = {1, 1, 1};
        if (!get_floats(c, l, "color", field, 3, col))
            return false;
    }
    for (size_t i = 0; i < json_array_size(c->cameras); i++) {
        json_t *cam = json_array_get(c->cameras, i);
        char field[64];
        snprintf(field, sizeof(field), "cameras[%zu]", i);
        const char *type = json_string_value(json_object_get(cam, "type"));
        if (!type || (strcmp(type, "perspective") && strcmp(type, "orthographic")))
            return fail(c, 400, field, "type must be perspective or orthographic");
    }
    return true;
}

/* ---- world matrices (column-major, as glTF stores them) ---- */

static void mat_mul(const double a[16], const double b[16], double out[16])
{
    double r[16];
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += a[k * 4 + row] * b[col * 4 + k];
            r[col * 4 + row] = s;
        }
    memcpy(out, r, sizeof(r));
}

static void node_local(json_t *node, double m[16])
{
    static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    memcpy(m, id, sizeof(id));
    json_t *mat = json_object_get(node, "matrix");
    if (mat) {
        for (int i = 0; i < 16; i++)
            m[i] = json_number_value(json_array_get(mat, (size_t)i));
        return;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    for (int i = 0; i < 3; i++) {
        json_t *tv = json_object_get(node, "translation"), *sv = json_object_get(node, "scale");
        if (tv)
            t[i] = json_number_value(json_array_get(tv, (size_t)i));
        if (sv)
            s[i] = json_number_value(json_array_get(sv, (size_t)i));
    }
    json_t *rv = json_object_get(node, "rotation");
    if (rv) {
        double n = 0;
        for (int i = 0; i < 4; i++) {
            q[i] = json_number_value(json_array_get(rv, (size_t)i));
            n += q[i] * q[i];
        }
        n = sqrt(n);
        if (n > 0)
            for (int i = 0; i < 4; i++)
                q[i] /= n;
    }
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                   2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int col = 0; col < 3; col++)
        for (int row = 0; row < 3; row++)
            m[col * 4 + row] = r[col * 3 + row] * s[col];
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
}

static void node_world(struct ctx *c, int i, double m[16])
{
    node_local(json_array_get(c->nodes, (size_t)i), m);
    for (int p = c->parent[i]; p != -1; p = c->parent[p]) {
        double pm[16];
        node_local(json_array_get(c->nodes, (size_t)p), pm);
        mat_mul(pm, m, m);
    }
}

static void xform_point(const double m[16], const float in[3], float out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = (float)(m[r] * in[0] + m[4 + r] * in[1] + m[8 + r] * in[2] + m[12 + r]);
}

static void xform_dir(const double m[16], const double in[3], double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m[r] * in[0] + m[4 + r] * in[1] + m[8 + r] * in[2];
}

static void normalize3(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (n > 1e-30)
        for (int i = 0; i < 3; i++)
            v[i] /= n;
}

/* The inverse transpose of the upper 3x3 (for normals), and its determinant. */
static double normal_matrix(const double m[16], double n[9])
{
    double a = m[0], b = m[4], cc = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], k = m[10];
    double det = a * (e * k - f * h) - b * (d * k - f * g) + cc * (d * h - e * g);
    /* cofactor matrix = det * inverse transpose; the scale does not matter
     * since normals are renormalised, only its sign (kept by using the
     * cofactors divided by |det| where det != 0). */
    double s = det < 0 ? -1.0 : 1.0;
    n[0] = s * (e * k - f * h);
    n[1] = s * -(d * k - f * g);
    n[2] = s * (d * h - e * g);
    n[3] = s * -(b * k - cc * h);
    n[4] = s * (a * k - cc * g);
    n[5] = s * -(a * h - b * g);
    n[6] = s * (b * f - cc * e);
    n[7] = s * -(a * f - cc * d);
    n[8] = s * (a * e - b * d);
    return det;
}

/* ---- images ---- */

static bool decode_png(struct ctx *c, struct span s, struct asset_image *im, const char *field)
{
    png_image p;
    memset(&p, 0, sizeof(p));
    p.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&p, s.data, (size_t)s.len))
        return fail(c, 400, field, "bad PNG: %s", p.message);
    p.format = PNG_FORMAT_RGBA;
    if (p.width != im->width || p.height != im->height) {
        png_image_free(&p);
        return fail(c, 400, field, "bad PNG: the size changed while reading");
    }
    /* Sized here in size_t: PNG_IMAGE_SIZE is 32-bit arithmetic. */
    im->rgba = malloc((size_t)im->width * im->height * 4);
    if (!im->rgba) {
        png_image_free(&p);
        return fail(c, 500, field, "out of memory");
    }
    if (!png_image_finish_read(&p, NULL, im->rgba, 0, NULL)) {
        png_image_free(&p);
        return fail(c, 400, field, "bad PNG: %s", p.message);
    }
    return true;
}

struct jpeg_err {
    struct jpeg_error_mgr mgr;
    jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

static void jpeg_fail(j_common_ptr cinfo)
{
    struct jpeg_err *e = (struct jpeg_err *)cinfo->err;
    cinfo->err->format_message(cinfo, e->message);
    longjmp(e->jump, 1);
}

static void jpeg_quiet(j_common_ptr cinfo, int level)
{
    (void)cinfo;
    (void)level;
}

static bool decode_jpeg(struct ctx *c, struct span s, struct asset_image *im, const char *field)
{
    struct jpeg_decompress_struct cinfo;
    struct jpeg_err jerr;
    memset(&cinfo, 0, sizeof(cinfo));
    cinfo.err = jpeg_std_error(&jerr.mgr);
    jerr.mgr.error_exit = jpeg_fail;
    jerr.mgr.emit_message = jpeg_quiet;
    jerr.message[0] = '\0';
    /* volatile: im->rgba is set after setjmp and freed on the longjmp path. */
    uint8_t *volatile rgba = NULL;
    if (setjmp(jerr.jump)) {
        jpeg_destroy_decompress(&cinfo);
        free(rgba);
        im->rgba = NULL;
        return fail(c, 400, field, "bad JPEG: %s", jerr.message);
    }
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, s.data, (unsigned long)s.len);
    jpeg_read_header(&cinfo, TRUE);
    if (cinfo.image_width != im->width || cinfo.image_height != im->height ||
        (cinfo.jpeg_color_space != JCS_GRAYSCALE && cinfo.jpeg_color_space != JCS_YCbCr &&
         cinfo.jpeg_color_space != JCS_RGB)) {
        jpeg_destroy_decompress(&cinfo);
        return fail(c, 400, field, "JPEG size or colour space (CMYK?) not supported");
    }
    cinfo.out_color_space = JCS_EXT_RGBA;
    jpeg_start_decompress(&cinfo);
    rgba = malloc((size_t)im->width * im->height * 4);
    if (!rgba) {
        jpeg_destroy_decompress(&cinfo);
        return fail(c, 500, field, "out of memory");
    }
    while (cinfo.output_scanline < cinfo.output_height) {
        JSAMPROW row = rgba + (size_t)cinfo.output_scanline * im->width * 4;
        jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    im->rgba = rgba;
    return true;
}

static bool build_images(struct ctx *c, struct asset *a)
{
    if (!c->nimages)
        return true;
    if (!(a->images = calloc(c->nimages, sizeof(*a->images))))
        return fail(c, 500, "images", "out of memory");
    for (size_t i = 0; i < c->nimages; i++) {
        struct asset_image *im = &a->images[i];
        char field[64], fallback[32];
        snprintf(field, sizeof(field), "images[%zu]", i);
        snprintf(fallback, sizeof(fallback), "image%zu", i);
        copy_name(im->name, json_array_get(c->imgs, i), fallback);
        image_size(c->images[i], &im->width, &im->height);
        a->image_count = (uint32_t)i + 1;
        bool ok = is_png(c->images[i]) ? decode_png(c, c->images[i], im, field)
                                       : decode_jpeg(c, c->images[i], im, field);
        if (!ok)
            return false;
    }
    return true;
}

/* ---- materials, lights, cameras from the checked JSON ---- */

static bool build_materials(struct ctx *c, struct asset *a)
{
    size_t n = json_array_size(c->materials);
    if (!n)
        return true;
    if (!(a->materials = calloc(n, sizeof(*a->materials))))
        return fail(c, 500, "materials", "out of memory");
    a->material_count = (uint32_t)n;
    static const char *const slots[] = {"baseColorTexture", "metallicRoughnessTexture",
                                        "normalTexture", "occlusionTexture", "emissiveTexture"};
    for (size_t i = 0; i < n; i++) {
        json_t *m = json_array_get(c->materials, i);
        json_t *pbr = json_object_get(m, "pbrMetallicRoughness");
        struct asset_material *am = &a->materials[i];
        char fallback[32];
        snprintf(fallback, sizeof(fallback), "material%zu", i);
        copy_name(am->name, m, fallback);
        double bc[4] = {1, 1, 1, 1}, em[3] = {0, 0, 0};
        char field[64];
        snprintf(field, sizeof(field), "materials[%zu]", i);
        if (!get_floats(c, pbr, "baseColorFactor", field, 4, bc) ||
            !get_floats(c, m, "emissiveFactor", field, 3, em))
            return false;
        double strength = num_or(json_object_get(json_object_get(m, "extensions"),
                                                 "KHR_materials_emissive_strength"),
                                 "emissiveStrength", 1.0);
        for (int k = 0; k < 4; k++)
            am->base_color[k] = (float)bc[k];
        for (int k = 0; k < 3; k++)
            am->emissive[k] = (float)(em[k] * strength);
        am->metallic = (float)num_or(pbr, "metallicFactor", 1.0);
        am->roughness = (float)num_or(pbr, "roughnessFactor", 1.0);
        const char *mode = json_string_value(json_object_get(m, "alphaMode"));
        am->alpha_mode = !mode || !strcmp(mode, "OPAQUE") ? ASSET_ALPHA_OPAQUE
                         : !strcmp(mode, "MASK")          ? ASSET_ALPHA_MASK
                                                          : ASSET_ALPHA_BLEND;
        am->alpha_cutoff = (float)num_or(m, "alphaCutoff", 0.5);
        am->double_sided = json_is_true(json_object_get(m, "doubleSided"));
        if (json_object_get(json_object_get(m, "extensions"), "KHR_materials_unlit"))
            ignore(c, "KHR_materials_unlit (lit as PBR)");
        for (int s = 0; s < ASSET_TEX_SLOTS; s++) {
            struct asset_texture_ref *t = &am->tex[s];
            t->image = -1;
            t->wrap_s = t->wrap_t = 10497;
            t->min_filter = 9987;
            t->mag_filter = 9729;
            t->scale = 1.0f;
            json_t *ti = json_object_get(s < 2 ? pbr : m, slots[s]);
            if (!ti)
                continue;
            json_t *tex = json_array_get(c->textures, (size_t)json_integer_value(json_object_get(ti, "index")));
            json_t *src = json_object_get(tex, "source");
            if (!src)
                continue;
            t->image = (int32_t)json_integer_value(src);
            json_int_t set = json_integer_value(json_object_get(ti, "texCoord"));
            if (set > 1) {
                ignore(c, "texCoord sets above 1 (read as 0)");
                set = 0;
            }
            t->uv_set = (int32_t)set;
            if (s == ASSET_TEX_NORMAL)
                t->scale = (float)num_or(ti, "scale", 1.0);
            else if (s == ASSET_TEX_OCCLUSION)
                t->scale = (float)num_or(ti, "strength", 1.0);
            json_t *smp = json_object_get(tex, "sampler")
                              ? json_array_get(c->samplers, (size_t)json_integer_value(json_object_get(tex, "sampler")))
                              : NULL;
            if (smp) {
                t->wrap_s = (uint32_t)num_or(smp, "wrapS", 10497);
                t->wrap_t = (uint32_t)num_or(smp, "wrapT", 10497);
                t->min_filter = (uint32_t)num_or(smp, "minFilter", 9987);
                t->mag_filter = (uint32_t)num_or(smp, "magFilter", 9729);
            }
        }
    }
    return true;
}

/* Lights and cameras instanced by the scene's nodes, in world space. */
static bool build_lights_cameras(struct ctx *c, struct asset *a, const bool *in_scene)
{
    size_t nn = json_array_size(c->nodes), nl = 0, nc = 0;
    for (size_t i = 0; i < nn; i++) {
        if (!in_scene[i])
            continue;
        json_t *node = json_array_get(c->nodes, i);
        nl += json_object_get(json_object_get(json_object_get(node, "extensions"),
                                              "KHR_lights_punctual"), "light") != NULL;
        nc += json_object_get(node, "camera") != NULL;
    }
    if (nl > c->lim->max_lights)
        return fail(c, 422, "limits.max_lights", "%zu light instances, the limit is %u", nl,
                    c->lim->max_lights);
    if (nc > c->lim->max_cameras)
        return fail(c, 422, "limits.max_cameras", "%zu camera instances, the limit is %u", nc,
                    c->lim->max_cameras);
    if (nl && !(a->lights = calloc(nl, sizeof(*a->lights))))
        return fail(c, 500, "lights", "out of memory");
    if (nc && !(a->cameras = calloc(nc, sizeof(*a->cameras))))
        return fail(c, 500, "cameras", "out of memory");
    for (size_t i = 0; i < nn; i++) {
        if (!in_scene[i])
            continue;
        json_t *node = json_array_get(c->nodes, i);
        json_t *li = json_object_get(json_object_get(json_object_get(node, "extensions"),
                                                     "KHR_lights_punctual"), "light");
        json_t *ci = json_object_get(node, "camera");
        if (!li && !ci)
            continue;
        double m[16];
        node_world(c, (int)i, m);
        const float origin[3] = {0, 0, 0};
        double fwd[3] = {0, 0, -1}, up[3] = {0, 1, 0};
        xform_dir(m, (double[3]){0, 0, -1}, fwd);
        xform_dir(m, (double[3]){0, 1, 0}, up);
        normalize3(fwd);
        normalize3(up);
        char fallback[32];
        if (li) {
            json_t *l = json_array_get(c->lights, (size_t)json_integer_value(li));
            struct asset_light *al = &a->lights[a->light_count++];
            snprintf(fallback, sizeof(fallback), "light%lld", (long long)json_integer_value(li));
            copy_name(al->name, l, fallback);
            const char *type = json_string_value(json_object_get(l, "type"));
            al->type = !strcmp(type, "point") ? ASSET_LIGHT_POINT
                       : !strcmp(type, "spot") ? ASSET_LIGHT_SPOT
                                               : ASSET_LIGHT_DIRECTIONAL;
            double col[3] = {1, 1, 1};
            get_floats(c, l, "color", "light", 3, col);
            for (int k = 0; k < 3; k++) {
                al->color[k] = (float)col[k];
                al->direction[k] = (float)fwd[k];
            }
            al->intensity = (float)num_or(l, "intensity", 1.0);
            al->range = (float)num_or(l, "range", 0.0);
            json_t *spot = json_object_get(l, "spot");
            al->inner_cone = (float)num_or(spot, "innerConeAngle", 0.0);
            al->outer_cone = (float)num_or(spot, "outerConeAngle", 0.7853981633974483);
            xform_point(m, origin, al->position);
        }
        if (ci) {
            json_t *cam = json_array_get(c->cameras, (size_t)json_integer_value(ci));
            struct asset_camera *ac = &a->cameras[a->camera_count++];
            snprintf(fallback, sizeof(fallback), "camera%lld", (long long)json_integer_value(ci));
            copy_name(ac->name, cam, fallback);
            ac->perspective = !strcmp(json_string_value(json_object_get(cam, "type")), "perspective");
            json_t *p = json_object_get(cam, ac->perspective ? "perspective" : "orthographic");
            ac->znear = (float)num_or(p, "znear", 0.1);
            ac->zfar = (float)num_or(p, "zfar", 0.0);
            if (ac->perspective) {
                ac->yfov = (float)num_or(p, "yfov", 0.8);
                ac->aspect = (float)num_or(p, "aspectRatio", 0.0);
            } else { /* asset.h: ymag in yfov, xmag / ymag in aspect */
                double ymag = fabs(num_or(p, "ymag", 1.0)), xmag = fabs(num_or(p, "xmag", 1.0));
                ac->yfov = (float)ymag;
                ac->aspect = ymag > 0 ? (float)(xmag / ymag) : 0.0f;
            }
            xform_point(m, origin, ac->eye);
            for (int k = 0; k < 3; k++) {
                ac->forward[k] = (float)fwd[k];
                ac->up[k] = (float)up[k];
            }
        }
    }
    return true;
}

/* ---- meshes ---- */

static void any_tangent(const float n[3], float t[4])
{
    /* Perpendicular to n, from the axis n is least aligned with. */
    double a[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    double v[3] = {a[0] - d * n[0], a[1] - d * n[1], a[2] - d * n[2]};
    normalize3(v);
    t[0] = (float)v[0];
    t[1] = (float)v[1];
    t[2] = (float)v[2];
    t[3] = 1.0f;
}

static double tri_area2(const float a[2], const float b[2], const float cc[2])
{
    return fabs((double)(b[0] - a[0]) * (cc[1] - a[1]) - (double)(cc[0] - a[0]) * (b[1] - a[1])) / 2;
}

/* Vertex v of assimp's mesh in world space (uv1 from the file, when it has
 * one; the caller sets generated charts). */
static bool fill_vertex(struct ctx *c, const struct aiMesh *am, float *const uvs[2], unsigned v,
                        const double m[16], const double nm[9], double det, struct asset_vertex *vx,
                        const char *field)
{
    const float pos[3] = {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z};
    xform_point(m, pos, vx->pos);
    double n[3] = {0, 1, 0};
    if (am->mNormals) {
        double in[3] = {am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z};
        for (int r = 0; r < 3; r++)
            n[r] = nm[r] * in[0] + nm[3 + r] * in[1] + nm[6 + r] * in[2];
        normalize3(n);
        if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.5))
            n[0] = 0, n[1] = 1, n[2] = 0; /* a degenerate normal: any unit one */
    }
    for (int r = 0; r < 3; r++)
        vx->normal[r] = (float)n[r];
    any_tangent(vx->normal, vx->tangent);
    if (am->mTangents && am->mBitangents && am->mNormals) {
        double tin[3] = {am->mTangents[v].x, am->mTangents[v].y, am->mTangents[v].z};
        double nin[3] = {am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z};
        double bin[3] = {am->mBitangents[v].x, am->mBitangents[v].y, am->mBitangents[v].z};
        /* glTF: bitangent = cross(normal, tangent) * w. assimp computed its
         * bitangent on V-flipped coordinates, which points it the way glTF's
         * does (towards decreasing glTF v, up in the image), so the sign of
         * this dot product is w, for tangents from the file or generated. */
        double cr[3] = {nin[1] * tin[2] - nin[2] * tin[1], nin[2] * tin[0] - nin[0] * tin[2],
                        nin[0] * tin[1] - nin[1] * tin[0]};
        double w = cr[0] * bin[0] + cr[1] * bin[1] + cr[2] * bin[2] < 0 ? -1.0 : 1.0;
        double tw[3];
        xform_dir(m, tin, tw);
        /* Keep it perpendicular to the world normal (a non-uniform scale
         * skews the two apart). */
        double d = tw[0] * n[0] + tw[1] * n[1] + tw[2] * n[2];
        for (int r = 0; r < 3; r++)
            tw[r] -= d * n[r];
        double len2 = tw[0] * tw[0] + tw[1] * tw[1] + tw[2] * tw[2];
        if (isfinite(len2) && len2 > 1e-20) {
            normalize3(tw);
            for (int r = 0; r < 3; r++)
                vx->tangent[r] = (float)tw[r];
            vx->tangent[3] = (float)(det < 0 ? -w : w);
        }
    }
    if (uvs[0]) {
        vx->uv0[0] = uvs[0][2 * v];
        vx->uv0[1] = uvs[0][2 * v + 1];
    }
    if (uvs[1]) {
        float u = uvs[1][2 * v], w = uvs[1][2 * v + 1];
        vx->uv1[0] = u < 0 ? 0 : u > 1 ? 1 : u;
        vx->uv1[1] = w < 0 ? 0 : w > 1 ? 1 : w;
    }
    for (int r = 0; r < 4; r++)
        if (!isfinite(vx->tangent[r]))
            any_tangent(vx->normal, vx->tangent);
    for (int r = 0; r < 3; r++)
        if (!isfinite(vx->pos[r]) || !isfinite(vx->normal[r]))
            return fail(c, 400, field, "a vertex is not finite in world space");
    if (!isfinite(vx->uv0[0]) || !isfinite(vx->uv0[1]))
        return fail(c, 400, field, "TEXCOORD_0 is not finite");
    return true;
}

static bool build_mesh(struct ctx *c, const struct aiMesh *am, const double m[16], json_t *node,
                       size_t node_index, size_t mi, size_t p, const struct prim_info *pi,
                       int material, struct asset_mesh *out)
{
    char field[96];
    snprintf(field, sizeof(field), "meshes[%zu].primitives[%zu]", mi, p);
    double nm[9];
    double det = normal_matrix(m, nm);
    uint32_t ntri = 0;
    for (unsigned f = 0; f < am->mNumFaces; f++)
        ntri += am->mFaces[f].mNumIndices == 3;
    if (!ntri)
        return true; /* points or lines only: already in ignored */
    /* Both uv sets in glTF's convention (origin top left), from assimp or,
     * for quantized accessors, which assimp 5.2 copies as raw bytes into
     * floats, decoded here from the checked accessor. */
    float *uvs[2] = {NULL, NULL};
    uint32_t *corners = NULL;
    float *world = NULL;
    struct uv_charts charts = {0};
    bool ok = false, uv1_file = false;
    for (int set = 0; set < 2; set++) {
        if (pi->uv_accessor[set] < 0)
            continue;
        if (!(uvs[set] = malloc((size_t)am->mNumVertices * 2 * sizeof(float)))) {
            fail(c, 500, field, "out of memory");
            goto done;
        }
        struct accessor acc;
        if (!check_accessor(c, (size_t)pi->uv_accessor[set], &acc))
            goto done;
        if (acc.count != am->mNumVertices) {
            fail(c, 500, field, "assimp made %u vertices of %" PRIu64, am->mNumVertices, acc.count);
            goto done;
        }
        bool normalized = json_is_true(json_object_get(json_array_get(c->accessors,
                                                                      (size_t)pi->uv_accessor[set]),
                                                       "normalized"));
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            if (acc.ctype == 5126) {
                if (!am->mTextureCoords[set]) {
                    fail(c, 500, field, "assimp dropped TEXCOORD_%d", set);
                    goto done;
                }
                uvs[set][2 * v] = am->mTextureCoords[set][v].x;
                uvs[set][2 * v + 1] = 1.0f - am->mTextureCoords[set][v].y; /* assimp flips V */
                continue;
            }
            const uint8_t *e = acc.view.data + acc.offset + acc.stride * v;
            for (int k = 0; k < 2; k++) {
                float x = acc.ctype == 5121 ? e[k] : (float)(e[2 * k] | e[2 * k + 1] << 8);
                uvs[set][2 * v + k] = normalized ? x / (acc.ctype == 5121 ? 255.0f : 65535.0f) : x;
            }
        }
    }
    uv1_file = uvs[1] != NULL;
    for (unsigned v = 0; uv1_file && v < am->mNumVertices; v++) {
        float u = uvs[1][2 * v], w = uvs[1][2 * v + 1];
        if (!(u >= -1e-4f && u <= 1.0001f && w >= -1e-4f && w <= 1.0001f))
            uv1_file = false;
    }
    if (uvs[1] && !uv1_file) {
        ignore(c, "TEXCOORD_1 outside [0, 1] (uv1 generated instead)");
        free(uvs[1]);
        uvs[1] = NULL;
    }
    /* The triangles' corners, mirrored ones swapped so that front faces
     * stay counter-clockwise after a negative-determinant matrix. */
    corners = malloc((size_t)ntri * 3 * sizeof(uint32_t));
    world = uv1_file ? NULL : malloc((size_t)am->mNumVertices * 3 * sizeof(float));
    if (!corners || (!uv1_file && !world)) {
        fail(c, 500, field, "out of memory");
        goto done;
    }
    uint32_t t = 0;
    for (unsigned f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *face = &am->mFaces[f];
        if (face->mNumIndices != 3)
            continue;
        for (int k = 0; k < 3; k++) {
            int kk = det < 0 ? (k == 1 ? 2 : k == 2 ? 1 : 0) : k;
            corners[3 * t + k] = face->mIndices[kk];
            if (face->mIndices[kk] >= am->mNumVertices) {
                fail(c, 500, field, "assimp gave an index out of range");
                goto done;
            }
        }
        t++;
    }
    uint64_t nv = am->mNumVertices;
    if (!uv1_file) {
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            const float p3[3] = {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z};
            xform_point(m, p3, world + 3 * (size_t)v);
        }
        char cerr[128];
        if (!uv_charts_build(world, am->mNumVertices, corners, ntri, c->lim->max_vertices, &charts,
                             cerr, sizeof(cerr))) {
            if (strstr(cerr, "memory"))
                fail(c, 500, field, "%s", cerr);
            else
                fail(c, 422, "limits.max_vertices", "%s: %s", field, cerr);
            goto done;
        }
        nv = charts.vertex_count;
    }
    if (nv > c->lim->max_vertices) {
        fail(c, 422, "limits.max_vertices", "%s has %" PRIu64 " vertices", field, nv);
        goto done;
    }
    out->vertices = calloc((size_t)nv, sizeof(*out->vertices));
    out->indices = malloc((size_t)ntri * 3 * sizeof(uint32_t));
    if (!out->vertices || !out->indices) {
        fail(c, 500, field, "out of memory");
        goto done;
    }
    out->vertex_count = (uint32_t)nv;
    out->index_count = ntri * 3;
    out->material = material;
    out->uv1_from_file = uv1_file;
    out->tangents_from_file = pi->has_tangent && am->mTangents;
    const char *nname = json_string_value(json_object_get(node, "name"));
    if (nname && nname[0]) {
        char head[48]; /* room for "/" and the primitive's number */
        snprintf(head, sizeof(head), "%s", nname);
        utf8_trim(head);
        snprintf(out->name, ASSET_NAME_MAX, "%s/%u", head, (unsigned)p);
    } else {
        snprintf(out->name, ASSET_NAME_MAX, "node%zu/mesh%zu/%zu", node_index, mi, p);
    }
    struct asset_vertex *vs = out->vertices;
    for (uint32_t v = 0; v < out->vertex_count; v++) {
        if (!fill_vertex(c, am, uvs, uv1_file ? v : charts.source[v], m, nm, det, &vs[v], field))
            goto done;
        if (!uv1_file) {
            vs[v].uv1[0] = charts.uv[v][0];
            vs[v].uv1[1] = charts.uv[v][1];
        }
    }
    memcpy(out->indices, uv1_file ? corners : charts.indices, (size_t)ntri * 3 * sizeof(uint32_t));
    double covered = 0;
    for (t = 0; t < ntri; t++) {
        const uint32_t *ix = &out->indices[t * 3];
        covered += tri_area2(vs[ix[0]].uv1, vs[ix[1]].uv1, vs[ix[2]].uv1);
    }
    double waste = 1.0 - covered;
    out->uv1_waste = (float)(waste < 0 ? 0 : waste > 1 ? 1 : waste);
    for (int r = 0; r < 3; r++) {
        out->box_min[r] = INFINITY;
        out->box_max[r] = -INFINITY;
    }
    for (uint32_t v = 0; v < out->vertex_count; v++)
        for (int r = 0; r < 3; r++) {
            out->box_min[r] = fminf(out->box_min[r], vs[v].pos[r]);
            out->box_max[r] = fmaxf(out->box_max[r], vs[v].pos[r]);
        }
    ok = true;
done:
    free(corners);
    free(world);
    free(uvs[0]);
    free(uvs[1]);
    uv_charts_free(&charts);
    return ok;
}

static bool build_meshes(struct ctx *c, const struct aiScene *sc, struct prim_info **infos,
                         const bool *in_scene, struct asset *a)
{
    size_t nm = json_array_size(c->meshes);
    size_t *offset = calloc(nm + 1, sizeof(size_t));
    if (!offset)
        return fail(c, 500, "meshes", "out of memory");
    for (size_t m = 0; m < nm; m++)
        offset[m + 1] = offset[m] + json_array_size(json_object_get(json_array_get(c->meshes, m),
                                                                    "primitives"));
    bool ok = false;
    if (offset[nm] != sc->mNumMeshes) {
        fail(c, 500, "meshes", "assimp made %u meshes of %zu primitives", sc->mNumMeshes, offset[nm]);
        goto done;
    }
    size_t count = 0;
    for (size_t i = 0; i < json_array_size(c->nodes); i++) {
        json_t *mi = json_object_get(json_array_get(c->nodes, i), "mesh");
        if (in_scene[i] && mi)
            count += offset[json_integer_value(mi) + 1] - offset[json_integer_value(mi)];
    }
    if (count && !(a->meshes = calloc(count, sizeof(*a->meshes)))) {
        fail(c, 500, "meshes", "out of memory");
        goto done;
    }
    uint64_t total_v = 0, total_i = 0;
    for (size_t i = 0; i < json_array_size(c->nodes); i++) {
        json_t *node = json_array_get(c->nodes, i);
        json_t *mi = json_object_get(node, "mesh");
        if (!in_scene[i] || !mi)
            continue;
        size_t m = (size_t)json_integer_value(mi);
        double w[16];
        node_world(c, (int)i, w);
        json_t *prims = json_object_get(json_array_get(c->meshes, m), "primitives");
        for (size_t p = 0; p < json_array_size(prims); p++) {
            const struct aiMesh *am = sc->mMeshes[offset[m] + p];
            json_t *mat = json_object_get(json_array_get(prims, p), "material");
            struct asset_mesh *out = &a->meshes[a->mesh_count];
            if (!build_mesh(c, am, w, node, i, m, p, &infos[m][p], mat ? (int)json_integer_value(mat) : -1,
                            out)) {
                a->mesh_count++; /* so that asset_finish frees what it holds */
                goto done;
            }
            if (!out->index_count)
                continue;
            total_v += out->vertex_count;
            total_i += out->index_count;
            a->mesh_count++;
        }
    }
    if (total_v > c->lim->max_vertices || total_i > c->lim->max_indices) {
        fail(c, 422, total_v > c->lim->max_vertices ? "limits.max_vertices" : "limits.max_indices",
             "%" PRIu64 " vertices and %" PRIu64 " indices after import", total_v, total_i);
        goto done;
    }
    if (!a->mesh_count) {
        fail(c, 422, "meshes", "the scene has no triangles");
        goto done;
    }
    for (int r = 0; r < 3; r++) {
        a->box_min[r] = INFINITY;
        a->box_max[r] = -INFINITY;
    }
    for (uint32_t k = 0; k < a->mesh_count; k++)
        for (int r = 0; r < 3; r++) {
            a->box_min[r] = fminf(a->box_min[r], a->meshes[k].box_min[r]);
            a->box_max[r] = fmaxf(a->box_max[r], a->meshes[k].box_max[r]);
        }
    ok = true;
done:
    free(offset);
    return ok;
}

static bool convert(const uint8_t *data, size_t len, const struct asset_limits *lim,
                    struct asset *out, struct asset_convert_error *err, bool import)
{
    memset(out, 0, sizeof(*out));
    memset(err, 0, sizeof(*err));
    struct ctx c = {.lim = lim, .err = err};
    struct prim_info **infos = NULL;
    bool *in_scene = NULL;
    const struct aiScene *sc = NULL;
    bool ok = false;
    if ((uint64_t)len > lim->max_file_bytes || len > UINT32_MAX /* assimp takes an unsigned size */) {
        fail(&c, 422, "limits.max_file_bytes", "%zu bytes, the limit is %" PRIu64, len,
             lim->max_file_bytes);
        goto done;
    }
    json_t *ext;
    int64_t scene_index = 0;
    if (!check_container(&c, data, len) || !check_asset_and_extensions(&c) || !check_buffers(&c) ||
        !check_accessors(&c) ||
        !opt_array(&c, c.root, "meshes", "meshes", &c.meshes) ||
        !opt_array(&c, c.root, "materials", "materials", &c.materials) ||
        !opt_array(&c, c.root, "textures", "textures", &c.textures) ||
        !opt_array(&c, c.root, "samplers", "samplers", &c.samplers) ||
        !opt_array(&c, c.root, "images", "images", &c.imgs) ||
        !opt_array(&c, c.root, "cameras", "cameras", &c.cameras))
        goto done;
    ext = json_object_get(json_object_get(c.root, "extensions"), "KHR_lights_punctual");
    if (ext && !opt_array(&c, ext, "lights", "extensions.KHR_lights_punctual.lights", &c.lights))
        goto done;
    if (!check_graph(&c, &scene_index) || !check_images(&c) || !check_textures_materials(&c) ||
        !check_lights_cameras(&c) || !check_meshes(&c, scene_index, &infos))
        goto done;

    size_t nn = json_array_size(c.nodes);
    in_scene = calloc(nn + 1, sizeof(bool));
    if (!in_scene) {
        fail(&c, 500, "nodes", "out of memory");
        goto done;
    }
    json_t *roots = json_object_get(json_array_get(json_object_get(c.root, "scenes"),
                                                   (size_t)scene_index), "nodes");
    for (size_t i = 0; i < nn; i++) {
        int top = (int)i;
        while (c.parent[top] != -1)
            top = c.parent[top];
        for (size_t k = 0; k < json_array_size(roots); k++)
            in_scene[i] |= json_integer_value(json_array_get(roots, k)) == top;
    }

    /* Stage 2: the geometry. No JoinIdenticalVertices: it would weld
     * vertices that differ only in uv1 across a chart seam; no
     * PreTransformVertices: the world matrices are applied here, per node.
     * Without import (the fuzz target), the rest of what the checked JSON
     * gives. */
    if (!import) {
        ok = build_materials(&c, out) && build_images(&c, out) &&
             build_lights_cameras(&c, out, in_scene);
        goto done;
    }
    sc = aiImportFileFromMemory((const char *)data, (unsigned)len,
                                aiProcess_Triangulate | aiProcess_GenNormals |
                                    aiProcess_CalcTangentSpace,
                                c.glb ? "glb" : "gltf");
    if (!sc) {
        /* The checks passed, so this is the importer's own failure (out of
         * memory under the limits, or a rule of assimp's the checks do not
         * know): the loader failed, not a verdict on the file. */
        fail(&c, 500, "file", "assimp could not import it: %s", aiGetErrorString());
        goto done;
    }
    if (!build_meshes(&c, sc, infos, in_scene, out) || !build_materials(&c, out) ||
        !build_images(&c, out) || !build_lights_cameras(&c, out, in_scene))
        goto done;
    if (c.nignored) {
        out->ignored = calloc(c.nignored, sizeof(char *));
        if (!out->ignored) {
            fail(&c, 500, "ignored", "out of memory");
            goto done;
        }
        memcpy(out->ignored, c.ignored, c.nignored * sizeof(char *));
        out->ignored_count = c.nignored;
        c.nignored = 0;
    }
    ok = true;
done:
    if (sc)
        aiReleaseImport(sc);
    if (infos)
        for (size_t m = 0; m < json_array_size(c.meshes); m++)
            free(infos[m]);
    free(infos);
    free(in_scene);
    for (uint32_t i = 0; i < c.nignored; i++)
        free(c.ignored[i]);
    for (size_t i = 0; i < c.nowned; i++)
        free(c.owned[i]);
    free(c.owned);
    free(c.buffers);
    free(c.images);
    free(c.parent);
    json_decref(c.root);
    if (!ok) {
        if (!err->status)
            fail(&c, 500, "file", "conversion failed");
        asset_finish(out);
    }
    return ok;
}

bool asset_convert_buffer(const uint8_t *data, size_t len, const struct asset_limits *lim,
                          struct asset *out, struct asset_convert_error *err)
{
    return convert(data, len, lim, out, err, true);
}

bool asset_convert_checks(const uint8_t *data, size_t len, const struct asset_limits *lim,
                          struct asset *out, struct asset_convert_error *err)
{
    return convert(data, len, lim, out, err, false);
}
