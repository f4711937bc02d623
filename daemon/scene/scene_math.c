/* Leaf helpers of the scene's files: the deterministic hash every build
 * draws from, low-discrepancy sequences, colours and the frustum test. */
#include "daemon/scene/scene_math.h"

#include <math.h>

double scene_hash01(uint32_t index, uint32_t salt)
{
    /* lowbias32 (Wellons) over the index mixed with a hashed salt: full
     * avalanche, so neighbouring indices and streams are unrelated. */
    uint32_t x = salt * 0x9e3779b9u;
    x ^= x >> 16;
    x = index ^ (x * 0x7feb352du);
    for (int round = 0; round < 2; round++) {
        x ^= x >> 16;
        x *= 0x7feb352du;
        x ^= x >> 15;
        x *= 0x846ca68bu;
        x ^= x >> 16;
    }
    return x / 4294967296.0;
}

double scene_radical_inverse(unsigned i, unsigned base)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    for (; i; i /= base, f *= inv)
        r += f * (i % base);
    return r;
}

void scene_hsv_to_rgb(double h, double s, double v, float out[3])
{
    double c = v * s, hp = fmod(h, 1.0) * 6.0, x = c * (1 - fabs(fmod(hp, 2.0) - 1));
    double r = 0, g = 0, b = 0;
    if (hp < 1) r = c, g = x;
    else if (hp < 2) r = x, g = c;
    else if (hp < 3) g = c, b = x;
    else if (hp < 4) g = x, b = c;
    else if (hp < 5) r = x, b = c;
    else r = c, b = x;
    out[0] = (float)(r + v - c), out[1] = (float)(g + v - c), out[2] = (float)(b + v - c);
}

bool scene_sphere_in_frustum(const float m[16], const float p[3], float r, bool fully)
{
    /* Gribb-Hartmann planes from the combined matrix. */
    for (int plane = 0; plane < 6; plane++) {
        int row = plane / 2;
        float sign = plane % 2 ? -1.0f : 1.0f, eq[4];
        for (int c = 0; c < 4; c++)
            eq[c] = m[c * 4 + 3] + sign * m[c * 4 + row];
        float len = sqrtf(eq[0] * eq[0] + eq[1] * eq[1] + eq[2] * eq[2]);
        float dist = (eq[0] * p[0] + eq[1] * p[1] + eq[2] * p[2] + eq[3]) / len;
        if (fully ? dist < r : dist < -r)
            return false;
    }
    return true;
}
