#ifndef SHADEBENCH_ENVIRONMENT_H
#define SHADEBENCH_ENVIRONMENT_H

/* An environment image: the equirectangular HDR map a user uploads
 * (PUT /v1/assets/NAME.hdr, a Radiance .hdr) and a look names
 * (look.ibl.environment {"asset": NAME}). The converter child decodes the
 * upload (daemon/assets/env_convert.c) and writes it here as linear RGB
 * floats in the asset's cache file, STATE/assets/SHA256.sbasset; the
 * render thread reads that file whole before anything is timed and uploads
 * it (daemon/look/sky.c). A direction d is read at u = 0.5 + atan2(d.z,
 * d.x) / (2 pi), v = acos(d.y) / pi with v = 0 the image's first (top)
 * row: the top row is the +y pole and the centre column looks along +x, as
 * the glTF Sample Viewer maps a panorama (docs/scenes.md, "Environment
 * maps"). GL-free; a value belongs to one thread at a time. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct environment_image {
    uint32_t width, height;
    float *rgb; /* width * height * 3, linear, finite, >= 0 */
};

/* What an environment may take: the converter refuses a file over either
 * from its header, before decoding, and the cache reader too. Shown in
 * /v1/info (assets.environment_limits). */
struct environment_limits {
    uint32_t max_edge;   /* width or height */
    uint64_t max_pixels; /* width * height: the decoded bytes are 12 a pixel */
};
void environment_limits_defaults(struct environment_limits *lim);
json_t *environment_limits_to_json(const struct environment_limits *lim);

/* The cache file: "SBENV001", u32 width, u32 height (little-endian), then
 * the floats (little-endian IEEE 754). write: to path, atomically enough
 * for the converter (its caller renames). read: the whole file checked
 * (size, limits, every value finite and >= 0); false with err. */
bool environment_file_write(const struct environment_image *e, const char *path, char *err,
                            size_t errlen);
bool environment_file_read(struct environment_image *e, const char *path,
                           const struct environment_limits *lim, char *err, size_t errlen);
/* True when the file at path starts as an environment cache does. */
bool environment_file_is(const char *path);
/* Frees the pixels; takes a zeroed or filled image. */
void environment_image_finish(struct environment_image *e);

/* The asset's description (GET /v1/assets/NAME): kind "environment", its
 * size, its radiance's mean and peak luminance. New reference or NULL. */
json_t *environment_describe(const struct environment_image *e, const char *format);

#endif
