/* The asset cache reader (asset_file_parse) on any bytes. Invariants: it
 * never crashes or over-allocates (libFuzzer's RSS limit); a refusal has a
 * message and leaves a zeroed asset; what it accepts holds only in-range
 * indices, image and material references, finite uv1 in [0, 1], and
 * describes. */
#include <math.h>
#include <string.h>

#include "daemon/scene/asset.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    struct asset a;
    char err[256] = "";
    if (!asset_file_parse(&a, data, size, &lim, err, sizeof(err))) {
        FUZZ_ASSERT(err[0] != '\0');
        FUZZ_ASSERT(a.meshes == NULL && a.images == NULL && a.mesh_count == 0);
        return 0;
    }
    for (uint32_t m = 0; m < a.mesh_count; m++) {
        const struct asset_mesh *me = &a.meshes[m];
        FUZZ_ASSERT(me->index_count % 3 == 0);
        FUZZ_ASSERT(me->material < (int32_t)a.material_count);
        for (uint32_t k = 0; k < me->index_count; k++)
            FUZZ_ASSERT(me->indices[k] < me->vertex_count);
        for (uint32_t v = 0; v < me->vertex_count; v++)
            FUZZ_ASSERT(me->vertices[v].uv1[0] >= 0 && me->vertices[v].uv1[0] <= 1);
    }
    for (uint32_t i = 0; i < a.material_count; i++)
        for (int s = 0; s < ASSET_TEX_SLOTS; s++)
            FUZZ_ASSERT(a.materials[i].tex[s].image < (int32_t)a.image_count);
    json_t *d = asset_describe(&a);
    FUZZ_ASSERT(d != NULL);
    json_decref(d);
    asset_finish(&a);
    return 0;
}
