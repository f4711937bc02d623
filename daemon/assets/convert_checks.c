#define _POSIX_C_SOURCE 200809L
/* Stage 1, the checks (convert_internal.h), with jansson, before anything
 * else reads the file: the GLB container, the JSON, every buffer,
 * bufferView and accessor range, the index values, the node graph (a
 * forest, bounded depth), the images' signatures and sizes, the URIs
 * (data: only), and the declared counts against the limits. assimp trusts
 * what it reads; these checks are what keeps malformed input away from it,
 * and they allocate nothing in proportion to a declared count. */
#include "daemon/assets/convert_internal.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- data URIs ---- */

/* The standard alphabet only (RFC 2045, as RFC 2397 asks): assimp decodes
 * the URI again with its own table, which has no URL-safe letters, so a
 * letter it reads otherwise would give it other bytes than the ones
 * checked here. */
static int b64_value(uint8_t ch)
{
    if (ch >= 'A' && ch <= 'Z')
        return ch - 'A';
    if (ch >= 'a' && ch <= 'z')
        return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9')
        return ch - '0' + 52;
    if (ch == '+')
        return 62;
    if (ch == '/')
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
    /* Whole groups of four, '=' only as the last one or two (assimp refuses
     * any other length, and reads an '=' inside as a letter). */
    size_t pad = n >= 1 && p[n - 1] == '=' ? (n >= 2 && p[n - 2] == '=' ? 2 : 1) : 0;
    if (n % 4)
        return fail(c, 400, field, "data: URI's base64 text is %zu characters, not a multiple of 4",
                    n);
    uint8_t *buf = malloc(n / 4 * 3 + 3);
    if (!buf)
        return fail(c, 500, field, "out of memory");
    size_t o = 0;
    uint32_t acc = 0;
    int bits = 0;
    for (size_t i = 0; i < n - pad; i++) {
        int v = b64_value(p[i]);
        if (v < 0) {
            free(buf);
            return fail(c, 400, field, "data: URI has a byte that is not base64 (standard "
                        "alphabet, '=' only at the end) at %zu", i);
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

/* ---- stage 1: the checks ---- */

bool check_container(struct ctx *c, const uint8_t *data, size_t len)
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

bool check_asset_and_extensions(struct ctx *c)
{
    json_t *asset = json_object_get(c->root, "asset");
    const char *version = json_string_value(json_object_get(asset, "version"));
    if (!version)
        return fail(c, 400, "asset.version", "missing");
    if (version[0] != '2')
        return fail(c, 422, "asset.version", "glTF %s, only 2.x is supported", version);
    static const char *const handled[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                          "KHR_texture_transform"};
    json_t *req = json_object_get(c->root, "extensionsRequired");
    size_t i;
    json_t *v;
    json_array_foreach(req, i, v) {
        const char *name = json_string_value(v);
        bool ok = name && (strcmp(name, handled[0]) == 0 || strcmp(name, handled[1]) == 0 ||
                           strcmp(name, handled[2]) == 0 ||
                           strcmp(name, "KHR_materials_unlit") == 0);
        if (!ok) {
            char field[64];
            snprintf(field, sizeof(field), "extensionsRequired[%zu]", i);
            return fail(c, 422, field, "required extension %s is not supported", name ? name : "?");
        }
    }
    json_array_foreach(json_object_get(c->root, "extensionsUsed"), i, v) {
        const char *name = json_string_value(v);
        if (name && strcmp(name, handled[0]) != 0 && strcmp(name, handled[1]) != 0 &&
            strcmp(name, handled[2]) != 0)
            ignore(c, "extension %s", name);
    }
    if (json_array_size(json_object_get(c->root, "animations")))
        ignore(c, "animations");
    if (json_array_size(json_object_get(c->root, "skins")))
        ignore(c, "skins");
    return true;
}

bool check_buffers(struct ctx *c)
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
        /* A data URI holds the buffer exactly (the glTF validator's
         * BUFFER_EMBEDDED_BYTELENGTH_MISMATCH; assimp refuses it too); the
         * GLB chunk may carry up to 3 bytes of padding. */
        if (uri && (uint64_t)blen != s.len) {
            snprintf(field, sizeof(field), "buffers[%zu].byteLength", i);
            return fail(c, 400, field, "byteLength %" PRId64 " but the data URI holds %" PRIu64
                        " bytes", blen, s.len);
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

bool check_accessor(struct ctx *c, size_t i, struct accessor *a)
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

bool check_accessors(struct ctx *c)
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


/* Attribute name's accessor: one of ctypes, ncomp or ncomp_or components
 * (ncomp_or 0: ncomp only), vcount elements. */
static bool check_attribute(struct ctx *c, json_t *attrs, const char *name, const char *field,
                            uint64_t vcount, const int64_t *ctypes, int ncomp, int ncomp_or,
                            bool *present)
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
    if (!ok || (a.ncomp != ncomp && a.ncomp != ncomp_or))
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
    if (!check_attribute(c, attrs, "NORMAL", f, pa.count, FLOAT, 3, 0, &pi->has_normal) ||
        !check_attribute(c, attrs, "TANGENT", f, pa.count, FLOAT, 4, 0, &pi->has_tangent) ||
        !check_attribute(c, attrs, "TEXCOORD_0", f, pa.count, UV, 2, 0, &present) ||
        !check_attribute(c, attrs, "TEXCOORD_1", f, pa.count, UV, 2, 0, &pi->has_uv1))
        return false;
    for (int set = 0; set < 2; set++) {
        json_t *uv = json_object_get(attrs, set ? "TEXCOORD_1" : "TEXCOORD_0");
        pi->uv_accessor[set] = uv ? json_integer_value(uv) : -1;
    }
    /* COLOR_0: float, or unsigned byte or short (normalized), VEC3 or VEC4. */
    pi->color_accessor = -1;
    if (!check_attribute(c, attrs, "COLOR_0", f, pa.count, UV, 3, 4, &present))
        return false;
    if (present)
        pi->color_accessor = json_integer_value(json_object_get(attrs, "COLOR_0"));
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
        /* An accessor's largest index is read once, however many
         * primitives share it. */
        if (c->index_max[idx] < 0) {
            uint32_t most = 0;
            for (uint64_t k = 0; k < ia.count; k++) {
                uint32_t x = read_index(&ia, k);
                most = x > most ? x : most;
            }
            c->index_max[idx] = most;
        }
        if ((uint64_t)c->index_max[idx] >= pa.count) {
            uint64_t k = 0;
            while (read_index(&ia, k) < pa.count)
                k++;
            return fail(c, 400, f, "index %" PRIu64 " is %u, POSITION has %" PRIu64 " vertices",
                        k, read_index(&ia, k), pa.count);
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

bool check_graph(struct ctx *c, int64_t *scene_index)
{
    json_t *scenes;
    if (!opt_array(c, c->root, "nodes", "nodes", &c->nodes) ||
        !opt_array(c, c->root, "scenes", "scenes", &scenes))
        return false;
    size_t n = json_array_size(c->nodes);
    if (n > c->lim->max_nodes)
        return fail(c, 422, "limits.max_nodes", "%zu nodes, the limit is %u", n,
                    c->lim->max_nodes);
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
    /* Depth bounded and no cycle, in one pass: each node's level (1 for a
     * root) from its nearest ancestor whose level is known, so that every
     * node is climbed through once whatever the shape (a million roots, or
     * a deep chain); a cycle has no root, so its climb runs past
     * MAX_NODE_DEPTH. top[] is each node's root. */
    if (n && (!(c->level = calloc(n, sizeof(int))) || !(c->top = malloc(n * sizeof(int)))))
        return fail(c, 500, "nodes", "out of memory");
    for (size_t i = 0; i < n; i++) {
        int chain[MAX_NODE_DEPTH + 1];
        int len = 0, p = (int)i;
        while (p != -1 && !c->level[p]) {
            if (len == MAX_NODE_DEPTH + 1)
                break;
            chain[len++] = p;
            p = c->parent[p];
        }
        if (!len)
            continue;
        int above = p == -1 ? 0 : c->level[p];
        if (len == MAX_NODE_DEPTH + 1 || above + len > MAX_NODE_DEPTH) {
            char field[64];
            snprintf(field, sizeof(field), "nodes[%zu]", i);
            return fail(c, 422, field, "the node hierarchy is deeper than %d levels (or a cycle)",
                        MAX_NODE_DEPTH);
        }
        int top = p == -1 ? chain[len - 1] : c->top[p];
        for (int k = len - 1; k >= 0; k--) {
            c->level[chain[k]] = above + (len - k);
            c->top[chain[k]] = top;
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
    /* The nodes the scene draws: those whose root it lists. */
    bool *listed = calloc(n + 1, sizeof(bool));
    if (!listed || !(c->in_scene = calloc(n + 1, sizeof(bool)))) {
        free(listed);
        return fail(c, 500, "nodes", "out of memory");
    }
    json_array_foreach(roots, k, r)
        listed[json_integer_value(r)] = true;
    for (size_t i = 0; i < n; i++)
        c->in_scene[i] = listed[c->top[i]];
    free(listed);
    return true;
}

/* Counts what the scene instances against the limits, before any import:
 * each mesh's primitives summed once, then each node adds its mesh's sums
 * (linear in primitives plus nodes, however many nodes share a mesh). */
bool check_meshes(struct ctx *c, struct prim_info ***infos)
{
    size_t nm = json_array_size(c->meshes), na = json_array_size(c->accessors);
    *infos = nm ? calloc(nm, sizeof(**infos)) : NULL;
    struct mesh_sums {
        uint64_t meshes, triangles, vertices, indices;
    } *sums = calloc(nm + 1, sizeof(*sums));
    bool ok = false;
    if ((nm && !*infos) || !sums || !(c->index_max = malloc((na + 1) * sizeof(int64_t)))) {
        fail(c, 500, "meshes", "out of memory");
        goto out;
    }
    for (size_t k = 0; k < na; k++)
        c->index_max[k] = -1;
    for (size_t m = 0; m < nm; m++) {
        json_t *mesh = json_array_get(c->meshes, m);
        char field[64];
        snprintf(field, sizeof(field), "meshes[%zu]", m);
        json_t *prims;
        if (!json_is_object(mesh) || !opt_array(c, mesh, "primitives", field, &prims) ||
            !json_array_size(prims)) {
            fail(c, 400, field, "must be an object with primitives");
            goto out;
        }
        (*infos)[m] = calloc(json_array_size(prims), sizeof(struct prim_info));
        if (!(*infos)[m]) {
            fail(c, 500, field, "out of memory");
            goto out;
        }
        for (size_t p = 0; p < json_array_size(prims); p++) {
            struct prim_info *pi = &(*infos)[m][p];
            if (!check_primitive(c, m, p, json_array_get(prims, p), pi))
                goto out;
            if (!pi->triangles)
                continue;
            sums[m].meshes++;
            sums[m].triangles += pi->triangles;
            /* Generated uv1 gives each triangle its own three vertices, and
             * so do flat normals where the file has none. */
            sums[m].vertices += pi->has_uv1 && pi->has_normal ? pi->vertices : 3 * pi->triangles;
            sums[m].indices += 3 * pi->triangles;
        }
    }
    /* Every node of the scene: instances of each mesh. */
    struct mesh_sums all = {0};
    for (size_t i = 0; i < json_array_size(c->nodes); i++) {
        json_t *mi = json_object_get(json_array_get(c->nodes, i), "mesh");
        if (!c->in_scene[i] || !mi)
            continue;
        const struct mesh_sums *s = &sums[json_integer_value(mi)];
        all.meshes += s->meshes;
        all.triangles += s->triangles;
        all.vertices += s->vertices;
        all.indices += s->indices;
    }
    if (all.meshes > c->lim->max_meshes)
        fail(c, 422, "limits.max_meshes", "%" PRIu64 " mesh instances, the limit is %u",
             all.meshes, c->lim->max_meshes);
    else if (all.vertices > c->lim->max_vertices)
        fail(c, 422, "limits.max_vertices", "%" PRIu64 " vertices, the limit is %" PRIu64,
             all.vertices, c->lim->max_vertices);
    else if (all.indices > c->lim->max_indices)
        fail(c, 422, "limits.max_indices", "%" PRIu64 " indices, the limit is %" PRIu64,
             all.indices, c->lim->max_indices);
    else if (!all.triangles)
        fail(c, 422, "meshes", "the scene has no triangles");
    else
        ok = true;
out:
    free(sums);
    return ok;
}

bool check_images(struct ctx *c)
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
        /* What the header claims, against what the bytes can hold: a
         * 16x16 JPEG that declares 8192x8192 is refused here, before a
         * decoder pads it out to 256 MiB. */
        char why[320];
        if (!image_size_honest(c->images[i], w, h, why, sizeof(why)))
            return fail(c, 400, field, "%s", why);
        pixels += (uint64_t)w * h;
        if (pixels > c->lim->max_texture_pixels)
            return fail(c, 422, "limits.max_texture_pixels",
                        "%" PRIu64 " texture pixels up to images[%zu], the limit is %" PRIu64,
                        pixels, i, c->lim->max_texture_pixels);
    }
    return true;
}

bool check_textures_materials(struct ctx *c)
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
            json_t *tt = json_object_get(json_object_get(ti, "extensions"), "KHR_texture_transform");
            if (tt) {
                char f[160];
                snprintf(f, sizeof(f), "%s.extensions.KHR_texture_transform", field);
                double v2[2];
                json_t *rot = json_object_get(tt, "rotation");
                if (!json_is_object(tt) || !get_floats(c, tt, "offset", f, 2, v2) ||
                    !get_floats(c, tt, "scale", f, 2, v2) ||
                    !get_int(c, tt, "texCoord", f, false, 0, 1 << 20, 0, &set))
                    return fail(c, 400, f, "must be an object with offset and scale arrays of 2 "
                                "numbers, a rotation number and a texCoord index");
                if (rot && (!json_is_number(rot) || !(fabs(json_number_value(rot)) <= 1e30)))
                    return fail(c, 400, f, "rotation must be a finite number");
            }
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

bool check_lights_cameras(struct ctx *c)
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
