#include "daemon/techniques/osl/osl_atlas.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

bool osl_atlas_pack(const int *sizes, int count, int max_size, double max_bytes,
                    struct atlas_tile *tiles, int *width, int *height, char *err,
                    size_t errlen)
{
    double area = 0;
    int largest = 0;
    for (int i = 0; i < count; i++) {
        int s = sizes[i];
        if (s < 1 || (s & (s - 1))) {
            snprintf(err, errlen, "tile %d has size %d, not a power of two", i, s);
            return false;
        }
        area += (double)s * s;
        if (s > largest)
            largest = s;
    }
    /* Smallest S x H with H in {S/2, S} holding the area and the largest tile. */
    int w = largest > 0 ? largest : 1, h = w;
    while ((double)w * h < area) {
        if (h < w)
            h = w;
        else
            w *= 2, h = w / 2 >= largest ? w / 2 : w;
    }
    if (w > max_size || (double)w * h * 4.0 > max_bytes) {
        snprintf(err, errlen,
                 "the shading atlas needs %dx%d texels (%.0f MiB) for %d tiles; this "
                 "device allows at most %dx%d and the limit is %.0f MiB: lower "
                 "osl.resolution or osl.texel_density",
                 w, h, (double)w * h * 4.0 / 1048576.0, count, max_size, max_size,
                 max_bytes / 1048576.0);
        return false;
    }
    int *order = malloc((size_t)(count ? count : 1) * sizeof(int));
    if (!order) {
        snprintf(err, errlen, "out of memory packing the atlas");
        return false;
    }
    atlas_place(sizes, count, w, h, order, tiles);
    free(order);
    *width = w;
    *height = h;
    return true;
}

int osl_auto_tile_size(double pixels_per_unit, double uv_per_unit, double texel_density)
{
    double texels = pixels_per_unit * texel_density / uv_per_unit;
    if (!(texels > OSL_TILE_MIN))
        return OSL_TILE_MIN;
    int size = 1 << (int)lround(log2(texels));
    if (size < OSL_TILE_MIN)
        return OSL_TILE_MIN;
    return size > OSL_TILE_MAX ? OSL_TILE_MAX : size;
}
