/* The teapot mesh (daemon/scene/teapot.c): the patches meet where the data
 * says they do, every edge after welding is shared by at most two
 * consistently oriented triangles and the edges used once are exactly the
 * data's known open boundaries (teapot.h lists them), normals point
 * outwards (a point just outside the surface has winding number 0, just
 * inside 1), charts cover their grid cells, the tessellation error falls
 * with the segment count and "auto" picks from it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/teapot.h"
#include "tests/unit/check.h"

static const double PI = 3.14159265358979323846;

struct welded {
    uint32_t *id;   /* vertex -> welded vertex */
    int count;
};

static const struct mesh *sort_mesh;
static int by_position(const void *a, const void *b)
{
    const float *p = sort_mesh->vertices[*(const uint32_t *)a].pos;
    const float *q = sort_mesh->vertices[*(const uint32_t *)b].pos;
    for (int k = 0; k < 3; k++) {
        long x = lround(p[k] * 1e4), y = lround(q[k] * 1e4);
        if (x != y)
            return x < y ? -1 : 1;
    }
    return 0;
}

/* Vertices closer than 1e-4 (rounded to a 1e-4 grid) become one. */
static void weld(const struct mesh *m, struct welded *w)
{
    uint32_t *order = malloc(m->vertex_count * sizeof(uint32_t));
    w->id = malloc(m->vertex_count * sizeof(uint32_t));
    for (uint32_t i = 0; i < m->vertex_count; i++)
        order[i] = i;
    sort_mesh = m;
    qsort(order, m->vertex_count, sizeof(uint32_t), by_position);
    w->count = 0;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        if (i && by_position(&order[i - 1], &order[i]) != 0)
            w->count++;
        w->id[order[i]] = (uint32_t)w->count;
    }
    w->count++;
    free(order);
}

struct edge {
    uint32_t lo, hi;
    int forward; /* +1 when the triangle runs lo -> hi */
    int tri;
};

static int by_edge(const void *a, const void *b)
{
    const struct edge *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi)
        return x->hi < y->hi ? -1 : 1;
    return 0;
}

/* Solid angle of triangle (a, b, c) seen from q (Van Oosterom and
 * Strackee), positive when the triangle is counter-clockwise seen from q's
 * side opposite its normal... i.e. from inside. */
static double solid_angle(const float *a, const float *b, const float *c, const double q[3])
{
    double A[3], B[3], C[3];
    for (int k = 0; k < 3; k++)
        A[k] = a[k] - q[k], B[k] = b[k] - q[k], C[k] = c[k] - q[k];
    double la = sqrt(A[0] * A[0] + A[1] * A[1] + A[2] * A[2]);
    double lb = sqrt(B[0] * B[0] + B[1] * B[1] + B[2] * B[2]);
    double lc = sqrt(C[0] * C[0] + C[1] * C[1] + C[2] * C[2]);
    double det = A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0]) +
                 A[2] * (B[0] * C[1] - B[1] * C[0]);
    double dab = A[0] * B[0] + A[1] * B[1] + A[2] * B[2];
    double dbc = B[0] * C[0] + B[1] * C[1] + B[2] * C[2];
    double dca = C[0] * A[0] + C[1] * A[1] + C[2] * A[2];
    return 2.0 * atan2(det, la * lb * lc + dab * lc + dbc * la + dca * lb);
}

static double winding(const struct mesh *m, const double q[3])
{
    double sum = 0;
    for (uint32_t t = 0; t < m->index_count; t += 3)
        sum += solid_angle(m->vertices[m->indices[t]].pos, m->vertices[m->indices[t + 1]].pos,
                           m->vertices[m->indices[t + 2]].pos, q);
    return sum / (4.0 * PI);
}

/* Which known boundary the edge between welded positions p and q lies on:
 * 0 none. */
enum boundary { B_NONE, B_SPOUT_MOUTH, B_SPOUT_BASE, B_HANDLE_ENDS, B_LID_EDGE, B_RIM_INNER };

static enum boundary classify(int patch, const struct mesh *m, uint32_t va, uint32_t vb,
                              int segments)
{
    /* Vertex index within its patch gives (i, j) = (u, v) grid position. */
    uint32_t side = (uint32_t)segments + 1, la = va % (side * side), lb = vb % (side * side);
    uint32_t ia = la / side, ib = lb / side;
    (void)m;
    enum teapot_part part = teapot_patch_part(patch);
    bool u0 = ia == 0 && ib == 0, u1 = ia == side - 1 && ib == side - 1;
    if (part == TEAPOT_SPOUT && patch >= 18 && u1)
        return B_SPOUT_MOUTH;
    if (part == TEAPOT_SPOUT && patch < 18 && u0)
        return B_SPOUT_BASE;
    if (part == TEAPOT_HANDLE && ((patch < 14 && u0) || (patch >= 14 && u1)))
        return B_HANDLE_ENDS;
    if (part == TEAPOT_LID && patch >= 24 && u1)
        return B_LID_EDGE;
    if (part == TEAPOT_RIM && u0)
        return B_RIM_INNER;
    return B_NONE;
}

