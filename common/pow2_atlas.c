#include "common/pow2_atlas.h"

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

void atlas_place(const int *sizes, int count, int w, int h, int *order,
                 struct atlas_tile *tiles)
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
