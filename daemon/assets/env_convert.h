#ifndef SHADEBENCH_ENV_CONVERT_H
#define SHADEBENCH_ENV_CONVERT_H

/* The environment half of the converter child (shadebench-asset): an
 * uploaded equirectangular Radiance .hdr image (or an OpenEXR one:
 * env_exr.h) checked and decoded into an environment image
 * (daemon/scene/environment.h); and the Radiance copy of a decoded image
 * that the Khronos viewer, which reads only .hdr, is given for an OpenEXR
 * upload. The header is read first
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

/* "radiance_hdr" when data starts as a Radiance file does ("#?"),
 * "openexr" when it starts with OpenEXR's magic number, else NULL. */
const char *env_convert_format(const uint8_t *data, size_t len);

/* Decodes data, a Radiance or OpenEXR image by its first bytes, into out
 * (environment_image_finish frees it); false with e: status 422 naming
 * limits.max_environment_edge or _pixels, or body for a file that is
 * neither, is truncated or corrupt. */
bool env_convert_buffer(const uint8_t *data, size_t len, const struct environment_limits *lim,
                        struct environment_image *out, struct asset_convert_error *e);

/* Writes img to path as a Radiance .hdr (RGBE: 8 bits of mantissa shared
 * by the three channels, so a channel keeps about 1/256 of the largest's
 * precision), scanlines run-length coded as most writers do; synced. False
 * with err. */
bool env_convert_write_radiance(const struct environment_image *img, const char *path, char *err,
                                size_t errlen);

#endif