static void test_closed(int segments)
{
    struct mesh m;
    CHECK(mesh_create_teapot(&m, segments, 1.0f));
    uint32_t tris = m.index_count / 3;
    CHECK(tris == (uint32_t)(64 * segments * segments));
    struct welded w;
    weld(&m, &w);
    struct edge *edges = malloc(m.index_count * sizeof(struct edge));
    int ne = 0, degenerate = 0;
    for (uint32_t t = 0; t < tris; t++) {
        uint32_t v[3] = {w.id[m.indices[t * 3]], w.id[m.indices[t * 3 + 1]],
                         w.id[m.indices[t * 3 + 2]]};
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
            degenerate++; /* collapsed at the lid's knob and the bottom's centre */
            continue;
        }
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            edges[ne++] = (struct edge){a < b ? a : b, a < b ? b : a, a < b ? 1 : -1, (int)t};
        }
    }
    qsort(edges, (size_t)ne, sizeof(struct edge), by_edge);
    int shared = 0, open = 0, overused = 0, misoriented = 0, unexplained = 0;
    int by_boundary[6] = {0};
    for (int i = 0; i < ne;) {
        int j = i;
        while (j < ne && by_edge(&edges[i], &edges[j]) == 0)
            j++;
        int uses = j - i;
        if (uses == 2) {
            shared++;
            misoriented += edges[i].forward == edges[i + 1].forward;
        } else if (uses == 1) {
            open++;
            /* Find the triangle's original vertices for this edge. */
            int t = edges[i].tri, patch = t / (2 * segments * segments);
            uint32_t orig[2] = {0, 0};
            int found = 0;
            for (int k = 0; k < 3 && found < 2; k++) {
                uint32_t o = m.indices[t * 3 + k];
                if (w.id[o] == edges[i].lo || w.id[o] == edges[i].hi)
                    orig[found++] = o;
            }
            enum boundary b = classify(patch, &m, orig[0], orig[1], segments);
            by_boundary[b]++;
            unexplained += b == B_NONE;
            if (b == B_NONE)
                fprintf(stderr, "open edge in patch %d (%s)\n", patch,
                        teapot_part_names[teapot_patch_part(patch)]);
        } else {
            overused++;
        }
        i = j;
    }
    CHECK(overused == 0);     /* manifold: no edge in three triangles */
    CHECK(misoriented == 0);  /* neighbours agree on the orientation */
    CHECK(unexplained == 0);  /* every open edge is a known boundary */
    /* Each known boundary is a whole loop of its patches' edges. */
    CHECK(by_boundary[B_SPOUT_MOUTH] == 2 * segments);
    CHECK(by_boundary[B_SPOUT_BASE] == 2 * segments);
    CHECK(by_boundary[B_HANDLE_ENDS] == 4 * segments);
    CHECK(by_boundary[B_LID_EDGE] == 4 * segments);
    CHECK(by_boundary[B_RIM_INNER] == 4 * segments);
    CHECK(shared > 0 && open == 16 * segments);
    CHECK(degenerate == 8 * segments); /* one collapsed triangle per pole quad */
    printf("segments %d: %d welded vertices, %d shared edges, %d open, %d degenerate\n",
           segments, w.count, shared, open, degenerate);
    free(edges);
    free(w.id);
    mesh_finish(&m);
}

/* Normals point outwards: for a point on each patch (away from the open
 * boundaries), a step out along the normal has winding number about 0 and
 * a step in about 1 (2 where the handle and spout sink into the body). */
