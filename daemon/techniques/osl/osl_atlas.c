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

void osl_chart_owners(const float (*rects)[4], int count, int size, int *owner)
{
    for (size_t t = 0; t < (size_t)size * size; t++)
        owner[t] = -1;
    for (int r = 0; r < count; r++) {
        int x0 = (int)ceil(rects[r][0] * size - 0.5), y0 = (int)ceil(rects[r][1] * size - 0.5);
        int x1 = (int)floor(rects[r][2] * size - 0.5), y1 = (int)floor(rects[r][3] * size - 0.5);
        x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
        x1 = x1 >= size ? size - 1 : x1, y1 = y1 >= size ? size - 1 : y1;
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++)
                owner[(size_t)y * size + x] = r;
    }
}

long osl_dilate_geometry(float *pos, float *nrm, float *const *extra, int extra_count, int size,
                         int passes, const int *owner)
{
    long filled = 0;
    for (int pass = 0; pass < passes; pass++) {
        /* Coverage as the pass found it: w == 1 marks covered; texels this
         * pass fills are marked 2 until the pass ends. */
        long this_pass = 0;
        for (int y = 0; y < size; y++)
            for (int x = 0; x < size; x++) {
                float *p = &pos[((size_t)y * size + x) * 4];
                if (p[3] != 0.0f)
                    continue;
                int own = owner ? owner[(size_t)y * size + x] : -1;
                float ps[3] = {0, 0, 0}, ns[4] = {0, 0, 0, 0}, es[4][4] = {{0}};
                int n = 0;
                float first[3] = {0, 0, 1}; /* a neighbour's normal, where the mean cancels */
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        int qx = x + dx, qy = y + dy;
                        if ((!dx && !dy) || qx < 0 || qy < 0 || qx >= size || qy >= size)
                            continue;
                        const float *q = &pos[((size_t)qy * size + qx) * 4];
                        if (q[3] != 1.0f || (own >= 0 && owner[(size_t)qy * size + qx] != own))
                            continue;
                        size_t at = ((size_t)qy * size + qx) * 4;
                        for (int k = 0; k < 3; k++)
                            ps[k] += q[k];
                        for (int k = 0; k < 4; k++)
                            ns[k] += nrm[at + k];
                        if (!n)
                            for (int k = 0; k < 3; k++)
                                first[k] = nrm[at + k];
                        for (int e = 0; e < extra_count && e < 4; e++)
                            for (int k = 0; k < 4; k++)
                                es[e][k] += extra[e][at + k];
                        n++;
                    }
                if (!n)
                    continue;
                float len = sqrtf(ns[0] * ns[0] + ns[1] * ns[1] + ns[2] * ns[2]);
                size_t at = ((size_t)y * size + x) * 4;
                float *m = &nrm[at];
                for (int k = 0; k < 3; k++) {
                    p[k] = ps[k] / (float)n;
                    m[k] = len > 1e-6f ? ns[k] / len : first[k];
                }
                m[3] = ns[3] / (float)n;
                for (int e = 0; e < extra_count && e < 4; e++)
                    for (int k = 0; k < 4; k++)
                        extra[e][at + k] = es[e][k] / (float)n;
                p[3] = 2.0f;
                this_pass++;
            }
        for (size_t t = 0; t < (size_t)size * size; t++)
            if (pos[t * 4 + 3] == 2.0f)
                pos[t * 4 + 3] = 1.0f;
        filled += this_pass;
        if (!this_pass)
            break;
    }
    return filled;
}
