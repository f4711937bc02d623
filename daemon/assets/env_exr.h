#ifndef SHADEBENCH_ENV_EXR_H
#define SHADEBENCH_ENV_EXR_H

/* An uploaded equirectangular OpenEXR image (issue 32) into an environment
 * image (daemon/scene/environment.h), for the converter child
 * (shadebench-asset) beside the Radiance reader (env_convert.c), with the
 * same rules: the header is read first and a size over the limits refused
 * before anything is decoded; each chunk's extent is checked against the
 * file before it is read, so that a file cut short is refused naming the
 * chunk where it ends. OpenEXR's C library (OpenEXRCore, Debian's
 * libopenexr-dev) parses and decompresses, from memory: it opens no file.
 * The first part is read: scanline or tiled (level 0), its R, G and B
 * channels (or Y alone, as grey), half, float or uint, each converted to
 * float; deep images and subsampled channels are refused. Never linked into
 * the daemon. One thread. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/assets/asset_convert.h" /* struct asset_convert_error */
#include "daemon/scene/environment.h"

/* True when data starts with OpenEXR's magic number (76 2f 31 01). */
/* An environment's refusal: e filled with the status, the field and the
 * message; returns false (env_convert.c, for both decoders). */
bool env_fail(struct asset_convert_error *e, int status, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

bool env_exr_is(const uint8_t *data, size_t len);

/* Decodes data into out (environment_image_finish frees it); false with
 * e: status 422 naming limits.max_environment_edge or _pixels, or body for
 * a file that is not an OpenEXR image, is truncated or corrupt, or holds
 * no colour channels the environment can take. */
bool env_exr_decode(const uint8_t *data, size_t len, const struct environment_limits *lim,
                    struct environment_image *out, struct asset_convert_error *e);

#endif
