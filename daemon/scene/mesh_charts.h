#ifndef SHADEBENCH_MESH_CHARTS_H
#define SHADEBENCH_MESH_CHARTS_H

/* The charts of an asset mesh's uv1 (OSL's unique parametrisation): the
 * triangles connected through shared vertices form a chart, and each
 * vertex gets its chart's bounding rectangle (mesh_vertex.chart), so that
 * OSL's raster pass keeps its filtering inside the chart's own texels at
 * every level, as it does on the procedural meshes' rectangular charts.
 * Charts whose rectangles overlap another's (a file's uv1 may interleave
 * them) keep [0, 1]^2, no clamp. GL-free; any thread, on a mesh it owns. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/scene/mesh.h"

struct mesh_chart_stats {
    uint32_t charts;      /* connected pieces of uv1 */
    uint32_t overlapping; /* of them, with a rectangle that overlaps another's */
};

/* Sets every vertex's chart; false when out of memory (the mesh is left as
 * it was). stats may be NULL. */
bool mesh_chart_rects(struct mesh *m, struct mesh_chart_stats *stats);

#endif
