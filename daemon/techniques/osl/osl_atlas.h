#ifndef SHADEBENCH_OSL_ATLAS_H
#define SHADEBENCH_OSL_ATLAS_H

/* The shading atlas (the thesis's "mega texture"): one power-of-two tile per
 * instance, each aligned to its own size. GL-free.
 *
 * Tiles are packed edge to edge: the gutter that keeps bilinear filtering
 * inside a chart is enforced where the atlas is sampled, by clamping to the
 * centres of texels that lie inside the chart (osl_draw.frag), so it
 * holds at every tile size from 8 texels up without wasting atlas space. */

#include <stdbool.h>
#include <stddef.h>

#include "common/pow2_atlas.h"

#define OSL_TILE_MIN 8
#define OSL_TILE_MAX 1024

/* Packs tiles of the given power-of-two sizes into the smallest atlas of
 * S x S or S x S/2 texels (S a power of two) that holds them, at most
 * max_size on a side and max_bytes at 4 bytes a texel, placed by
 * atlas_place. */
bool osl_atlas_pack(const int *sizes, int count, int max_size, double max_bytes,
                    struct atlas_tile *tiles, int *width, int *height, char *err,
                    size_t errlen);

/* Tile edge that gives about texel_density texels per covered pixel for an
 * object covering pixels_per_unit pixels per world unit whose UV layout has
 * uv_per_unit UV units per world unit: the nearest power of two in log
 * space, clamped to [OSL_TILE_MIN, OSL_TILE_MAX]. */
int osl_auto_tile_size(double pixels_per_unit, double uv_per_unit, double texel_density);

#endif
