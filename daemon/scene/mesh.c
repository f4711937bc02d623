#include "daemon/scene/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

static bool mesh_alloc(struct mesh *m, uint32_t vertices, uint32_t indices)
{
    memset(m, 0, sizeof(*m));
    m->vertices = calloc(vertices, sizeof(*m->vertices));
    m->indices = calloc(indices, sizeof(*m->indices));
    if (!m->vertices || !m->indices) {
        mesh_finish(m);
        return false;
    }
    m->vertex_count = vertices;
    m->index_count = indices;
    return true;
}

void mesh_finish(struct mesh *m)
{
    if (!m)
        return;
    free(m->vertices);
    free(m->indices);
    memset(m, 0, sizeof(*m));
}

void mesh_compute_box(struct mesh *m)
{
    for (int k = 0; k < 3; k++) {
        m->box_min[k] = m->vertex_count ? INFINITY : 0.0f;
        m->box_max[k] = m->vertex_count ? -INFINITY : 0.0f;
    }
    for (uint32_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            m->box_min[k] = fminf(m->box_min[k], m->vertices[i].pos[k]);
            m->box_max[k] = fmaxf(m->box_max[k], m->vertices[i].pos[k]);
        }
}

bool mesh_create_sphere(struct mesh *out, float radius, int segments)
{
    /* Latitude-longitude sphere: one chart covering the whole tile. The pole
     * rows are quads whose upper edge collapses to the pole in 3D, so in UV
     * space the chart is still fully covered (no uncovered wedges). */
    int rings = segments / 2;
    uint32_t cols = (uint32_t)segments + 1, rows = (uint32_t)rings + 1;
    if (!mesh_alloc(out, cols * rows, (uint32_t)segments * (uint32_t)rings * 6))
        return false;
    for (uint32_t i = 0; i < rows; i++) {
        double v = (double)i / rings, theta = v * PI;
        for (uint32_t j = 0; j < cols; j++) {
            double u = (double)j / segments, phi = u * 2.0 * PI;
            struct mesh_vertex *vx = &out->vertices[i * cols + j];
            double n[3] = {sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi)};
            for (int k = 0; k < 3; k++) {
                vx->normal[k] = (float)n[k];
                vx->pos[k] = (float)(n[k] * radius);
            }
            vx->uv[0] = (float)u;
            vx->uv[1] = (float)v;
            vx->chart[0] = 0.0f;
            vx->chart[1] = 0.0f;
            vx->chart[2] = 1.0f;
            vx->chart[3] = 1.0f;
        }
    }
    uint32_t *idx = out->indices;
    for (uint32_t i = 0; i < (uint32_t)rings; i++) {
        for (uint32_t j = 0; j < (uint32_t)segments; j++) {
            uint32_t a = i * cols + j, b = (i + 1) * cols + j;
            uint32_t c = (i + 1) * cols + j + 1, d = i * cols + j + 1;
            /* Counter-clockwise seen from outside. */
            *idx++ = a, *idx++ = c, *idx++ = b;
            *idx++ = a, *idx++ = d, *idx++ = c;
        }
    }
    out->bound_radius = radius;
    out->uv_per_unit = (float)(1.0 / (2.0 * PI * radius));
    return true;
}

bool mesh_create_cube(struct mesh *out, float h)
{
    /* Six charts in a 3x2 grid, one per face: hard edges keep their own normals. */
    static const float faces[6][3][3] = {
        /* normal, s axis, t axis with s x t = normal */
        {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},   {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
    };
    static const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    if (!mesh_alloc(out, 24, 36))
        return false;
    for (int f = 0; f < 6; f++) {
        float chart[4] = {(float)(f % 3) / 3.0f, (float)(f / 3) / 2.0f,
                          (float)(f % 3 + 1) / 3.0f, (float)(f / 3 + 1) / 2.0f};
        for (int c = 0; c < 4; c++) {
            struct mesh_vertex *vx = &out->vertices[f * 4 + c];
            for (int k = 0; k < 3; k++) {
                vx->normal[k] = faces[f][0][k];
                vx->pos[k] = h * (faces[f][0][k] + corners[c][0] * faces[f][1][k] +
                                  corners[c][1] * faces[f][2][k]);
            }
            vx->uv[0] = chart[0] + (chart[2] - chart[0]) * (corners[c][0] + 1) * 0.5f;
            vx->uv[1] = chart[1] + (chart[3] - chart[1]) * (corners[c][1] + 1) * 0.5f;
            memcpy(vx->chart, chart, sizeof(chart));
        }
        uint32_t base = (uint32_t)f * 4, *idx = &out->indices[f * 6];
        idx[0] = base, idx[1] = base + 1, idx[2] = base + 2;
        idx[3] = base, idx[4] = base + 2, idx[5] = base + 3;
    }
    out->bound_radius = h * sqrtf(3.0f);
    out->uv_per_unit = (1.0f / 3.0f) / (2.0f * h);
    return true;
}

bool mesh_create_plane(struct mesh *out, float h)
{
    /* Two triangles, counter-clockwise seen from above; u runs with x and v
     * with z over one chart covering the tile. Lighting is per fragment (and
     * per texel in OSL), so more vertices would add nothing. */
    static const float corners[4][2] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
    static const uint32_t indices[6] = {0, 1, 2, 0, 2, 3};
    if (!mesh_alloc(out, 4, 6))
        return false;
    for (int c = 0; c < 4; c++) {
        struct mesh_vertex *vx = &out->vertices[c];
        vx->pos[0] = h * corners[c][0];
        vx->pos[2] = h * corners[c][1];
        vx->normal[1] = 1.0f;
        vx->uv[0] = (corners[c][0] + 1) * 0.5f;
        vx->uv[1] = (corners[c][1] + 1) * 0.5f;
        vx->chart[2] = 1.0f;
        vx->chart[3] = 1.0f;
    }
    memcpy(out->indices, indices, sizeof(indices));
    out->bound_radius = h * sqrtf(2.0f);
    out->uv_per_unit = 1.0f / (2.0f * h);
    return true;
}
