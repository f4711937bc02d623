#ifndef SHADEBENCH_MESH_H
#define SHADEBENCH_MESH_H

/* Procedural meshes with UV layouts for object-space shading. GL-free; a
 * mesh belongs to the thread that built it, and reading one is safe from
 * any number of threads.
 * Every chart is an axis-aligned rectangle in UV space that the mesh's
 * triangles cover completely, so a texel whose centre lies inside a chart is
 * always written by the UV-space rasterization; samplers clamp to those
 * texel centres (see daemon/techniques/osl/osl_draw.frag), which is what
 * keeps bilinear filtering from bleeding across chart edges at every tile
 * size. */

#include <stdbool.h>
#include <stdint.h>

struct mesh_vertex {
    float pos[3];
    float normal[3];
    float uv[2];
    float chart[4]; /* u0, v0, u1, v1 of the chart this vertex belongs to */
    /* The material's texture coordinates, tangent frame and vertex colour
     * (an asset's TEXCOORD_0 in xy and TEXCOORD_1 in zw, TANGENT with its
     * handedness in w, COLOR_0); the procedural meshes have no textures and
     * leave them 0. */
    float tex[4];
    float tangent[4];
    float color[4];
};

struct mesh {
    struct mesh_vertex *vertices;
    uint32_t *indices;
    uint32_t vertex_count, index_count;
    float bound_radius;
    /* UV units per object-space unit along the chart's densest direction;
     * lets a tile size be chosen from an object's size on screen. */
    float uv_per_unit;
    float box_min[3], box_max[3]; /* object space; mesh_compute_box */
};

bool mesh_create_sphere(struct mesh *out, float radius, int segments);
bool mesh_create_cube(struct mesh *out, float half_extent);
/* A square in the XZ plane facing +y, one chart over the whole tile. */
bool mesh_create_plane(struct mesh *out, float half_extent);
void mesh_finish(struct mesh *m);
/* Sets box_min and box_max from the vertices (zero for an empty mesh). */
void mesh_compute_box(struct mesh *m);

#endif
