/* A uv set's coverage and overlap on a texel grid (uv_overlap.h). */
#include "daemon/assets/uv_overlap.h"

#include <math.h>
#include <stdlib.h>

struct tri2 {
    double x[3], y[3]; /* texel units, counter-clockwise (positive area) */
};

/* Edge i (corner i to i + 1) holds p: inside, or on the edge and the edge
 * is one that owns its points (going up, or going left when level). Of two
 * triangles sharing an edge, which run it in opposite directions, exactly
 * one owns it. */
static bool edge_holds(const struct tri2 *t, int i, double px, double py)
{
    int j = i == 2 ? 0 : i + 1;
    double dx = t->x[j] - t->x[i], dy = t->y[j] - t->y[i];
    double e = dx * (py - t->y[i]) - dy * (px - t->x[i]);
    if (e != 0.0)
        return e > 0.0;
    return dy < 0.0 || (dy == 0.0 && dx > 0.0);
}

static bool holds(const struct tri2 *t, double px, double py)
{
    return edge_holds(t, 0, px, py) && edge_holds(t, 1, px, py) && edge_holds(t, 2, px, py);
}

/* Row py's centres inside the triangle lie in [*lo, *hi] (a bound found in
 * floating point, refined by holds() at its ends). */
static void row_span(const struct tri2 *t, double py, double *lo, double *hi)
{
    *lo = -INFINITY;
    *hi = INFINITY;
    for (int i = 0; i < 3; i++) {
        int j = i == 2 ? 0 : i + 1;
        double dx = t->x[j] - t->x[i], dy = t->y[j] - t->y[i];
        /* e(px) = dx (py - y_i) - dy (px - x_i) >= 0 */
        double a = dx * (py - t->y[i]) + dy * t->x[i];
        if (dy > 0.0)
            *hi = fmin(*hi, a / dy);
        else if (dy < 0.0)
            *lo = fmax(*lo, a / dy);
        else if (dx * (py - t->y[i]) < 0.0)
            *lo = INFINITY; /* the row lies outside this level edge */
    }
}

bool uv_overlap_measure(const float *uv, uint32_t vertex_count, const uint32_t *tri,
                        uint32_t tri_count, int resolution, struct uv_coverage *out)
{
    (void)vertex_count;
    int n = resolution;
    out->texels = (uint64_t)n * (uint64_t)n;
    out->covered = out->overlapped = 0;
    uint8_t *grid = calloc((size_t)n * (size_t)n, 1);
    if (!grid)
        return false;
    for (uint32_t k = 0; k < tri_count; k++) {
        struct tri2 t;
        for (int c = 0; c < 3; c++) {
            const float *p = uv + 2 * (size_t)tri[3 * k + (uint32_t)c];
            t.x[c] = (double)p[0] * n;
            t.y[c] = (double)p[1] * n;
        }
        double area = (t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.x[2] - t.x[0]) * (t.y[1] - t.y[0]);
        if (!(area != 0.0) || !isfinite(area))
            continue; /* degenerate: holds no centre */
        if (area < 0.0) {
            double sx = t.x[1], sy = t.y[1];
            t.x[1] = t.x[2], t.y[1] = t.y[2];
            t.x[2] = sx, t.y[2] = sy;
        }
        double ymin = fmin(t.y[0], fmin(t.y[1], t.y[2])), ymax = fmax(t.y[0], fmax(t.y[1], t.y[2]));
        int y0 = (int)fmax(0.0, ceil(ymin - 0.5)), y1 = (int)fmin(n - 1.0, floor(ymax - 0.5));
        for (int y = y0; y <= y1; y++) {
            double py = y + 0.5, lo, hi;
            row_span(&t, py, &lo, &hi);
            if (!(lo <= hi))
                continue;
            int x0 = (int)fmax(0.0, ceil(lo - 0.5) - 1.0), x1 = (int)fmin(n - 1.0, floor(hi - 0.5) + 1.0);
            uint8_t *row = grid + (size_t)y * (size_t)n;
            for (int x = x0; x <= x1; x++) {
                if (!holds(&t, x + 0.5, py))
                    continue;
                if (row[x] == 0)
                    out->covered++;
                else if (row[x] == 1)
                    out->overlapped++;
                if (row[x] < 2)
                    row[x]++;
            }
        }
    }
    free(grid);
    return true;
}

double uv_coverage_overlap_share(const struct uv_coverage *c)
{
    return c->covered ? (double)c->overlapped / (double)c->covered : 0.0;
}

bool uv_coverage_overlaps(const struct uv_coverage *c)
{
    return c->overlapped > 4 && c->overlapped * 1000 > c->covered;
}
