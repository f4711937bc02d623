#define _POSIX_C_SOURCE 200809L
/* Building the asset (convert_internal.h) from assimp's meshes and the
 * checked JSON, where assimp loses what the file says: materials with each
 * slot's TEXCOORD set and sampler filters, KHR_lights_punctual's intensity
 * and range, the cameras' yfov, and the meshes in world space with their
 * uv1 charts, from the file or generated. */
#include "daemon/assets/convert_internal.h"
#include "daemon/assets/uv_charts.h"
#include "daemon/assets/uv_overlap.h"

#include <assimp/mesh.h>
#include <assimp/scene.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- materials, lights, cameras from the checked JSON ---- */

bool build_materials(struct ctx *c, struct asset *a)
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
            t->transform = (struct asset_uv_transform)ASSET_UV_IDENTITY;
            json_t *ti = json_object_get(s < 2 ? pbr : m, slots[s]);
            if (!ti)
                continue;
            json_t *tex = json_array_get(c->textures, (size_t)json_integer_value(json_object_get(ti, "index")));
            json_t *src = json_object_get(tex, "source");
            if (!src)
                continue;
            t->image = (int32_t)json_integer_value(src);
            json_int_t set = json_integer_value(json_object_get(ti, "texCoord"));
            /* KHR_texture_transform (checked): offset, rotation, scale, and
             * a texCoord that overrides the textureInfo's. */
            json_t *tt = json_object_get(json_object_get(ti, "extensions"), "KHR_texture_transform");
            if (tt) {
                double off[2] = {0, 0}, scl[2] = {1, 1};
                get_floats(c, tt, "offset", field, 2, off);
                get_floats(c, tt, "scale", field, 2, scl);
                for (int k = 0; k < 2; k++) {
                    t->transform.offset[k] = (float)off[k];
                    t->transform.scale[k] = (float)scl[k];
                }
                t->transform.rotation = (float)num_or(tt, "rotation", 0.0);
                if (json_object_get(tt, "texCoord"))
                    set = json_integer_value(json_object_get(tt, "texCoord"));
            }
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
bool build_lights_cameras(struct ctx *c, struct asset *a, const bool *in_scene)
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

/* Component k of element v of a checked accessor as a float: floats as
 * they are, unsigned bytes and shorts divided by 255 and 65535 where
 * normalized (glTF's texture coordinates and colours of those types must
 * be). */
static float accessor_float(const struct accessor *a, uint64_t v, int k, bool normalized)
{
    const uint8_t *e = a->view.data + a->offset + a->stride * v;
    switch (a->ctype) {
    case 5126: {
        float f;
        memcpy(&f, e + 4 * k, 4);
        return f;
    }
    case 5121:
        return normalized ? e[k] / 255.0f : (float)e[k];
    default: {
        float x = (float)(e[2 * k] | e[2 * k + 1] << 8);
        return normalized ? x / 65535.0f : x;
    }
    }
}

/* ncomp floats per vertex from accessor index (vertex order as assimp's:
 * its glTF importer keeps the accessor's, checked by the count). */
static bool decode_attribute(struct ctx *c, int64_t index, const struct aiMesh *am, int ncomp,
                             const char *what, const char *field, float **out)
{
    struct accessor acc;
    if (!check_accessor(c, (size_t)index, &acc))
        return false;
    if (acc.count != am->mNumVertices)
        return fail(c, 500, field, "assimp made %u vertices of %" PRIu64 " (%s)", am->mNumVertices,
                    acc.count, what);
    if (!(*out = malloc((size_t)am->mNumVertices * (size_t)ncomp * sizeof(float))))
        return fail(c, 500, field, "out of memory");
    bool normalized = acc.ctype != 5126;
    for (unsigned v = 0; v < am->mNumVertices; v++)
        for (int k = 0; k < ncomp; k++)
            (*out)[(size_t)v * (size_t)ncomp + (size_t)k] =
                k < acc.ncomp ? accessor_float(&acc, v, k, normalized) : 1.0f;
    return true;
}

/* The uv set the material's normal texture reads (0 without one), as
 * build_materials resolves it. */
