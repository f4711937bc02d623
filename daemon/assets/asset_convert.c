#define _POSIX_C_SOURCE 200809L
/* The converter's core (asset_convert.h): runs its stages in order. Three
 * stages, each in its own file (convert_internal.h):
 *
 * 1. Checks (convert_checks.c), with jansson, before anything else reads
 *    the file: the GLB container, the JSON, every buffer, bufferView and accessor range, the
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
 * 3. The rest comes from the checked JSON, where assimp loses it
 *    (convert_build.c): the node tree and its world matrices
 *    (convert_matrices.c; assimp keeps them, but folds lights and cameras
 *    into nodes by name), materials with each slot's TEXCOORD set
 *    and sampler filters, KHR_lights_punctual's intensity and range, the
 *    cameras' yfov, and the images, decoded with libpng and libjpeg
 *    from the bytes stage 1 checked (convert_images.c). */
#include "daemon/assets/asset_convert.h"
#include "daemon/assets/convert_internal.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

static bool convert(const uint8_t *data, size_t len, const struct asset_limits *lim,
                    struct asset *out, struct asset_convert_error *err, bool import)
{
    memset(out, 0, sizeof(*out));
    memset(err, 0, sizeof(*err));
    struct ctx c = {.lim = lim, .err = err};
    struct prim_info **infos = NULL;
    const bool *in_scene = NULL;
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
        !check_lights_cameras(&c) || !check_meshes(&c, &infos))
        goto done;

    in_scene = c.in_scene;

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
    if (!build_meshes(&c, sc, infos, in_scene, scene_index, out) || !build_materials(&c, out) ||
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
    free(c.in_scene);
    free(c.index_max);
    free(c.level);
    free(c.top);
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
