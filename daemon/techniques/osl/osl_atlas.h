#ifndef SHADEBENCH_OSL_ATLAS_H
#define SHADEBENCH_OSL_ATLAS_H

/* The shading atlas (the thesis's "mega texture"): one power-of-two tile per
 * instance, each aligned to its own size. GL-free.
 *
 * Tiles are packed edge to edge: the gutter that keeps bilinear filtering
 * inside a chart is enforced where the atlas is sampled, by clamping to the
 * centres of texels that lie inside the chart (shaders/osl_draw.frag), so it
 * holds at every tile size from 8 texels up without wasting atlas space. */

#include <stdbool.h>
#include <stddef.h>

#define OSL_TILE_MIN 8
#define OSL_TILE_MAX 1024

struct osl_tile {
    int x, y, size;
};

/* Packs tiles of the given power-of-two sizes into the smallest atlas of
 * S x S or S x S/2 texels (S a power of two) that holds them, at most
 * max_size on a side and max_bytes at 4 bytes a texel. */
bool osl_atlas_pack(const int *sizes, int count, int max_size, double max_bytes,
                    struct osl_tile *tiles, int *width, int *height, char *err,
                    size_t errlen);

/* Places tiles of power-of-two sizes, largest first (equal sizes in index
 * order), each at the next Z-order position of its size, in an atlas of
 * w x h texels (h a power of two at least the largest size, w a multiple
 * of h) whose area holds them all; order is scratch for count ints. Never
 * allocates, so the shadow atlas (daemon/lighting/shadow_plan.c) packs with
 * it every frame. */
void osl_atlas_place(const int *sizes, int count, int w, int h, int *order,
                     struct osl_tile *tiles);

/* Tile edge that gives about texel_density texels per covered pixel for an
 * object covering pixels_per_unit pixels per world unit whose UV layout has
 * uv_per_unit UV units per world unit: the nearest power of two in log
 * space, clamped to [OSL_TILE_MIN, OSL_TILE_MAX]. */
int osl_auto_tile_size(double pixels_per_unit, double uv_per_unit, double texel_density);

#endif
