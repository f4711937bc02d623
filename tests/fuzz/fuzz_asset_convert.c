/* The converter's own code on a memory buffer (asset_convert_checks: the
 * glTF checks, then the materials, PNG and JPEG decoding, lights and
 * cameras), on any bytes, under limits small enough for the fuzzer's
 * memory. Not assimp's import: assimp 5.2 crashes on inputs the checks pass
 * (this target found one in seconds when it ran the import), which the
 * converter, a child process of the daemon, survives as a loader failure;
 * tests/fuzz/regressions/asset_convert keeps such inputs for the replay,
 * which runs the checks the same way. Invariants: no crash, no leak; a
 * refusal is 400, 422 or 500 with a field and a message; what is accepted
 * holds in-range references and images within the limits, and describes. */
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
    if (!asset_convert_checks(data, size, &lim, &a, &err)) {
        FUZZ_ASSERT(err.status == 400 || err.status == 422 || err.status == 500);
        FUZZ_ASSERT(err.field[0] != '\0' && err.message[0] != '\0');
        FUZZ_ASSERT(a.meshes == NULL && a.mesh_count == 0);
        return 0;
    }
    FUZZ_ASSERT(a.mesh_count == 0 && a.meshes == NULL);
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
