#include "daemon/lighting/cube_faces.h"

#include <math.h>
#include <string.h>

static const float AXES[6][3][3] = {
    /* forward, s axis, t axis */
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}},
};

void cube_face_axes(int face, float forward[3], float s_axis[3], float t_axis[3])
{
    memcpy(forward, AXES[face][0], 3 * sizeof(float));
    memcpy(s_axis, AXES[face][1], 3 * sizeof(float));
    memcpy(t_axis, AXES[face][2], 3 * sizeof(float));
}

int cube_face_of(const float d[3])
{
    float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    if (ax >= ay && ax >= az)
        return d[0] >= 0 ? 0 : 1;
    if (ay >= az)
        return d[1] >= 0 ? 2 : 3;
    return d[2] >= 0 ? 4 : 5;
}

void cube_face_view_proj(int face, const float eye[3], float widen, float n, float f, float out[16])
{
    /* View rows: x = s_axis, y = t_axis, z = -forward (GL looks down -z), a
     * rotation for every face; then a square perspective with
     * 1 / tan(half angle) = 1 / widen. */
    const float(*ax)[3] = AXES[face];
    float rows[3][4];
    for (int r = 0; r < 3; r++) {
        const float *a = r == 0 ? ax[1] : r == 1 ? ax[2] : ax[0];
        float sign = r == 2 ? -1.0f : 1.0f;
        for (int k = 0; k < 3; k++)
            rows[r][k] = sign * a[k];
        rows[r][3] = -(rows[r][0] * eye[0] + rows[r][1] * eye[1] + rows[r][2] * eye[2]);
    }
    float g = 1.0f / widen, A = (f + n) / (n - f), B = 2.0f * f * n / (n - f);
    /* clip = P * V with P = diag(g, g) and the z/w rows; column-major out[c * 4 + r]. */
    memset(out, 0, 16 * sizeof(float));
    for (int c = 0; c < 4; c++) {
        out[c * 4 + 0] = g * rows[0][c];
        out[c * 4 + 1] = g * rows[1][c];
        out[c * 4 + 2] = A * rows[2][c] + (c == 3 ? B : 0.0f);
        out[c * 4 + 3] = -rows[2][c];
    }
}

float cube_face_depth(float major, float n, float f)
{
    /* z_view = -major: ndc = (A z + B) / -z = -A - B / major... with A, B as above. */
    float A = (f + n) / (n - f), B = 2.0f * f * n / (n - f);
    float ndc = (A * -major + B) / major;
    return 0.5f * ndc + 0.5f;
}