static int normal_uv_set(struct ctx *c, int material)
{
    json_t *ti = material >= 0 ? json_object_get(json_array_get(c->materials, (size_t)material),
                                                 "normalTexture")
                               : NULL;
    if (!ti)
        return 0;
    json_t *tt = json_object_get(json_object_get(ti, "extensions"), "KHR_texture_transform");
    json_t *set = tt && json_object_get(tt, "texCoord") ? json_object_get(tt, "texCoord")
                                                        : json_object_get(ti, "texCoord");
    return json_integer_value(set) == 1 ? 1 : 0;
}

/* A primitive's vertices in object space, as the converter builds the
 * asset's from them: assimp's mesh and the checked accessors, one entry per
 * vertex of the file or, where the file has no normals, per triangle
 * corner (unweld). */
struct vertex_sources {
    uint32_t count;
    float *pos;          /* 3 per vertex */
    float *normals;      /* 3 per vertex (any unit normal where NULL) */
    float *tangents;     /* 4 per vertex: direction and handedness w (w 0: none) */
    float *uvs[2];       /* TEXCOORD_0 and _1, 2 per vertex, or NULL */
    float *colors;       /* COLOR_0, 4 per vertex (alpha 1 for VEC3), or NULL */
    bool uv1_file;       /* uv1 is the file's TEXCOORD_1 */
};

static void sources_free(struct vertex_sources *s)
{
    free(s->pos);
    free(s->normals);
    free(s->tangents);
    free(s->uvs[0]);
    free(s->uvs[1]);
    free(s->colors);
    memset(s, 0, sizeof(*s));
}

/* Positions, normals and tangents from assimp's mesh. assimp's tangents
 * come with its bitangents, computed on V-flipped coordinates, which point
 * the way glTF's bitangent does (towards decreasing glTF v, up in the
 * image); glTF's is cross(normal, tangent) * w, so the sign of that dot
 * product is w, for tangents from the file or generated. */
static bool sources_from_assimp(const struct aiMesh *am, bool file_normals, struct vertex_sources *s)
{
    size_t n = am->mNumVertices;
    s->count = am->mNumVertices;
    s->pos = malloc(n * 3 * sizeof(float));
    s->tangents = calloc(n * 4, sizeof(float));
    s->normals = file_normals && am->mNormals ? malloc(n * 3 * sizeof(float)) : NULL;
    if (!s->pos || !s->tangents || (file_normals && am->mNormals && !s->normals))
        return false;
    for (size_t v = 0; v < n; v++) {
        s->pos[3 * v] = am->mVertices[v].x;
        s->pos[3 * v + 1] = am->mVertices[v].y;
        s->pos[3 * v + 2] = am->mVertices[v].z;
        if (s->normals) {
            s->normals[3 * v] = am->mNormals[v].x;
            s->normals[3 * v + 1] = am->mNormals[v].y;
            s->normals[3 * v + 2] = am->mNormals[v].z;
        }
        if (!am->mTangents || !am->mBitangents || !am->mNormals)
            continue;
        double t[3] = {am->mTangents[v].x, am->mTangents[v].y, am->mTangents[v].z};
        double nn[3] = {am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z};
        double b[3] = {am->mBitangents[v].x, am->mBitangents[v].y, am->mBitangents[v].z};
        double cr[3] = {nn[1] * t[2] - nn[2] * t[1], nn[2] * t[0] - nn[0] * t[2],
                        nn[0] * t[1] - nn[1] * t[0]};
        for (int k = 0; k < 3; k++)
            s->tangents[4 * v + (size_t)k] = (float)t[k];
        s->tangents[4 * v + 3] = cr[0] * b[0] + cr[1] * b[1] + cr[2] * b[2] < 0 ? -1.0f : 1.0f;
    }
    return true;
}

/* Tangents in object space from uv (2 floats per vertex) for a normal
 * texture that reads a set assimp does not derive them from (it uses
 * TEXCOORD_0): each triangle's dP/du and dP/dv, summed at its corners, dP/du
 * made perpendicular to the normal; w makes cross(normal, tangent) * w point
 * along -dP/dv, up the image as glTF's bitangent does. Written over
 * s->tangents; a vertex no triangle gives a direction keeps w = 0 (any
 * tangent). corners: the file's winding. */
