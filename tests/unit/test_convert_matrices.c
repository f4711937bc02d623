/* The converter's normal matrix (daemon/assets/convert_matrices.c): for
 * rotations it is the rotation (a quarter turn about x takes +y to +z, not
 * to -z as M^-1 would); for a non-uniform scale the inverse scale; for a
 * mirror it keeps the surface's turn (det < 0); for any matrix M^T N =
 * |det| I, stored column-major as xform_normal reads it; and a normal
 * transformed by it stays perpendicular to every tangent transformed by M. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/assets/convert_internal.h"
#include "tests/unit/check.h"

/* Column-major 4x4 from a 3x3 given by rows. */
static void from_rows(const double r[3][3], double m[16])
{
    memset(m, 0, 16 * sizeof(double));
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            m[4 * j + i] = r[i][j];
    m[15] = 1.0;
}

static void normal_of(const double m[16], const double in[3], double out[3])
{
    double n[9];
    normal_matrix(m, n);
    xform_normal(n, in, out);
    normalize3(out);
}

int main(void)
{
    double m[16], out[3];

    /* A quarter turn about x: y -> z, z -> -y. */
    const double quarter[3][3] = {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}};
    from_rows(quarter, m);
    normal_of(m, (double[3]){0, 1, 0}, out);
    CHECK_NEAR(out[0], 0.0, 1e-12);
    CHECK_NEAR(out[1], 0.0, 1e-12);
    CHECK_NEAR(out[2], 1.0, 1e-12);
    normal_of(m, (double[3]){0, 0, 1}, out);
    CHECK_NEAR(out[1], -1.0, 1e-12);

    /* A general rotation: the normal turns as a direction does. */
    double c = cos(0.7), s = sin(0.7);
    const double rot[3][3] = {{c, -s, 0}, {s * 0.6, c * 0.6, -0.8}, {s * 0.8, c * 0.8, 0.6}};
    from_rows(rot, m);
    const double v[3] = {0.3, -0.5, 0.81};
    double d[3];
    xform_dir(m, v, d);
    normalize3(d);
    normal_of(m, v, out);
    for (int k = 0; k < 3; k++)
        CHECK_NEAR(out[k], d[k], 1e-12);

    /* A non-uniform scale: a 45-degree normal in xy leans towards the
     * squashed axis. */
    const double scale[3][3] = {{4, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    from_rows(scale, m);
    normal_of(m, (double[3]){1, 1, 0}, out);
    CHECK(out[1] > 0.9 && out[0] > 0.2 && out[0] < 0.3);

    /* A mirror: x flips, and the normal of a surface facing +x faces -x. */
    const double mirror[3][3] = {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    from_rows(mirror, m);
    double det = normal_matrix(m, (double[9]){0});
    CHECK(det < 0);
    normal_of(m, (double[3]){1, 0, 0}, out);
    CHECK_NEAR(out[0], -1.0, 1e-12);
    normal_of(m, (double[3]){0, 1, 0}, out);
    CHECK_NEAR(out[1], 1.0, 1e-12);

    /* Any matrix: M^T N = |det| I, and transformed tangents stay
     * perpendicular to the transformed normal. */
    srand(7);
    int perpendicular = 0, identity = 0;
    for (int trial = 0; trial < 200; trial++) {
        double r[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                r[i][j] = (double)rand() / RAND_MAX * 4.0 - 2.0;
        from_rows(r, m);
        double n[9];
        double dt = normal_matrix(m, n);
        if (fabs(dt) < 1e-3)
            continue;
        bool ok = true;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                /* (M^T N)[i][j] = sum_k M[k][i] N[k][j]; N[k][j] = n[3 j + k]. */
                double x = 0;
                for (int k = 0; k < 3; k++)
                    x += r[k][i] * n[3 * j + k];
                ok = ok && fabs(x - (i == j ? fabs(dt) : 0.0)) < 1e-9 * fmax(1.0, fabs(dt));
            }
        identity += ok;
        double nrm[3] = {0.2, 0.9, -0.4}, tan[3] = {0.9, -0.2, 0.0};
        double nw[3], tw[3];
        xform_normal(n, nrm, nw);
        xform_dir(m, tan, tw);
        double dot = nw[0] * tw[0] + nw[1] * tw[1] + nw[2] * tw[2];
        double dot0 = nrm[0] * tan[0] + nrm[1] * tan[1] + nrm[2] * tan[2];
        perpendicular += fabs(dot - fabs(dt) * dot0) < 1e-9 * fmax(1.0, fabs(dt));
    }
    CHECK(identity > 150 && perpendicular == identity);
    return check_finish("test_convert_matrices");
}
