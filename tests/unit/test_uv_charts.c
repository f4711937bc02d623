/* The converter's uv1 charts (daemon/assets/uv_charts.c): a flat grid is
 * one chart with almost no waste; a cube is six charts of four vertices; a
 * UV sphere, a bumpy grid and a mirrored pair get a unique parametrisation
 * (no two triangles share a texel of a 512-texel raster, sampled inside
 * each triangle away from its edges), every uv in [0, 1], every index in
 * range, each new vertex copying an input vertex, and texel density the
 * same within cos 30 degrees across the mesh; the skyline packing keeps the
 * waste of the sphere, the bumpy grid and the mirrored halves at 0.45 to
 * 0.54 (the shelves left 0.47 to 0.63). */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/assets/uv_charts.h"
#include "tests/unit/check.h"

enum { RASTER = 512 };

struct mesh {
    float *pos;
    uint32_t *tri;
    uint32_t nv, nt;
};

static void grid(struct mesh *m, int n, double amp)
{
    m->nv = (uint32_t)((n + 1) * (n + 1));
    m->nt = (uint32_t)(2 * n * n);
    m->pos = malloc(m->nv * 3 * sizeof(float));
    m->tri = malloc(m->nt * 3 * sizeof(uint32_t));
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float *p = m->pos + 3 * (j * (n + 1) + i);
            p[0] = (float)(2.0 * i / n - 1);
            p[1] = (float)(2.0 * j / n - 1);
            p[2] = (float)(amp * sin(i * 0.7 + j * 0.3));
        }
    uint32_t k = 0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), w = (uint32_t)n + 1;
            uint32_t q[6] = {a, a + 1, a + w + 1, a, a + w + 1, a + w};
            memcpy(m->tri + k, q, sizeof(q));
            k += 6;
        }
}

static void sphere(struct mesh *m, int seg, int rings)
{
    m->nv = (uint32_t)((seg + 1) * (rings + 1));
    m->nt = (uint32_t)(2 * seg * rings);
    m->pos = malloc(m->nv * 3 * sizeof(float));
    m->tri = malloc(m->nt * 3 * sizeof(uint32_t));
    for (int r = 0; r <= rings; r++)
        for (int s = 0; s <= seg; s++) {
            double th = M_PI * r / rings, ph = 2 * M_PI * s / seg;
            float *p = m->pos + 3 * (r * (seg + 1) + s);
            p[0] = (float)(sin(th) * cos(ph));
            p[1] = (float)cos(th);
            p[2] = (float)(sin(th) * sin(ph));
        }
    uint32_t k = 0;
    for (int r = 0; r < rings; r++)
        for (int s = 0; s < seg; s++) {
            uint32_t a = (uint32_t)(r * (seg + 1) + s), w = (uint32_t)seg + 1;
            uint32_t q[6] = {a, a + w, a + w + 1, a, a + w + 1, a + 1};
            memcpy(m->tri + k, q, sizeof(q));
            k += 6;
        }
}

static void cube(struct mesh *m)
{
    static const int faces[6][3][3] = {
        {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}};
    m->nv = 24;
    m->nt = 12;
    m->pos = malloc(24 * 3 * sizeof(float));
    m->tri = malloc(36 * sizeof(uint32_t));
    static const int corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int f = 0; f < 6; f++) {
        for (int c = 0; c < 4; c++)
            for (int k = 0; k < 3; k++)
                m->pos[3 * (4 * f + c) + k] = (float)(faces[f][0][k] + corner[c][0] * faces[f][1][k] +
                                                      corner[c][1] * faces[f][2][k]);
        uint32_t b = (uint32_t)(4 * f);
        uint32_t q[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(m->tri + 6 * f, q, sizeof(q));
    }
}

