/* A uv set's coverage and overlap (daemon/assets/uv_overlap.c): a seamless
 * grid, charts touching edge to edge with vertices of their own, and a fan
 * whose centre sits on a texel centre count every texel once; mirrored
 * halves sharing one chart, a folded triangle and a stacked copy are
 * caught; degenerate triangles cover nothing; the rule's threshold. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/assets/uv_overlap.h"
#include "tests/unit/check.h"

enum { R = UV_OVERLAP_RESOLUTION };

/* An n x n grid of quads over [u0, u1] x [v0, v1], two triangles each,
 * appended to uv/tri (vertices counted by *nv, triangles by *nt); mirror
 * flips its u (the same texels, the other way round). */
static void grid(float *uv, uint32_t *tri, uint32_t *nv, uint32_t *nt, int n, double u0, double v0,
                 double u1, double v1, bool mirror)
{
    uint32_t base = *nv;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            double s = (double)i / n, t = (double)j / n;
            uv[2 * *nv] = (float)(u0 + (mirror ? 1.0 - s : s) * (u1 - u0));
            uv[2 * *nv + 1] = (float)(v0 + t * (v1 - v0));
            (*nv)++;
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1),
                     d = c + 1;
            uint32_t q[6] = {a, b, d, a, d, c};
            memcpy(&tri[3 * *nt], q, sizeof(q));
            *nt += 2;
        }
}

int main(void)
{
    static float uv[2 * 20000];
    static uint32_t tri[3 * 20000];
    uint32_t nv = 0, nt = 0;
    struct uv_coverage c;

    /* A seamless 16 x 16 grid over [0.1, 0.9]^2: 0.64 of the texels once. */
    grid(uv, tri, &nv, &nt, 16, 0.1, 0.1, 0.9, 0.9, false);
    CHECK(uv_overlap_measure(uv, nv, tri, nt, R, &c));
    CHECK(c.texels == (uint64_t)R * R && c.overlapped == 0);
    CHECK_NEAR((double)c.covered / (double)c.texels, 0.64, 0.005);
    CHECK(!uv_coverage_overlaps(&c) && uv_coverage_overlap_share(&c) == 0.0);

    /* Mirrored halves: a second grid on the same texels, u flipped. */
    grid(uv, tri, &nv, &nt, 16, 0.1, 0.1, 0.9, 0.9, true);
    CHECK(uv_overlap_measure(uv, nv, tri, nt, R, &c));
    CHECK_NEAR(uv_coverage_overlap_share(&c), 1.0, 0.01);
    CHECK(uv_coverage_overlaps(&c));

    /* Two charts side by side, touching along u = 0.5 with vertices of
     * their own, and odd grid sizes whose diagonals cross texel centres
     * exactly: every texel once. */
    nv = nt = 0;
    grid(uv, tri, &nv, &nt, 7, 0.0, 0.0, 0.5, 1.0, false);
    grid(uv, tri, &nv, &nt, 9, 0.5, 0.0, 1.0, 1.0, false);
    CHECK(uv_overlap_measure(uv, nv, tri, nt, R, &c));
    CHECK(c.overlapped == 0 && c.covered == (uint64_t)R * R);

    /* A fan of 12 triangles around a vertex on a texel centre. */
    nv = nt = 0;
    float cx = 256.5f / R, cy = 100.5f / R;
    uv[0] = cx, uv[1] = cy;
    nv = 1;
    for (int k = 0; k < 12; k++) {
        double a = 2.0 * 3.14159265358979 * k / 12;
        uv[2 * nv] = (float)(cx + 0.2 * cos(a));
        uv[2 * nv + 1] = (float)(cy + 0.15 * sin(a));
        nv++;
    }
    for (uint32_t k = 0; k < 12; k++) {
        tri[3 * nt] = 0, tri[3 * nt + 1] = 1 + k, tri[3 * nt + 2] = 1 + (k + 1) % 12;
        nt++;
    }
    CHECK(uv_overlap_measure(uv, nv, tri, nt, R, &c));
    CHECK(c.overlapped == 0 && c.covered > 1000);

    /* A folded triangle: one of a quad's two triangles turned over onto
     * the other. */
    nv = nt = 0;
    float fold[8] = {0.2f, 0.2f, 0.8f, 0.2f, 0.8f, 0.8f, 0.6f, 0.3f};
    memcpy(uv, fold, sizeof(fold));
    nv = 4;
    uint32_t ft[6] = {0, 1, 2, 0, 2, 3};
    memcpy(tri, ft, sizeof(ft));
    nt = 2;
    CHECK(uv_overlap_measure(uv, nv, tri, nt, R, &c));
    CHECK(c.overlapped > 1000 && uv_coverage_overlaps(&c));

    /* Degenerate triangles (a point, a line) cover nothing. */
    float deg[6] = {0.5f, 0.5f, 0.5f, 0.5f, 0.7f, 0.7f};
    memcpy(uv, deg, sizeof(deg));
    uint32_t dt[3] = {0, 1, 2};
    memcpy(tri, dt, sizeof(dt));
    CHECK(uv_overlap_measure(uv, 3, tri, 1, R, &c));
    CHECK(c.covered == 0 && c.overlapped == 0 && uv_coverage_overlap_share(&c) == 0.0);

    /* The rule: more than four texels and more than a thousandth. */
    struct uv_coverage r = {R * (uint64_t)R, 100000, 4};
    CHECK(!uv_coverage_overlaps(&r));
    r.overlapped = 100;
    CHECK(!uv_coverage_overlaps(&r));
    r.overlapped = 101;
    CHECK(uv_coverage_overlaps(&r));
    r.covered = 1000, r.overlapped = 5;
    CHECK(uv_coverage_overlaps(&r));
    return check_finish("test_uv_overlap");
}
