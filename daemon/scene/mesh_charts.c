/* uv1 charts of an asset mesh (mesh_charts.h). */
#include "daemon/scene/mesh_charts.h"

#include <stdlib.h>
#include <string.h>

static uint32_t find(uint32_t *parent, uint32_t v)
{
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

struct rect_key {
    float lo; /* the rectangle's u0, for the sweep */
    uint32_t chart;
};

static int by_lo(const void *a, const void *b)
{
    const struct rect_key *x = a, *y = b;
    return x->lo < y->lo ? -1 : x->lo > y->lo ? 1 : (x->chart > y->chart) - (x->chart < y->chart);
}

bool mesh_chart_rects(struct mesh *m, struct mesh_chart_stats *stats)
{
    uint32_t n = m->vertex_count;
    uint32_t *parent = malloc((size_t)(n ? n : 1) * sizeof(uint32_t));
    uint32_t *chart = malloc((size_t)(n ? n : 1) * sizeof(uint32_t));
    float(*rect)[4] = NULL;
    unsigned char *overlap = NULL;
    struct rect_key *keys = NULL;
    bool ok = false;
    if (!parent || !chart)
        goto done;
    for (uint32_t v = 0; v < n; v++)
        parent[v] = v;
    for (uint32_t t = 0; t + 2 < m->index_count; t += 3) {
        uint32_t a = find(parent, m->indices[t]);
        for (int k = 1; k < 3; k++) {
            uint32_t b = find(parent, m->indices[t + k]);
            if (a != b)
                parent[b] = a;
        }
    }
    /* Charts of the vertices the triangles use (a vertex no triangle uses
     * is no chart: it keeps the whole square). */
    for (uint32_t v = 0; v < n; v++)
        chart[v] = UINT32_MAX;
    for (uint32_t t = 0; t + 2 < m->index_count; t += 3)
        for (int k = 0; k < 3; k++)
            chart[find(parent, m->indices[t + k])] = 0;
    uint32_t charts = 0;
    for (uint32_t v = 0; v < n; v++)
        if (find(parent, v) == v && chart[v] == 0)
            chart[v] = charts++ | 0x80000000u;
    /* Each vertex takes its root's chart: the others first, then the roots
     * themselves (which the first pass reads). */
    for (int roots = 0; roots < 2; roots++)
        for (uint32_t v = 0; v < n; v++) {
            uint32_t root = find(parent, v);
            if ((root == v) != (roots == 1))
                continue;
            uint32_t r = chart[root];
            chart[v] = r == UINT32_MAX || !(r & 0x80000000u) ? UINT32_MAX : r & 0x7fffffffu;
        }
    rect = malloc((size_t)(charts ? charts : 1) * sizeof(*rect));
    overlap = calloc(charts ? charts : 1, 1);
    keys = malloc((size_t)(charts ? charts : 1) * sizeof(*keys));
    if (!rect || !overlap || !keys)
        goto done;
    for (uint32_t c = 0; c < charts; c++)
        rect[c][0] = rect[c][1] = 1.0f, rect[c][2] = rect[c][3] = 0.0f;
    for (uint32_t v = 0; v < n; v++) {
        if (chart[v] == UINT32_MAX)
            continue;
        float *r = rect[chart[v]];
        const float *uv = m->vertices[v].uv;
        for (int k = 0; k < 2; k++) {
            r[k] = uv[k] < r[k] ? uv[k] : r[k];
            r[k + 2] = uv[k] > r[k + 2] ? uv[k] : r[k + 2];
        }
    }
    /* Overlaps by a sweep along u: each rectangle against those that begin
     * before it ends. Touching edges are no overlap (a texel centre lies in
     * one of two rectangles that only touch). */
    for (uint32_t c = 0; c < charts; c++)
        keys[c].lo = rect[c][0], keys[c].chart = c;
    qsort(keys, charts, sizeof(*keys), by_lo);
    for (uint32_t i = 0; i < charts; i++) {
        const float *a = rect[keys[i].chart];
        for (uint32_t j = i + 1; j < charts && keys[j].lo < a[2]; j++) {
            const float *b = rect[keys[j].chart];
            if (b[1] < a[3] && a[1] < b[3])
                overlap[keys[i].chart] = overlap[keys[j].chart] = 1;
        }
    }
    uint32_t overlapping = 0;
    for (uint32_t c = 0; c < charts; c++)
        overlapping += overlap[c];
    for (uint32_t v = 0; v < n; v++) {
        static const float whole[4] = {0.0f, 0.0f, 1.0f, 1.0f};
        memcpy(m->vertices[v].chart,
               chart[v] == UINT32_MAX || overlap[chart[v]] ? whole : rect[chart[v]], sizeof(whole));
    }
    if (stats) {
        stats->charts = charts;
        stats->overlapping = overlapping;
    }
    ok = true;
done:
    free(parent);
    free(chart);
    free(rect);
    free(overlap);
    free(keys);
    return ok;
}
