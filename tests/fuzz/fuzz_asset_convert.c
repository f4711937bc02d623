/* The converter's whole path on a memory buffer (asset_convert_buffer: the
 * glTF checks, assimp's import, PNG and JPEG decoding) on any bytes, under
 * limits small enough for the fuzzer's memory. Invariants: no crash, no
 * leak; a refusal is 400, 422 or 500 with a field and a message; an
 * accepted asset holds in-range indices and references, uv1 in [0, 1], and
 * what it holds passes the cache reader's checks (each mesh, each image
 * within the limits). */
#include <string.h>

#include "daemon/assets/asset_convert.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    lim.max_vertices = 1u << 20;
    lim.max_indices = 3u << 20;
    lim.max_texture_pixels = 4u << 20;
    lim.max_texture_edge = 4096;
    struct asset a;
    struct asset_convert_error err;
    if (!asset_convert_buffer(data, size, &lim, &a, &err)) {
        FUZZ_ASSERT(err.status == 400 || err.status == 422 || err.status == 500);
        FUZZ_ASSERT(err.field[0] != '\0' && err.message[0] != '\0');
        FUZZ_ASSERT(a.meshes == NULL && a.mesh_count == 0);
        return 0;
    }
    FUZZ_ASSERT(a.mesh_count > 0);
    uint64_t verts = 0;
    for (uint32_t m = 0; m < a.mesh_count; m++) {
        const struct asset_mesh *me = &a.meshes[m];
        FUZZ_ASSERT(me->index_count > 0 && me->index_count % 3 == 0);
        FUZZ_ASSERT(me->material >= -1 && me->material < (int32_t)a.material_count);
        verts += me->vertex_count;
        for (uint32_t k = 0; k < me->index_count; k++)
            FUZZ_ASSERT(me->indices[k] < me->vertex_count);
        for (uint32_t v = 0; v < me->vertex_count; v++) {
            const float *uv1 = me->vertices[v].uv1;
            FUZZ_ASSERT(uv1[0] >= 0 && uv1[0] <= 1 && uv1[1] >= 0 && uv1[1] <= 1);
        }
        FUZZ_ASSERT(me->uv1_waste >= 0 && me->uv1_waste <= 1);
    }
    FUZZ_ASSERT(verts <= lim.max_vertices);
    for (uint32_t i = 0; i < a.image_count; i++)
        FUZZ_ASSERT(a.images[i].rgba && a.images[i].width <= lim.max_texture_edge &&
                    a.images[i].height <= lim.max_texture_edge);
    for (uint32_t i = 0; i < a.material_count; i++)
        for (int s = 0; s < ASSET_TEX_SLOTS; s++)
            FUZZ_ASSERT(a.materials[i].tex[s].image >= -1 &&
                        a.materials[i].tex[s].image < (int32_t)a.image_count);
    json_t *d = asset_describe(&a);
    FUZZ_ASSERT(d != NULL);
    json_decref(d);
    asset_finish(&a);
    return 0;
}
