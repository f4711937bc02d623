#include "daemon/techniques/osl/osl_atlas.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int log2_of(int v)
{
    int l = 0;
    while ((1 << (l + 1)) <= v && l < 30)
        l++;
    return l;
}

/* Morton (Z-order) index to cell coordinates. */
static void demorton(unsigned long m, int *x, int *y)
{
    int cx = 0, cy = 0;
    for (int bit = 0; m; bit++, m >>= 2) {
        cx |= (int)(m & 1) << bit;
        cy |= (int)((m >> 1) & 1) << bit;
    }
    *x = cx;
    *y = cy;
}

bool osl_atlas_pack(const int *sizes, int count, int max_size, double max_bytes,
                    struct osl_tile *tiles, int *width, int *height, char *err,
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
    osl_atlas_place(sizes, count, w, h, order, tiles);
    free(order);
    *width = w;
    *height = h;
    return true;
}

void osl_atlas_place(const int *sizes, int count, int w, int h, int *order,
                     struct osl_tile *tiles)
{
    /* Largest first, equal sizes in index order: a counting sort over the
     * powers of two, so no allocation and the same order a stable sort
     * gives. */
    int per_log[32] = {0};
    for (int i = 0; i < count; i++)
        per_log[log2_of(sizes[i])]++;
    int start[32], next = 0;
    for (int l = 31; l >= 0; l--) {
        start[l] = next;
        next += per_log[l];
    }
    for (int i = 0; i < count; i++)
        order[start[log2_of(sizes[i])]++] = i;
    /* The atlas is w/h squares of h x h side by side. Largest tiles first,
     * each at the next Z-order position of its own size: with sizes falling,
     * the cursor is always aligned, so nothing overlaps and no space is lost. */
    (void)w;
    double cursor = 0;
    for (int k = 0; k < count; k++) {
        int i = order[k], s = sizes[i];
        double square_area = (double)h * h;
        int square = (int)(cursor / square_area);
        double inside = cursor - square * square_area;
        int cx, cy;
        demorton((unsigned long)(inside / ((double)s * s)), &cx, &cy);
        tiles[i].x = square * h + cx * s;
        tiles[i].y = cy * s;
        tiles[i].size = s;
        cursor += (double)s * s;
    }
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