static void test_outward(void)
{
    struct mesh m;
    CHECK(mesh_create_teapot(&m, 8, 1.0f));
    int bad = 0;
    for (int p = 0; p < TEAPOT_PATCH_COUNT; p++) {
        static const double at[][2] = {{0.5, 0.5}, {0.3, 0.7}, {0.7, 0.3}};
        for (int s = 0; s < 3; s++) {
            double pos[3], n[3], out[3], in[3];
            teapot_eval(p, at[s][0], at[s][1], pos, n);
            CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-9);
            for (int k = 0; k < 3; k++)
                out[k] = pos[k] + 0.03 * n[k], in[k] = pos[k] - 0.03 * n[k];
            double wo = winding(&m, out), wi = winding(&m, in);
            bool ok = fabs(wo) < 0.25 && wi - wo > 0.75;
            if (!ok)
                fprintf(stderr, "patch %d (%s) at %.1f,%.1f: winding out %.3f in %.3f\n", p,
                        teapot_part_names[teapot_patch_part(p)], at[s][0], at[s][1], wo, wi);
            bad += !ok;
        }
    }
    CHECK(bad == 0);
    /* The mesh's own normals agree with the triangles' winding. */
    int disagree = 0;
    for (uint32_t t = 0; t < m.index_count; t += 3) {
        const struct mesh_vertex *a = &m.vertices[m.indices[t]], *b = &m.vertices[m.indices[t + 1]],
                                 *c = &m.vertices[m.indices[t + 2]];
        double e1[3], e2[3], fn[3];
        for (int k = 0; k < 3; k++)
            e1[k] = b->pos[k] - a->pos[k], e2[k] = c->pos[k] - a->pos[k];
        fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
        fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
        fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double area = sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
        if (area < 1e-9)
            continue;
        double dot = 0;
        for (int k = 0; k < 3; k++)
            dot += fn[k] * (a->normal[k] + b->normal[k] + c->normal[k]);
        disagree += dot <= 0;
    }
    CHECK(disagree == 0);
    mesh_finish(&m);
}

static void test_charts_and_bounds(void)
{
    struct mesh m;
    CHECK(mesh_create_teapot(&m, 4, 2.0f));
    CHECK(m.vertex_count == 32 * 25);
    float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
    int outside = 0;
    for (uint32_t i = 0; i < m.vertex_count; i++) {
        const struct mesh_vertex *v = &m.vertices[i];
        for (int k = 0; k < 3; k++)
            lo[k] = fminf(lo[k], v->pos[k]), hi[k] = fmaxf(hi[k], v->pos[k]);
        outside += v->uv[0] < v->chart[0] - 1e-6f || v->uv[0] > v->chart[2] + 1e-6f ||
                   v->uv[1] < v->chart[1] - 1e-6f || v->uv[1] > v->chart[3] + 1e-6f;
        CHECK_NEAR((v->chart[2] - v->chart[0]) * (v->chart[3] - v->chart[1]), 1.0 / 32, 1e-6);
    }
    CHECK(outside == 0);
    /* Centred, y-up, height 3.15 x scale 2; the spout reaches +x. */
    CHECK_NEAR(hi[1] - lo[1], TEAPOT_HEIGHT * 2, 1e-3);
    CHECK_NEAR(hi[1] + lo[1], 0.0, 1e-3);
    CHECK(hi[0] > 3.0f && lo[0] < -2.9f);
    CHECK(m.bound_radius >= hi[0] && m.bound_radius < 2.0f * 4.0f);
    CHECK(m.uv_per_unit > 0 && m.uv_per_unit < 1.0f);
    mesh_finish(&m);
    CHECK(!mesh_create_teapot(&m, 0, 1.0f));
    CHECK(!mesh_create_teapot(&m, TEAPOT_MAX_SEGMENTS + 1, 1.0f));
}

static void test_tessellation_error(void)
{
    double prev = INFINITY;
    for (int s = 1; s <= 32; s *= 2) {
        double e = teapot_tessellation_error(s);
        CHECK(e > 0 && e < prev);
        /* Chord error falls with the square of the step. */
        if (s >= 4)
            CHECK(e < prev / 3.0);
        prev = e;
    }
    /* 100 pixels per unit at a 0.5 px bound: a tessellation that meets it,
     * whose predecessor does not. */
    int s = teapot_auto_segments(100.0, 0.5);
    CHECK(s > 1 && s <= TEAPOT_MAX_SEGMENTS);
    CHECK(teapot_tessellation_error(s) * 100.0 <= 0.5);
    CHECK(teapot_tessellation_error(s - 1) * 100.0 > 0.5);
    CHECK(teapot_auto_segments(1.0, 100.0) == TEAPOT_MIN_SEGMENTS);
    CHECK(teapot_auto_segments(1e9, 0.01) == TEAPOT_MAX_SEGMENTS);
}

int main(void)
{
    test_closed(2);
    test_closed(8);
    test_outward();
    test_charts_and_bounds();
    test_tessellation_error();
    return check_finish("test_teapot");
}