static double area3(const float *a, const float *b, const float *c)
{
    double e1[3], e2[3], n[3];
    for (int i = 0; i < 3; i++) {
        e1[i] = (double)b[i] - a[i];
        e2[i] = (double)c[i] - a[i];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
}

/* Checks one layout; returns how many raster texels two triangles share. */
static long check_layout(const char *name, const struct mesh *m, const struct uv_charts *c)
{
    bool in_range = true, sources = true;
    for (uint32_t v = 0; v < c->vertex_count; v++) {
        in_range &= c->uv[v][0] >= 0 && c->uv[v][0] <= 1 && c->uv[v][1] >= 0 && c->uv[v][1] <= 1;
        sources &= c->source[v] < m->nv;
    }
    CHECK(in_range);
    CHECK(sources);
    bool same_corner = true, idx_ok = true;
    for (uint32_t i = 0; i < m->nt * 3; i++) {
        idx_ok &= c->indices[i] < c->vertex_count;
        if (c->indices[i] < c->vertex_count)
            same_corner &= c->source[c->indices[i]] == m->tri[i];
    }
    CHECK(idx_ok);
    CHECK(same_corner);
    /* Texel density: uv area over world area, the same within cos 30. */
    double lo = INFINITY, hi = 0;
    for (uint32_t t = 0; t < m->nt; t++) {
        const float *a = c->uv[c->indices[3 * t]], *b = c->uv[c->indices[3 * t + 1]],
                    *d = c->uv[c->indices[3 * t + 2]];
        double uva = fabs((double)(b[0] - a[0]) * (d[1] - a[1]) - (double)(d[0] - a[0]) * (b[1] - a[1])) / 2;
        double wa = area3(m->pos + 3 * m->tri[3 * t], m->pos + 3 * m->tri[3 * t + 1],
                          m->pos + 3 * m->tri[3 * t + 2]);
        if (wa > 1e-9) {
            lo = fmin(lo, uva / wa);
            hi = fmax(hi, uva / wa);
        }
    }
    CHECK(lo > 0 && lo >= hi * 0.866 - 1e-6);
    /* Overlap: each triangle marks the texel centres strictly inside it
     * (by a margin of a quarter texel); a texel marked twice is shared. */
    unsigned char *raster = calloc(RASTER * RASTER, 1);
    long shared = 0;
    for (uint32_t t = 0; t < m->nt; t++) {
        const float *p[3] = {c->uv[c->indices[3 * t]], c->uv[c->indices[3 * t + 1]],
                             c->uv[c->indices[3 * t + 2]]};
        double x0 = fmin(p[0][0], fmin(p[1][0], p[2][0])) * RASTER, x1 = fmax(p[0][0], fmax(p[1][0], p[2][0])) * RASTER;
        double y0 = fmin(p[0][1], fmin(p[1][1], p[2][1])) * RASTER, y1 = fmax(p[0][1], fmax(p[1][1], p[2][1])) * RASTER;
        double area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        if (fabs(area) < 1e-12)
            continue;
        for (int y = (int)floor(y0); y <= (int)ceil(y1) && y < RASTER; y++)
            for (int x = (int)floor(x0); x <= (int)ceil(x1) && x < RASTER; x++) {
                if (x < 0 || y < 0)
                    continue;
                double px = (x + 0.5) / RASTER, py = (y + 0.5) / RASTER;
                bool inside = true;
                for (int k = 0; k < 3; k++) {
                    const float *a = p[k], *b = p[(k + 1) % 3];
                    double ex = b[0] - a[0], ey = b[1] - a[1];
                    double d = (ex * (py - a[1]) - ey * (px - a[0])) * (area > 0 ? 1 : -1);
                    double len = sqrt(ex * ex + ey * ey);
                    inside &= d > 0.25 / RASTER * len;
                }
                if (inside) {
                    shared += raster[y * RASTER + x] > 0;
                    raster[y * RASTER + x] = 1;
                }
            }
    }
    free(raster);
    printf("%s: %u charts, %u vertices, waste %.3f, density %.3f..%.3f, %ld shared texels\n", name,
           c->chart_count, c->vertex_count, c->waste, lo, hi, shared);
    return shared;
}

static void run(const char *name, struct mesh *m, uint32_t want_charts, uint32_t want_vertices,
                double max_waste)
{
    struct uv_charts c;
    char err[128];
    bool ok = uv_charts_build(m->pos, m->nv, m->tri, m->nt, 1u << 24, &c, err, sizeof(err));
    CHECK(ok);
    if (ok) {
        CHECK(check_layout(name, m, &c) == 0);
        if (want_charts)
            CHECK(c.chart_count == want_charts);
        if (want_vertices)
            CHECK(c.vertex_count == want_vertices);
        CHECK(c.waste > 0 && c.waste <= max_waste);
        uv_charts_free(&c);
    }
    free(m->pos);
    free(m->tri);
}

int main(void)
{
    struct mesh m;
    grid(&m, 32, 0);
    run("flat grid", &m, 1, 33 * 33, 0.02);
    cube(&m);
    run("cube", &m, 6, 24, 0.40);
    sphere(&m, 32, 16);
    run("sphere", &m, 0, 0, 0.50);
    grid(&m, 64, 0.05);
    run("bumpy grid", &m, 0, 0, 0.50);
    /* Mirrored halves (a file would often give both the same uv): the
     * bumps of x < 0 mirror those of x > 0; each half gets its own texels. */
    grid(&m, 32, 0.05);
    for (uint32_t v = 0; v < m.nv; v++)
        m.pos[3 * v + 2] = (float)(0.05 * sin(fabs(m.pos[3 * v]) * 11.0 + m.pos[3 * v + 1] * 5.0));
    run("mirrored halves", &m, 0, 0, 0.60);
    /* Degenerate triangles (a repeated corner) and a lone triangle. */
    grid(&m, 4, 0);
    m.tri[0] = m.tri[1];
    run("degenerate", &m, 0, 0, 1.0);
    /* The vertex limit. */
    grid(&m, 8, 0);
    struct uv_charts c;
    char err[128] = "";
    CHECK(!uv_charts_build(m.pos, m.nv, m.tri, m.nt, 10, &c, err, sizeof(err)) && strstr(err, "vertices"));
    CHECK(c.source == NULL && c.uv == NULL && c.indices == NULL);
    free(m.pos);
    free(m.tri);
    return check_finish("test_uv_charts");
}
