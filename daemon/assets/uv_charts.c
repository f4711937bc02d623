/* uv1 charts for meshes without TEXCOORD_1 (uv_charts.h). */
#include "daemon/assets/uv_charts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 30 degrees from the chart's first triangle: every triangle of a chart
 * faces its plane (no fold), and its area shrinks by at most cos 30 = 0.87
 * in the projection, so texel density varies by at most that much. */
#define COS_LIMIT 0.8660254
#define NONE UINT32_MAX

struct edge {
    uint32_t a, b; /* a < b */
    uint32_t tri;
    uint8_t slot;     /* which edge of the triangle */
    uint8_t forward;  /* the triangle runs a -> b */
};

static int edge_cmp(const void *x, const void *y)
{
    const struct edge *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    return p->tri < q->tri ? -1 : p->tri > q->tri;
}

struct chart {
    uint32_t first_vertex, vertex_end;
    double min[2], max[2];
    bool rotated; /* taller than wide: placed turned a quarter */
    double w, h;  /* as placed */
    double x, y;  /* placement, in world units of the atlas */
};

static void sub3(const float *a, const float *b, double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = (double)a[i] - (double)b[i];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Skyline packing of the charts (in the given order) into a square of side
 * s, each padded by gutter: each chart goes where its top ends lowest (then
 * leftmost) over the skyline of those placed before, either way round;
 * places them (and turns them) when place is set. The placements depend on
 * the sizes alone, so a trial and the placing pass agree. sky and tmp
 * hold 2 n + 2 segments each. */
struct segment {
    double x, y, w;
};

static bool skyline_fits(struct chart *ch, const uint32_t *order, uint32_t n, double s,
                         double gutter, bool place, struct segment *sky, struct segment *tmp)
{
    uint32_t ns = 1;
    sky[0] = (struct segment){0, 0, s};
    for (uint32_t k = 0; k < n; k++) {
        struct chart *c = &ch[order[k]];
        double best_top = INFINITY, best_x = 0, best_y = 0;
        int best_turn = 0;
        for (int turn = 0; turn < 2; turn++) {
            double pw = (turn ? c->h : c->w) + gutter, ph = (turn ? c->w : c->h) + gutter;
            for (uint32_t i = 0; i < ns; i++) {
                double x = sky[i].x;
                if (x + pw > s + 1e-12 * s)
                    break;
                double y = 0;
                for (uint32_t j = i; j < ns && sky[j].x < x + pw - 1e-12 * s; j++)
                    y = fmax(y, sky[j].y);
                if (y + ph <= s && (y + ph < best_top || (y + ph == best_top && x < best_x))) {
                    best_top = y + ph;
                    best_x = x;
                    best_y = y;
                    best_turn = turn;
                }
            }
        }
        if (best_top == INFINITY)
            return false;
        double pw = (best_turn ? c->h : c->w) + gutter;
        if (place) {
            if (best_turn) {
                double w = c->w;
                c->w = c->h;
                c->h = w;
                c->rotated = !c->rotated;
            }
            c->x = best_x + gutter / 2;
            c->y = best_y + gutter / 2;
        }
        /* The new segment replaces [best_x, best_x + pw) of the skyline. */
        struct segment put = {best_x, best_top, pw};
        struct segment keep[2];
        uint32_t first = ns, last = 0;
        for (uint32_t i = 0; i < ns; i++) {
            double a = sky[i].x, b = sky[i].x + sky[i].w;
            if (b <= put.x || a >= put.x + put.w)
                continue;
            if (first == ns)
                first = i;
            last = i;
        }
        /* Left remainder of the first overlapped segment, right remainder of the last. */
        uint32_t nk = 0;
        if (sky[first].x < put.x)
            keep[nk++] = (struct segment){sky[first].x, sky[first].y, put.x - sky[first].x};
        double end = sky[last].x + sky[last].w;
        struct segment right = {put.x + put.w, sky[last].y, end - (put.x + put.w)};
        /* Rebuild: before first, left part, put, right part, after last. */
        uint32_t m = 0;
        for (uint32_t i = last + 1; i < ns; i++)
            tmp[m++] = sky[i];
        uint32_t w = first;
        for (uint32_t i = 0; i < nk; i++)
            sky[w++] = keep[i];
        sky[w++] = put;
        if (right.w > 1e-12 * s)
            sky[w++] = right;
        for (uint32_t i = 0; i < m; i++)
            sky[w++] = tmp[i];
        ns = w;
        /* Merge neighbours of equal height. */
        uint32_t r = 0;
        for (uint32_t i = 0; i < ns; i++) {
            if (r && sky[r - 1].y == sky[i].y)
                sky[r - 1].w += sky[i].w;
            else
                sky[r++] = sky[i];
        }
        ns = r;
    }
    return true;
}

static const struct chart *sort_base;
static int height_desc(const void *x, const void *y)
{
    double a = sort_base[*(const uint32_t *)x].h, b = sort_base[*(const uint32_t *)y].h;
    return a > b ? -1 : a < b ? 1 : 0;
}

void uv_charts_free(struct uv_charts *c)
{
    free(c->source);
    free(c->uv);
    free(c->indices);
    memset(c, 0, sizeof(*c));
}

bool uv_charts_build(const float *pos, uint32_t nv, const uint32_t *tri, uint32_t ntri,
                     uint64_t max_vertices, struct uv_charts *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    bool ok = false;
    size_t ne = (size_t)ntri * 3;
    double (*normal)[3] = malloc((size_t)ntri * sizeof(*normal));
    struct edge *edges = malloc(ne * sizeof(*edges));
    uint32_t *nb = malloc(ne * sizeof(uint32_t)); /* neighbour across each edge */
    uint32_t *chart_of = malloc((size_t)ntri * sizeof(uint32_t));
    uint32_t *queue = malloc((size_t)ntri * sizeof(uint32_t));
    uint32_t *stamp = malloc((size_t)nv * sizeof(uint32_t));
    uint32_t *newidx = malloc((size_t)nv * sizeof(uint32_t));
    double (*proj)[2] = malloc(ne * sizeof(*proj));
    struct chart *ch = NULL;
    uint32_t *order = NULL;
    struct segment *sky = NULL, *sky_tmp = NULL;
    out->source = malloc(ne * sizeof(uint32_t));
    out->indices = malloc(ne * sizeof(uint32_t));
    if (!normal || !edges || !nb || !chart_of || !queue || !stamp || !newidx || !proj ||
        !out->source || !out->indices) {
        snprintf(err, errlen, "out of memory for uv1 charts");
        goto done;
    }
    double maxdim = 0;
    for (uint32_t t = 0; t < ntri; t++) {
        const float *p0 = pos + 3 * (size_t)tri[3 * t], *p1 = pos + 3 * (size_t)tri[3 * t + 1],
                    *p2 = pos + 3 * (size_t)tri[3 * t + 2];
        double e1[3], e2[3];
        sub3(p1, p0, e1);
        sub3(p2, p0, e2);
        cross3(e1, e2, normal[t]);
        double len = sqrt(dot3(normal[t], normal[t]));
        for (int i = 0; i < 3; i++)
            normal[t][i] = len > 0 ? normal[t][i] / len : 0;
        maxdim = fmax(maxdim, fmax(sqrt(dot3(e1, e1)), sqrt(dot3(e2, e2))));
        for (int k = 0; k < 3; k++) {
            uint32_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
            struct edge *e = &edges[3 * (size_t)t + k];
            e->a = a < b ? a : b;
            e->b = a < b ? b : a;
            e->tri = t;
            e->slot = (uint8_t)k;
            e->forward = a < b;
            nb[3 * (size_t)t + k] = NONE;
        }
    }
    /* Neighbours: an edge two triangles share, run in opposite directions
     * (consistently oriented); an edge of three or more is no seam to
     * grow across. */
    qsort(edges, ne, sizeof(*edges), edge_cmp);
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && edges[j].a == edges[i].a && edges[j].b == edges[i].b)
            j++;
        if (j - i == 2 && edges[i].forward != edges[i + 1].forward && edges[i].tri != edges[i + 1].tri) {
            nb[3 * (size_t)edges[i].tri + edges[i].slot] = edges[i + 1].tri;
            nb[3 * (size_t)edges[i + 1].tri + edges[i + 1].slot] = edges[i].tri;
        }
        i = j;
    }
    /* Charts by region growing from each unassigned triangle; new vertices
     * made chart by chart, so that each chart's are contiguous. */
    for (uint32_t t = 0; t < ntri; t++)
        chart_of[t] = NONE;
    for (uint32_t v = 0; v < nv; v++)
        stamp[v] = NONE;
    size_t chart_cap = 64;
    ch = malloc(chart_cap * sizeof(*ch));
    if (!ch) {
        snprintf(err, errlen, "out of memory for uv1 charts");
        goto done;
    }
    uint32_t nc = 0, nvout = 0;
    for (uint32_t seed = 0; seed < ntri; seed++) {
        if (chart_of[seed] != NONE)
            continue;
        if (nc == chart_cap) {
            chart_cap *= 2;
            struct chart *grown = realloc(ch, chart_cap * sizeof(*ch));
            if (!grown) {
                snprintf(err, errlen, "out of memory for uv1 charts");
                goto done;
            }
            ch = grown;
        }
        uint32_t id = nc++;
        const double *ns = normal[seed];
        bool flat = dot3(ns, ns) > 0.5;
        /* The chart's plane: u along the seed's longest edge. */
        double u[3] = {1, 0, 0}, w[3] = {0, 1, 0};
        if (flat) {
            double best = -1;
            for (int k = 0; k < 3; k++) {
                double e[3];
                sub3(pos + 3 * (size_t)tri[3 * seed + (k + 1) % 3], pos + 3 * (size_t)tri[3 * seed + k], e);
                double l = dot3(e, e);
                if (l > best) {
                    best = l;
                    for (int i = 0; i < 3; i++)
                        u[i] = e[i] / sqrt(l);
                }
            }
            cross3(ns, u, w);
        }
        struct chart *c = &ch[id];
        c->first_vertex = nvout;
        c->x = c->y = 0; /* placed by the packing; 0 if it cannot place it (non-finite sizes) */
        c->min[0] = c->min[1] = INFINITY;
        c->max[0] = c->max[1] = -INFINITY;
        uint32_t head = 0, tail = 0;
        queue[tail++] = seed;
        chart_of[seed] = id;
        while (head < tail) {
            uint32_t t = queue[head++];
            for (int k = 0; k < 3; k++) {
                uint32_t v = tri[3 * t + k];
                uint32_t dst;
                if (stamp[v] == id) {
                    dst = newidx[v];
                } else {
                    if (nvout >= max_vertices) {
                        snprintf(err, errlen, "uv1 charts need more than %llu vertices",
                                 (unsigned long long)max_vertices);
                        goto done;
                    }
                    dst = nvout++;
                    stamp[v] = id;
                    newidx[v] = dst;
                    out->source[dst] = v;
                    const float *p = pos + 3 * (size_t)v;
                    double pd[3] = {p[0], p[1], p[2]};
                    proj[dst][0] = dot3(pd, u);
                    proj[dst][1] = dot3(pd, w);
                }
                out->indices[3 * (size_t)t + k] = dst;
            }
            if (!flat)
                continue; /* a degenerate triangle is a chart of its own */
            for (int k = 0; k < 3; k++) {
                uint32_t n = nb[3 * (size_t)t + k];
                if (n != NONE && chart_of[n] == NONE && dot3(normal[n], normal[n]) > 0.5 &&
                    dot3(normal[n], ns) > COS_LIMIT) {
                    chart_of[n] = id;
                    queue[tail++] = n;
                }
            }
        }
        c->vertex_end = nvout;
        /* Turn the chart to its smallest bounding box among 32 angles over
         * the quarter turn (a bounding box repeats every quarter turn): an
         * axis-aligned square face would otherwise lie as a diamond, half
         * its box empty. */
        double best_area = INFINITY, best_a = 0;
        for (int k = 0; k < 32; k++) {
            double a = k * (3.14159265358979323846 / 2) / 32, ca = cos(a), sa = sin(a);
            double mn[2] = {INFINITY, INFINITY}, mx[2] = {-INFINITY, -INFINITY};
            for (uint32_t v = c->first_vertex; v < c->vertex_end; v++) {
                double x = proj[v][0] * ca + proj[v][1] * sa, y = -proj[v][0] * sa + proj[v][1] * ca;
                mn[0] = fmin(mn[0], x);
                mx[0] = fmax(mx[0], x);
                mn[1] = fmin(mn[1], y);
                mx[1] = fmax(mx[1], y);
            }
            double box = (mx[0] - mn[0]) * (mx[1] - mn[1]);
            if (box < best_area) {
                best_area = box;
                best_a = a;
            }
        }
        double ca = cos(best_a), sa = sin(best_a);
        for (uint32_t v = c->first_vertex; v < c->vertex_end; v++) {
            double x = proj[v][0] * ca + proj[v][1] * sa, y = -proj[v][0] * sa + proj[v][1] * ca;
            proj[v][0] = x;
            proj[v][1] = y;
            for (int i = 0; i < 2; i++) {
                c->min[i] = fmin(c->min[i], proj[v][i]);
                c->max[i] = fmax(c->max[i], proj[v][i]);
            }
        }
    }
    out->vertex_count = nvout;
    out->chart_count = nc;
    /* Sizes, turned so that each is at least as wide as tall; degenerate
     * ones get a sliver so the packing has something to place. */
    double floor_size = maxdim > 0 ? maxdim * 1e-6 : 1e-6, area = 0;
    for (uint32_t i = 0; i < nc; i++) {
        struct chart *c = &ch[i];
        double w = fmax(c->max[0] - c->min[0], floor_size), h = fmax(c->max[1] - c->min[1], floor_size);
        c->rotated = h > w;
        c->w = c->rotated ? h : w;
        c->h = c->rotated ? w : h;
        area += c->w * c->h;
    }
    order = malloc((size_t)nc * sizeof(uint32_t));
    if (!order) {
        snprintf(err, errlen, "out of memory for uv1 charts");
        goto done;
    }
    for (uint32_t i = 0; i < nc; i++)
        order[i] = i;
    sort_base = ch; /* one conversion per process: qsort has no context argument in C11 */
    qsort(order, nc, sizeof(uint32_t), height_desc);
    const double g = (double)UV_CHARTS_GUTTER_TEXELS / UV_CHARTS_ATLAS_TEXELS;
    sky = malloc((2 * (size_t)nc + 2) * sizeof(*sky));
    sky_tmp = malloc((2 * (size_t)nc + 2) * sizeof(*sky_tmp));
    if (!sky || !sky_tmp) {
        snprintf(err, errlen, "out of memory for uv1 charts");
        goto done;
    }
    double lo = sqrt(area), hi = lo;
    for (int i = 0; i < 200 && !skyline_fits(ch, order, nc, hi, g * hi, false, sky, sky_tmp); i++)
        hi *= 1.5;
    for (int i = 0; i < 40; i++) {
        double mid = (lo + hi) / 2;
        if (skyline_fits(ch, order, nc, mid, g * mid, false, sky, sky_tmp))
            hi = mid;
        else
            lo = mid;
    }
    skyline_fits(ch, order, nc, hi, g * hi, true, sky, sky_tmp);

    out->uv = malloc((size_t)(nvout ? nvout : 1) * sizeof(*out->uv));
    if (!out->uv) {
        snprintf(err, errlen, "out of memory for uv1 charts");
        goto done;
    }
    for (uint32_t i = 0; i < nc; i++) {
        const struct chart *c = &ch[i];
        for (uint32_t v = c->first_vertex; v < c->vertex_end; v++) {
            double px = proj[v][0] - c->min[0], py = proj[v][1] - c->min[1];
            double x = c->rotated ? py : px, y = c->rotated ? px : py;
            double uvx = (c->x + x) / hi, uvy = (c->y + y) / hi;
            out->uv[v][0] = (float)(uvx < 0 ? 0 : uvx > 1 ? 1 : uvx);
            out->uv[v][1] = (float)(uvy < 0 ? 0 : uvy > 1 ? 1 : uvy);
        }
    }
    double covered = 0;
    for (uint32_t t = 0; t < ntri; t++) {
        const float *a = out->uv[out->indices[3 * (size_t)t]], *b = out->uv[out->indices[3 * (size_t)t + 1]],
                    *cc = out->uv[out->indices[3 * (size_t)t + 2]];
        covered += fabs((double)(b[0] - a[0]) * (cc[1] - a[1]) - (double)(cc[0] - a[0]) * (b[1] - a[1])) / 2;
    }
    out->waste = covered >= 1 ? 0 : 1 - covered;
    ok = true;
done:
    free(normal);
    free(edges);
    free(nb);
    free(chart_of);
    free(queue);
    free(stamp);
    free(newidx);
    free(proj);
    free(ch);
    free(order);
    free(sky);
    free(sky_tmp);
    if (!ok)
        uv_charts_free(out);
    return ok;
}
