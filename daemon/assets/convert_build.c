#define _POSIX_C_SOURCE 200809L
/* Building the asset (convert_internal.h) from assimp's meshes and the
 * checked JSON, where assimp loses what the file says: materials with each
 * slot's TEXCOORD set and sampler filters, KHR_lights_punctual's intensity
 * and range, the cameras' yfov, and the meshes in world space with their
 * uv1 charts, from the file or generated. */
#include "daemon/assets/convert_internal.h"
#include "daemon/assets/uv_charts.h"

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
            ac->yfov = (float)num_or(p, "yfov", 0.8);
            ac->znear = (float)num_or(p, "znear", 0.1);
            ac->zfar = (float)num_or(p, "zfar", 0.0);
            ac->aspect = (float)num_or(p, "aspectRatio", 0.0);
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

bool build_meshes(struct ctx *c, const struct aiScene *sc, struct prim_info **infos,
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
