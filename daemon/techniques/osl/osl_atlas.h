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

/* Gutter filling for UV layouts whose charts do not cover whole rectangles
 * (an asset's uv1): texels no triangle covered (position w == 0) that touch
 * a covered one (8-neighbourhood) take the mean position, normal (xyz
 * renormalised, w averaged) and extra channels of the covered neighbours
 * and become covered (w = 1), `passes` times, each pass reading the
 * coverage the one before left. Bilinear filtering at a chart's edge then
 * reads shading of about the edge's surface instead of black. With owner
 * (size x size chart indices, -1 for none; may be NULL), a texel that a
 * chart owns is filled from that chart's texels only, so that a chart's
 * rectangle holds its own surface however near another chart lies. pos,
 * nrm and the extra images are size x size RGBA float images (rows of size
 * texels); returns the texels filled. */
long osl_dilate_geometry(float *pos, float *nrm, float *const *extra, int extra_count, int size,
                         int passes, const int *owner);

/* The owner map of the given chart rectangles (u0, v0, u1, v1 each) at a
 * size x size level: each texel whose centre lies inside rectangle r gets r
 * (the centres osl_draw.frag clamps its samples to), the others -1. */
void osl_chart_owners(const float (*rects)[4], int count, int size, int *owner);

#endif
