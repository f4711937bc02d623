#ifndef SHADEBENCH_UV_CHARTS_H
#define SHADEBENCH_UV_CHARTS_H

/* The converter's uv1 for a mesh whose file gives none: a unique
 * parametrisation in [0, 1]^2 for object-space shading. Adjacent triangles
 * whose normals stay within 30 degrees of their chart's first triangle
 * (and agree on orientation) form one chart, projected onto that
 * triangle's plane, so texel density is the same everywhere (uv area is
 * world area times one scale per mesh); their bounding rectangles are
 * packed on a skyline (the tallest first, each where its top ends lowest,
 * either way round) into the smallest square that holds them, each padded
 * by a gutter of GUTTER_TEXELS at an ATLAS_TEXELS-texel atlas: the
 * rectangles never overlap, which OSL's raster pass relies on to keep its
 * filtering inside each chart at every level (daemon/scene/mesh_charts.h).
 * Vertices are duplicated only where a chart boundary runs through them.
 * Pure and GL-free: any thread, no shared state. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum { UV_CHARTS_GUTTER_TEXELS = 1, UV_CHARTS_ATLAS_TEXELS = 1024 };

struct uv_charts {
    uint32_t vertex_count; /* the new vertices */
    uint32_t *source;      /* per new vertex: the input vertex it copies */
    float (*uv)[2];        /* per new vertex, in [0, 1] */
    uint32_t *indices;     /* 3 per input triangle, into the new vertices, corners in input order */
    uint32_t chart_count;
    double waste;          /* share of [0, 1]^2 no triangle covers */
};

/* pos: 3 floats per input vertex (world space); tri: 3 indices per
 * triangle, each < vertex_count. Fails (out of memory, or more than
 * max_vertices new vertices) with out freed. */
bool uv_charts_build(const float *pos, uint32_t vertex_count, const uint32_t *tri, uint32_t tri_count,
                     uint64_t max_vertices, struct uv_charts *out, char *err, size_t errlen);
void uv_charts_free(struct uv_charts *c);

#endif
