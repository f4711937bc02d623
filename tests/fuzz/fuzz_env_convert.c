/* The environment map converter (env_convert_buffer: a Radiance .hdr's
 * header, its scanline walk, stb_image; an OpenEXR image's header, chunk
 * extents and OpenEXRCore's decoders) on any bytes. Invariants: it never
 * crashes or over-allocates (libFuzzer's RSS limit: the size limits are
 * read from the header before anything is decoded); a refusal names a
 * field and a message and leaves the image empty; what it accepts is within
 * the limits, finite and not negative, and describes. */
#include <math.h>
#include <string.h>

#include "daemon/assets/env_convert.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct environment_limits lim;
    environment_limits_defaults(&lim);
    /* Smaller than the daemon's, so that a run decodes many inputs. */
    lim.max_edge = 512;
    lim.max_pixels = 65536;
    struct environment_image img;
    struct asset_convert_error e;
    if (!env_convert_buffer(data, size, &lim, &img, &e)) {
        FUZZ_ASSERT(e.field[0] != '\0' && e.message[0] != '\0');
        FUZZ_ASSERT(img.rgb == NULL && img.width == 0 && img.height == 0);
        return 0;
    }
    FUZZ_ASSERT(img.width >= 1 && img.height >= 1 && img.width <= lim.max_edge &&
                img.height <= lim.max_edge && (uint64_t)img.width * img.height <= lim.max_pixels);
    for (size_t i = 0; i < (size_t)img.width * img.height * 3; i++)
        FUZZ_ASSERT(isfinite(img.rgb[i]) && img.rgb[i] >= 0.0f);
    json_t *d = environment_describe(&img, env_convert_format(data, size));
    FUZZ_ASSERT(d != NULL);
    json_decref(d);
    environment_image_finish(&img);
    return 0;
}