static bool uv_tangents(struct vertex_sources *s, const float *uv, const uint32_t *corners,
                        uint32_t ntri)
{
    size_t nv = s->count;
    double *acc = calloc(nv * 6, sizeof(double));
    if (!acc)
        return false;
    for (uint32_t t = 0; t < ntri; t++) {
        const uint32_t *ix = &corners[3 * t];
        const float *p0 = &s->pos[3 * ix[0]], *p1 = &s->pos[3 * ix[1]], *p2 = &s->pos[3 * ix[2]];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double du1 = uv[2 * ix[1]] - uv[2 * ix[0]], dv1 = uv[2 * ix[1] + 1] - uv[2 * ix[0] + 1];
        double du2 = uv[2 * ix[2]] - uv[2 * ix[0]], dv2 = uv[2 * ix[2] + 1] - uv[2 * ix[0] + 1];
        double r = du1 * dv2 - du2 * dv1;
        if (!(fabs(r) > 1e-20) || !isfinite(r))
            continue;
        double sdir[3], tdir[3];
        for (int k = 0; k < 3; k++) {
            sdir[k] = (e1[k] * dv2 - e2[k] * dv1) / r;
            tdir[k] = (e2[k] * du1 - e1[k] * du2) / r;
        }
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 3; q++) {
                acc[6 * ix[k] + (uint32_t)q] += sdir[q];
                acc[6 * ix[k] + 3 + (uint32_t)q] += tdir[q];
            }
    }
    for (size_t v = 0; v < nv; v++) {
        s->tangents[4 * v + 3] = 0.0f;
        if (!s->normals)
            continue;
        const float *nf = &s->normals[3 * v];
        double n[3] = {nf[0], nf[1], nf[2]};
        double *sd = &acc[6 * v], *td = &acc[6 * v + 3];
        double d = n[0] * sd[0] + n[1] * sd[1] + n[2] * sd[2];
        double t[3] = {sd[0] - d * n[0], sd[1] - d * n[1], sd[2] - d * n[2]};
        double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        if (!(len > 1e-20) || !isfinite(len))
            continue;
        double cr[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2],
                        n[0] * t[1] - n[1] * t[0]};
        for (int k = 0; k < 3; k++)
            s->tangents[4 * v + (size_t)k] = (float)(t[k] / len);
        s->tangents[4 * v + 3] = cr[0] * td[0] + cr[1] * td[1] + cr[2] * td[2] > 0 ? -1.0f : 1.0f;
    }
    free(acc);
    return true;
}

/* Where the file gives no normals, glTF asks for flat ones: every triangle
 * corner its own vertex, with the triangle's normal (from the file's
 * winding: mirrored, swapped is 0, 2, 1). corners become 0, 1, 2, ... */
static bool unweld(struct vertex_sources *s, uint32_t *corners, uint32_t ntri, bool swapped)
{
    size_t n = (size_t)ntri * 3;
    struct vertex_sources f = {(uint32_t)n, NULL, NULL, NULL, {NULL, NULL}, NULL, false};
    f.pos = malloc(n * 3 * sizeof(float));
    f.normals = malloc(n * 3 * sizeof(float));
    f.tangents = malloc(n * 4 * sizeof(float));
    for (int set = 0; set < 2; set++)
        f.uvs[set] = s->uvs[set] ? malloc(n * 2 * sizeof(float)) : NULL;
    f.colors = s->colors ? malloc(n * 4 * sizeof(float)) : NULL;
    if (!f.pos || !f.normals || !f.tangents || (s->uvs[0] && !f.uvs[0]) ||
        (s->uvs[1] && !f.uvs[1]) || (s->colors && !f.colors)) {
        sources_free(&f);
        return false;
    }
    for (uint32_t t = 0; t < ntri; t++) {
        uint32_t *ix = &corners[3 * t];
        const float *p0 = &s->pos[3 * ix[0]], *p1 = &s->pos[3 * ix[swapped ? 2 : 1]],
                    *p2 = &s->pos[3 * ix[swapped ? 1 : 2]];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double fn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        normalize3(fn);
        for (int k = 0; k < 3; k++) {
            size_t o = 3 * (size_t)t + (size_t)k, v = ix[k];
            memcpy(&f.pos[3 * o], &s->pos[3 * v], 3 * sizeof(float));
            for (int q = 0; q < 3; q++)
                f.normals[3 * o + (size_t)q] = (float)fn[q];
            memcpy(&f.tangents[4 * o], &s->tangents[4 * v], 4 * sizeof(float));
            for (int set = 0; set < 2; set++)
                if (f.uvs[set])
                    memcpy(&f.uvs[set][2 * o], &s->uvs[set][2 * v], 2 * sizeof(float));
            if (f.colors)
                memcpy(&f.colors[4 * o], &s->colors[4 * v], 4 * sizeof(float));
            ix[k] = (uint32_t)o;
        }
    }
    sources_free(s);
    *s = f;
    return true;
}

