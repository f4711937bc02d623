#ifndef SHADEBENCH_UV_OVERLAP_H
#define SHADEBENCH_UV_OVERLAP_H

/* Whether a file's uv set can serve as the unique parametrisation that
 * object-space shading needs (asset.h's uv1): the triangles' uv coverage
 * rasterised at texel centres of a resolution x resolution grid over
 * [0, 1]^2, each centre counted once per triangle that holds it, edges
 * shared by two triangles owned by one of them (a top-left rule, so a
 * seamless chart counts each centre once). A centre more than one triangle
 * holds is a texel that object-space shading would light for two surface
 * points: mirrored halves sharing a chart, stacked or folded charts. The
 * work is one pass over the rows each triangle spans and the centres it
 * holds; the grid is resolution^2 bytes. Pure and GL-free: any thread, no
 * shared state. */

#include <stdbool.h>
#include <stdint.h>

enum { UV_OVERLAP_RESOLUTION = 512 };

struct uv_coverage {
    uint64_t texels;     /* resolution^2 */
    uint64_t covered;    /* centres at least one triangle holds */
    uint64_t overlapped; /* centres more than one triangle holds */
};

/* uv: 2 floats per vertex, assumed inside [0, 1] (centres outside the grid
 * are not counted); tri: 3 indices per triangle, each < vertex_count.
 * False only when the grid cannot be allocated. */
bool uv_overlap_measure(const float *uv, uint32_t vertex_count, const uint32_t *tri,
                        uint32_t tri_count, int resolution, struct uv_coverage *out);

/* overlapped / covered (0 for nothing covered). */
double uv_coverage_overlap_share(const struct uv_coverage *c);

/* The rule the converter applies: the set overlaps when more than a
 * thousandth of its covered texels, and more than four, are held twice
 * (below that, rounding along a chart's border, which object-space
 * shading's gutters absorb). */
bool uv_coverage_overlaps(const struct uv_coverage *c);

#endif
