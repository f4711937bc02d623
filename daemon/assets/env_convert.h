#ifndef SHADEBENCH_ENV_CONVERT_H
#define SHADEBENCH_ENV_CONVERT_H

/* The environment half of the converter child (shadebench-asset): an
 * uploaded equirectangular Radiance .hdr image checked and decoded into an
 * environment image (daemon/scene/environment.h). The header is read first
 * and a size over the limits refused before anything is decoded; the pixel
 * data is then walked scanline by scanline, so that a file cut short is
 * refused naming where it ends (stb_image, which decodes it, would fill
 * the missing rows with black); stb_image (Debian's libstb) decodes.
 * Never linked into the daemon. One thread. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/assets/asset_convert.h" /* struct asset_convert_error */
#include "daemon/scene/environment.h"

/* True when data starts as a Radiance file does ("#?"). */
bool env_convert_is_hdr(const uint8_t *data, size_t len);

/* Decodes data into out (environment_image_finish frees it); false with
 * e: status 422 naming limits.max_environment_edge or _pixels, or body for
 * a file that is not a Radiance image, is truncated or corrupt. */
bool env_convert_buffer(const uint8_t *data, size_t len, const struct environment_limits *lim,
                        struct environment_image *out, struct asset_convert_error *e);

#endif