/* Vertex v of the sources in world space (uv1 from the file where it is
 * used; the caller sets generated charts). */
static bool fill_vertex(struct ctx *c, const struct vertex_sources *src, uint32_t v,
                        const double m[16], const double nm[9], double det,
                        struct asset_vertex *vx, const char *field)
{
    xform_point(m, &src->pos[3 * (size_t)v], vx->pos);
    double n[3] = {0, 1, 0};
    if (src->normals) {
        const float *nf = &src->normals[3 * (size_t)v];
        double in[3] = {nf[0], nf[1], nf[2]};
        xform_normal(nm, in, n);
        normalize3(n);
        if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.5))
            n[0] = 0, n[1] = 1, n[2] = 0; /* a degenerate normal: any unit one */
    }
    for (int r = 0; r < 3; r++)
        vx->normal[r] = (float)n[r];
    any_tangent(vx->normal, vx->tangent);
    const float *tf = &src->tangents[4 * (size_t)v];
    if (tf[3] != 0.0f) {
        double tin[3] = {tf[0], tf[1], tf[2]}, tw[3];
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
            /* A mirroring matrix turns the frame's handedness. */
            vx->tangent[3] = det < 0 ? -tf[3] : tf[3];
        }
    }
    if (src->uvs[0]) {
        vx->uv0[0] = src->uvs[0][2 * (size_t)v];
        vx->uv0[1] = src->uvs[0][2 * (size_t)v + 1];
    }
    if (src->uvs[1]) {
        float u = src->uvs[1][2 * (size_t)v], t = src->uvs[1][2 * (size_t)v + 1];
        vx->texcoord1[0] = u;
        vx->texcoord1[1] = t;
        if (src->uv1_file) {
            vx->uv1[0] = u < 0 ? 0 : u > 1 ? 1 : u;
            vx->uv1[1] = t < 0 ? 0 : t > 1 ? 1 : t;
        }
    }
    for (int k = 0; k < 4; k++)
        vx->color[k] = src->colors ? src->colors[4 * (size_t)v + (size_t)k] : 1.0f;
    for (int r = 0; r < 4; r++)
        if (!isfinite(vx->tangent[r]))
            any_tangent(vx->normal, vx->tangent);
    for (int r = 0; r < 3; r++)
        if (!isfinite(vx->pos[r]) || !isfinite(vx->normal[r]))
            return fail(c, 400, field, "a vertex is not finite in world space");
    if (!isfinite(vx->uv0[0]) || !isfinite(vx->uv0[1]))
        return fail(c, 400, field, "TEXCOORD_0 is not finite");
    if (!isfinite(vx->texcoord1[0]) || !isfinite(vx->texcoord1[1]))
        return fail(c, 400, field, "TEXCOORD_1 is not finite");
    for (int k = 0; k < 4; k++)
        if (!isfinite(vx->color[k]))
            return fail(c, 400, field, "COLOR_0 is not finite");
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
    struct vertex_sources src = {0, NULL, NULL, NULL, {NULL, NULL}, NULL, false};
    uint32_t *corners = NULL;
    float *world = NULL;
    struct uv_charts charts = {0};
    bool ok = false;
    if (!sources_from_assimp(am, pi->has_normal, &src)) {
        fail(c, 500, field, "out of memory");
        goto done;
    }
    /* Both uv sets in glTF's convention (origin top left) and COLOR_0,
     * decoded from the checked accessors (assimp 5.2 copies quantized ones
     * as raw bytes into floats). */
    for (int set = 0; set < 2; set++)
        if (pi->uv_accessor[set] >= 0 &&
            !decode_attribute(c, pi->uv_accessor[set], am, 2, set ? "TEXCOORD_1" : "TEXCOORD_0",
                              field, &src.uvs[set]))
            goto done;
    if (pi->color_accessor >= 0 &&
        !decode_attribute(c, pi->color_accessor, am, 4, "COLOR_0", field, &src.colors))
        goto done;
    /* The triangles' corners, mirrored ones swapped so that front faces
     * stay counter-clockwise after a negative-determinant matrix. */
    corners = malloc((size_t)ntri * 3 * sizeof(uint32_t));
    if (!corners) {
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
    if (!pi->has_normal && !unweld(&src, corners, ntri, det < 0)) {
        fail(c, 500, field, "out of memory");
        goto done;
    }
    /* Tangents the file does not give, from the normal texture's set where
     * assimp's are not (it derives them from TEXCOORD_0, with the normals it
     * generates where the file has none, not the flat ones). Swapped
     * corners give the same sums. */
    int nset = normal_uv_set(c, material);
    if (!pi->has_tangent && src.uvs[nset] && (nset == 1 || !pi->has_normal) &&
        !uv_tangents(&src, src.uvs[nset], corners, ntri)) {
        fail(c, 500, field, "out of memory");
        goto done;
    }
    /* uv1: the file's TEXCOORD_1 where it stays inside [0, 1] and its
     * charts do not overlap, else generated charts; materials read the
     * file's sets either way. */
    enum asset_uv1_origin origin = src.uvs[1] ? ASSET_UV1_FILE : ASSET_UV1_GENERATED_NO_SET;
    for (uint32_t v = 0; origin == ASSET_UV1_FILE && v < src.count; v++) {
        float u = src.uvs[1][2 * v], w = src.uvs[1][2 * v + 1];
        if (!(u >= -1e-4f && u <= 1.0001f && w >= -1e-4f && w <= 1.0001f))
            origin = ASSET_UV1_GENERATED_OUTSIDE;
    }
    struct uv_coverage cov = {0, 0, 0};
    if (origin == ASSET_UV1_FILE) {
        if (!uv_overlap_measure(src.uvs[1], src.count, corners, ntri, UV_OVERLAP_RESOLUTION,
                                &cov)) {
            fail(c, 500, field, "out of memory");
            goto done;
        }
        out->texcoord1_overlap = (float)uv_coverage_overlap_share(&cov);
        if (uv_coverage_overlaps(&cov))
            origin = ASSET_UV1_GENERATED_OVERLAP;
    }
    src.uv1_file = origin == ASSET_UV1_FILE;
    uint64_t nv = src.count;
    if (!src.uv1_file) {
        if (!(world = malloc((size_t)src.count * 3 * sizeof(float)))) {
            fail(c, 500, field, "out of memory");
            goto done;
        }
        for (uint32_t v = 0; v < src.count; v++)
            xform_point(m, &src.pos[3 * (size_t)v], world + 3 * (size_t)v);
        char cerr[128];
        if (!uv_charts_build(world, src.count, corners, ntri, c->lim->max_vertices, &charts, cerr,
                             sizeof(cerr))) {
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
    out->uv1_origin = origin;
    out->tangents_from_file = pi->has_tangent && am->mTangents;
    out->has_uv0 = src.uvs[0] != NULL;
    out->has_texcoord1 = src.uvs[1] != NULL;
    out->has_color = src.colors != NULL;
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
        if (!fill_vertex(c, &src, src.uv1_file ? v : charts.source[v], m, nm, det, &vs[v], field))
            goto done;
        if (!src.uv1_file) {
            vs[v].uv1[0] = charts.uv[v][0];
            vs[v].uv1[1] = charts.uv[v][1];
        }
    }
    memcpy(out->indices, src.uv1_file ? corners : charts.indices, (size_t)ntri * 3 * sizeof(uint32_t));
    /* The share of uv1's square no triangle covers: the file's charts as
     * the raster measured them (what is covered, overlaps counted once),
     * the generated ones (which never overlap) by their area. */
    double covered = 0;
    if (src.uv1_file) {
        covered = (double)cov.covered / (double)cov.texels;
    } else {
        for (t = 0; t < ntri; t++) {
            const uint32_t *ix = &out->indices[t * 3];
            covered += tri_area2(vs[ix[0]].uv1, vs[ix[1]].uv1, vs[ix[2]].uv1);
        }
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
    sources_free(&src);
    uv_charts_free(&charts);
    return ok;
}

/* Where assimp put glTF node i's meshes, from its node an: assimp numbers
 * its meshes in the order it first reads them (children before their
 * parent's mesh) and never reads a mesh no node uses, so mesh m's
 * primitives are found through a node that draws it, not at a position
 * counted from the file. assimp's node tree mirrors the scene's: one node
 * per glTF node, children in order. first[m]: the assimp index of mesh m's
 * primitive 0 (SIZE_MAX until a node names it). */
static bool map_meshes(struct ctx *c, const struct aiScene *sc, const struct aiNode *an, size_t i,
                       size_t *first)
{
    json_t *node = json_array_get(c->nodes, i);
    json_t *children = json_object_get(node, "children");
    json_t *mi = json_object_get(node, "mesh");
    size_t prims = mi ? json_array_size(json_object_get(
                            json_array_get(c->meshes, (size_t)json_integer_value(mi)), "primitives"))
                      : 0;
    if (!an || an->mNumChildren != json_array_size(children) || an->mNumMeshes != prims)
        return fail(c, 500, "nodes", "assimp's node %zu does not match the file's", i);
    if (mi) {
        size_t m = (size_t)json_integer_value(mi), at = an->mMeshes[0];
        for (size_t p = 0; p < prims; p++)
            if (an->mMeshes[p] != at + p || at + p >= sc->mNumMeshes)
                return fail(c, 500, "meshes", "assimp's meshes of mesh %zu are not in order", m);
        if (first[m] != SIZE_MAX && first[m] != at)
            return fail(c, 500, "meshes", "assimp read mesh %zu twice", m);
        first[m] = at;
    }
    size_t k;
    json_t *ch;
    json_array_foreach(children, k, ch)
        if (!map_meshes(c, sc, an->mChildren[k], (size_t)json_integer_value(ch), first))
            return false;
    return true;
}

bool build_meshes(struct ctx *c, const struct aiScene *sc, struct prim_info **infos,
                  const bool *in_scene, int64_t scene_index, struct asset *a)
{
    size_t nm = json_array_size(c->meshes);
    size_t *offset = malloc((nm + 1) * sizeof(size_t));
    if (!offset)
        return fail(c, 500, "meshes", "out of memory");
    for (size_t m = 0; m <= nm; m++)
        offset[m] = SIZE_MAX;
    bool ok = false;
    json_t *roots = json_object_get(json_array_get(json_object_get(c->root, "scenes"),
                                                   (size_t)scene_index), "nodes");
    size_t nroots = json_array_size(roots);
    /* One root is assimp's root; several hang under a root of its own. */
    const struct aiNode *top = sc->mRootNode;
    if (!top || (nroots > 1 && top->mNumChildren != nroots)) {
        fail(c, 500, "nodes", "assimp's scene does not have the file's %zu root nodes", nroots);
        goto done;
    }
    for (size_t k = 0; k < nroots; k++)
        if (!map_meshes(c, sc, nroots > 1 ? top->mChildren[k] : top,
                        (size_t)json_integer_value(json_array_get(roots, k)), offset))
            goto done;
    size_t count = 0;
    for (size_t i = 0; i < json_array_size(c->nodes); i++) {
        json_t *mi = json_object_get(json_array_get(c->nodes, i), "mesh");
        if (in_scene[i] && mi)
            count += json_array_size(json_object_get(
                json_array_get(c->meshes, (size_t)json_integer_value(mi)), "primitives"));
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
