#ifndef SHADEBENCH_ASSET_SYNTHETIC_H
#define SHADEBENCH_ASSET_SYNTHETIC_H

/* The textured preset's asset, built in memory in the form the cache reader
 * gives (daemon/scene/asset.h), so that the preset exercises exactly the
 * path an uploaded glTF file takes: a checker ground with normal,
 * metallic-roughness and occlusion maps, boxes and spheres with tangents
 * and both uv sets, an emissive object, an alpha-masked leaf quad, a glass
 * pane, a swatch of a known sRGB texel, two cameras and a spot and a
 * directional light. Deterministic (no clock, no randomness). GL-free; the
 * asset belongs to the thread that built it. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/scene/asset.h"

/* The swatch's texel: the flat quarter of the checker image (texels x and y
 * below ASSET_SYNTHETIC_FLAT_EDGE), sRGB-encoded bytes. The "swatch" mesh
 * samples only that quarter, so every mip level it can reach holds this
 * value (tests/e2e/e2e_textured.py reads it back). */
enum { ASSET_SYNTHETIC_FLAT_EDGE = 32, ASSET_SYNTHETIC_IMAGE_EDGE = 64 };
extern const unsigned char ASSET_SYNTHETIC_FLAT_SRGB[3];

/* Fills *out; on failure (out of memory) it is freed and zeroed. */
bool asset_synthetic_textured(struct asset *out, char *err, size_t errlen);


#endif
