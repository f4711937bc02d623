/* The PBR model in C; see pbr_math.h. Kept term by term in step with
 * shaders/common/pbr.glsl. */
#include "daemon/lighting/pbr_math.h"

#include <math.h>
#include <stdint.h>

static const double PI = 3.14159265358979323846;

double pbr_alpha(double roughness)
{
    double r = roughness < PBR_MIN_ROUGHNESS ? PBR_MIN_ROUGHNESS : roughness > 1.0 ? 1.0 : roughness;
    return r * r;
}

double pbr_d_ggx(double NoH, double alpha)
{
    double a2 = alpha * alpha;
    double f = (NoH * a2 - NoH) * NoH + 1.0;
    return a2 / (PI * f * f);
}

double pbr_v_smith(double NoV, double NoL, double alpha)
{
    double a2 = alpha * alpha;
    double gv = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    double gl = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

double pbr_f_schlick(double f0, double VoH)
{
    double x = 1.0 - VoH, x2 = x * x;
    return f0 + (1.0 - f0) * (x2 * x2 * x);
}

void pbr_hammersley(unsigned i, unsigned n, double *u, double *v)
{
    uint32_t b = i;
    b = (b << 16) | (b >> 16);
    b = ((b & 0x55555555u) << 1) | ((b & 0xAAAAAAAAu) >> 1);
    b = ((b & 0x33333333u) << 2) | ((b & 0xCCCCCCCCu) >> 2);
    b = ((b & 0x0F0F0F0Fu) << 4) | ((b & 0xF0F0F0F0u) >> 4);
    b = ((b & 0x00FF00FFu) << 8) | ((b & 0xFF00FF00u) >> 8);
    *u = (double)i / n;
    *v = b * (1.0 / 4294967296.0);
}

void pbr_sample_ggx(double u, double v, double alpha, double h[3])
{
    double phi = 2.0 * PI * u;
    double cos_t = sqrt((1.0 - v) / (1.0 + (alpha * alpha - 1.0) * v));
    double sin_t = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    h[0] = sin_t * cos(phi);
    h[1] = sin_t * sin(phi);
    h[2] = cos_t;
}

void pbr_env_brdf(double roughness, double NoV, int samples, double *a, double *b)
{
    double alpha = pbr_alpha(roughness);
    double V[3] = {sqrt(fmax(0.0, 1.0 - NoV * NoV)), 0.0, NoV};
    double sa = 0, sb = 0;
    for (int i = 0; i < samples; i++) {
        double u, v, H[3];
        pbr_hammersley((unsigned)i, (unsigned)samples, &u, &v);
        pbr_sample_ggx(u, v, alpha, H);
        double VoH = V[0] * H[0] + V[1] * H[1] + V[2] * H[2];
        double NoL = 2.0 * VoH * H[2] - V[2];
        if (NoL <= 0.0 || VoH <= 0.0)
            continue;
        /* The estimator of F * D V * 4 NoL with pdf D NoH / (4 VoH) for L. */
        double g_vis = pbr_v_smith(NoV, NoL, alpha) * 4.0 * NoL * VoH / H[2];
        double x = 1.0 - VoH, fc = x * x * x * x * x;
        sa += (1.0 - fc) * g_vis;
        sb += fc * g_vis;
    }
    *a = sa / samples;
    *b = sb / samples;
}

bool pbr_env_brdf_table(int size, int samples, float *out)
{
    if (size < 1 || samples < 1 || !out)
        return false;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            double a, b;
            pbr_env_brdf((y + 0.5) / size, (x + 0.5) / size, samples, &a, &b);
            out[(y * size + x) * 2] = (float)a;
            out[(y * size + x) * 2 + 1] = (float)b;
        }
    return true;
}

double pbr_specular_albedo(double roughness, double NoV, double f0, int samples)
{
    /* Stratified uniform hemisphere sampling (pdf 1 / 2pi) of
     * f(L, V) NoL = D V F NoL, in a sqrt(samples) square grid. */
    double alpha = pbr_alpha(roughness);
    double V[3] = {sqrt(fmax(0.0, 1.0 - NoV * NoV)), 0.0, NoV};
    int side = (int)sqrt((double)samples);
    if (side < 1)
        side = 1;
    double sum = 0;
    for (int i = 0; i < side; i++)
        for (int j = 0; j < side; j++) {
            double cos_t = (i + 0.5) / side, sin_t = sqrt(1.0 - cos_t * cos_t);
            double phi = 2.0 * PI * (j + 0.5) / side;
            double L[3] = {sin_t * cos(phi), sin_t * sin(phi), cos_t};
            double h[3] = {L[0] + V[0], L[1] + V[1], L[2] + V[2]};
            double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            if (len < 1e-12)
                continue;
            double NoH = h[2] / len, VoH = (V[0] * h[0] + V[1] * h[1] + V[2] * h[2]) / len;
            double NoL = L[2];
            sum += pbr_d_ggx(NoH, alpha) * pbr_v_smith(NoV, NoL, alpha) *
                   pbr_f_schlick(f0, VoH) * NoL;
        }
    return sum * 2.0 * PI / ((double)side * side);
}
