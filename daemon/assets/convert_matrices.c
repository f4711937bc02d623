#define _POSIX_C_SOURCE 200809L
/* The nodes' world matrices and the transforms of points, directions and
 * normals (convert_internal.h). */
#include "daemon/assets/convert_internal.h"

#include <math.h>
#include <string.h>

static void mat_mul(const double a[16], const double b[16], double out[16])
{
    double r[16];
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += a[k * 4 + row] * b[col * 4 + k];
            r[col * 4 + row] = s;
        }
    memcpy(out, r, sizeof(r));
}

static void node_local(json_t *node, double m[16])
{
    static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    memcpy(m, id, sizeof(id));
    json_t *mat = json_object_get(node, "matrix");
    if (mat) {
        for (int i = 0; i < 16; i++)
            m[i] = json_number_value(json_array_get(mat, (size_t)i));
        return;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    for (int i = 0; i < 3; i++) {
        json_t *tv = json_object_get(node, "translation"), *sv = json_object_get(node, "scale");
        if (tv)
            t[i] = json_number_value(json_array_get(tv, (size_t)i));
        if (sv)
            s[i] = json_number_value(json_array_get(sv, (size_t)i));
    }
    json_t *rv = json_object_get(node, "rotation");
    if (rv) {
        double n = 0;
        for (int i = 0; i < 4; i++) {
            q[i] = json_number_value(json_array_get(rv, (size_t)i));
            n += q[i] * q[i];
        }
        n = sqrt(n);
        if (n > 0)
            for (int i = 0; i < 4; i++)
                q[i] /= n;
    }
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                   2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int col = 0; col < 3; col++)
        for (int row = 0; row < 3; row++)
            m[col * 4 + row] = r[col * 3 + row] * s[col];
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
}

void node_world(struct ctx *c, int i, double m[16])
{
    node_local(json_array_get(c->nodes, (size_t)i), m);
    for (int p = c->parent[i]; p != -1; p = c->parent[p]) {
        double pm[16];
        node_local(json_array_get(c->nodes, (size_t)p), pm);
        mat_mul(pm, m, m);
    }
}

void xform_point(const double m[16], const float in[3], float out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = (float)(m[r] * in[0] + m[4 + r] * in[1] + m[8 + r] * in[2] + m[12 + r]);
}

void xform_dir(const double m[16], const double in[3], double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m[r] * in[0] + m[4 + r] * in[1] + m[8 + r] * in[2];
}

void normalize3(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (n > 1e-30)
        for (int i = 0; i < 3; i++)
            v[i] /= n;
}

/* The normal matrix of m's upper 3x3, |det| M^-T, column-major like m,
 * and the determinant. M^-T is the cofactor matrix C over det; normals are
 * renormalised, so the scale does not matter, only the sign: C / sign(det)
 * keeps it (a mirroring m turns normals with the surface). C[i][j] is
 * stored at n[3 j + i], the column-major place of row i, column j. */
double normal_matrix(const double m[16], double n[9])
{
    /* Rows of the upper 3x3: (a b c), (d e f), (g h k). */
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], k = m[10];
    double det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g);
    double s = det < 0 ? -1.0 : 1.0;
    double cof[3][3] = {{e * k - f * h, -(d * k - f * g), d * h - e * g},
                        {-(b * k - c * h), a * k - c * g, -(a * h - b * g)},
                        {b * f - c * e, -(a * f - c * d), a * e - b * d}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            n[3 * j + i] = s * cof[i][j];
    return det;
}

void xform_normal(const double n[9], const double in[3], double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = n[r] * in[0] + n[3 + r] * in[1] + n[6 + r] * in[2];
}
