#define _DEFAULT_SOURCE /* M_SQRT1_2 */
/* LDR-FLIP: P. Andersson, J. Nilsson, T. Akenine-Moller, M. Oskarsson,
 * K. Astrom and M. D. Fairchild, "FLIP: A Difference Evaluator for
 * Alternating Images", HPG 2020. Constants as published (and as in NVIDIA's
 * reference implementation):
 *  - colour: sRGB -> linear RGB -> XYZ (D65) -> YyCxCz; each channel
 *    filtered by its contrast sensitivity function, a sum of Gaussians
 *    a1 sqrt(pi/b1) exp(-pi^2 d^2/b1) + a2 sqrt(pi/b2) exp(-pi^2 d^2/b2),
 *    d in degrees, with (a1, b1, a2, b2) = achromatic (1, 0.0047, 0, 1e-5),
 *    red-green (1, 0.0053, 0, 1e-5), blue-yellow (34.1, 0.04, 13.5, 0.025),
 *    radius ceil(3 sqrt(max b / (2 pi^2)) ppd), weights normalised to 1,
 *    borders replicated; back to linear RGB clamped to [0, 1]; CIELAB with
 *    the Hunt adjustment (a, b scaled by 0.01 L); HyAB distance; raised to
 *    qc = 0.7 and redistributed with pc = 0.4, pt = 0.95 against cmax, the
 *    HyAB distance between Hunt-adjusted green and blue raised to qc;
 *  - features: on the normalised luminance, first and second derivatives of
 *    a Gaussian with sigma = 0.5 w ppd, w = 0.082 degrees, radius ceil(3
 *    sigma), positive weights normalised to 1 and negative ones to -1; the
 *    largest of the edge and point magnitude differences, times 1/sqrt(2),
 *    raised to qf = 0.5;
 *  - FLIP = colour error ^ (1 - feature error).
 * Every 2-D kernel here factors into two 1-D ones, so filtering is separable. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/metrics.h"

static const double PI = 3.14159265358979323846;
enum { MAX_RADIUS = 256 };

double flip_default_ppd(void) { return 0.7 * 3840.0 / 0.7 * PI / 180.0; }

/* sRGB (D65) <-> XYZ, exact rationals from image-engineering.de, as FLIP uses. */
static const double RGB2XYZ[3][3] = {
    {10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
    {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
    {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0},
};
static const double XYZ2RGB[3][3] = {
    {3.241003275, -1.537398934, -0.498615861},
    {-0.969224334, 1.875930071, 0.041554224},
    {0.055639423, -0.204011202, 1.057148933},
};
static const double WHITE[3] = {0.950428545, 1.0, 1.088900371};
static const double INV_WHITE[3] = {1.052156925, 1.0, 0.918357670};

static double srgb_to_linear(double c)
{
    return c > 0.04045 ? pow((c + 0.055) / 1.055, 2.4) : c / 12.92;
}

static void mat3(const double m[3][3], const double in[3], double out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m[r][0] * in[0] + m[r][1] * in[1] + m[r][2] * in[2];
}

/* Per-pixel colour work is in float, as in NVIDIA's C++ reference. */
static void linear_to_hunt_lab(const double rgb[3], float lab[3])
{
    double xyz[3];
    float f[3];
    mat3(RGB2XYZ, rgb, xyz);
    const float delta = 6.0f / 29.0f, d3 = delta * delta * delta,
                factor = 1.0f / (3.0f * delta * delta);
    for (int i = 0; i < 3; i++) {
        float v = (float)(xyz[i] * INV_WHITE[i]);
        f[i] = v > d3 ? cbrtf(v) : factor * v + 4.0f / 29.0f;
    }
    lab[0] = 116.0f * f[1] - 16.0f;
    lab[1] = 0.01f * lab[0] * 500.0f * (f[0] - f[1]);
    lab[2] = 0.01f * lab[0] * 200.0f * (f[1] - f[2]);
}

static float hyab(const float a[3], const float b[3])
{
    float dl = a[0] - b[0], da = a[1] - b[1], db = a[2] - b[2];
    return fabsf(dl) + sqrtf(da * da + db * db);
}

/* Separable filter with replicated borders: dst = ky (x) kx * src. Taps
 * run outermost so the inner loops vectorize; row holds one padded row. */
METRICS_SIMD static void filter(float *dst, const float *src, float *tmp, float *row, int w, int h,
                   const float *kx, int rx, const float *ky, int ry)
{
    for (int y = 0; y < h; y++) {
        const float *in = src + (size_t)y * (size_t)w;
        float *out = tmp + (size_t)y * (size_t)w;
        for (int x = -rx; x < w + rx; x++)
            row[x + rx] = in[x < 0 ? 0 : (x >= w ? w - 1 : x)];
        for (int x = 0; x < w; x++)
            out[x] = 0.0f;
        for (int i = 0; i <= 2 * rx; i++) {
            const float k = kx[i], *r = row + i;
            for (int x = 0; x < w; x++)
                out[x] += k * r[x];
        }
    }
    for (int y = 0; y < h; y++) {
        float *out = dst + (size_t)y * (size_t)w;
        for (int x = 0; x < w; x++)
            out[x] = 0.0f;
        for (int j = -ry; j <= ry; j++) {
            int yy = y + j < 0 ? 0 : (y + j >= h ? h - 1 : y + j);
            const float *in = tmp + (size_t)yy * (size_t)w;
            const float k = ky[j + ry];
            for (int x = 0; x < w; x++)
                out[x] += k * in[x];
        }
    }
}

struct csf_filter {
    int radius;
    int terms;
    float weight[2];               /* c_i (sum g_i)^2 / total */
    float kernel[2][2 * MAX_RADIUS + 1]; /* g_i / sum g_i */
};

static void make_csf(struct csf_filter *f, double ppd, double a1, double b1, double a2, double b2)
{
    const double max_b = 0.04; /* largest of every channel's b parameters */
    f->radius = (int)ceil(3.0 * sqrt(max_b / (2.0 * PI * PI)) * ppd);
    if (f->radius > MAX_RADIUS)
        f->radius = MAX_RADIUS;
    double a[2] = {a1, a2}, b[2] = {b1, b2}, mass[2], total = 0;
    f->terms = a2 > 0 ? 2 : 1;
    for (int t = 0; t < f->terms; t++) {
        double sum = 0;
        for (int i = -f->radius; i <= f->radius; i++) {
            double d = i / ppd;
            double g = exp(-PI * PI * d * d / b[t]);
            f->kernel[t][i + f->radius] = (float)g;
            sum += g;
        }
        for (int i = 0; i <= 2 * f->radius; i++)
            f->kernel[t][i] = (float)(f->kernel[t][i] / sum);
        /* The 2-D term's mass: c (sum g)^2, with c = a sqrt(pi / b). */
        mass[t] = a[t] * sqrt(PI / b[t]) * sum * sum;
        total += mass[t];
    }
    for (int t = 0; t < f->terms; t++)
        f->weight[t] = (float)(mass[t] / total);
}

static void apply_csf(float *plane, float *acc, float *tmp, float *tmp2, float *row, int w,
                      int h, const struct csf_filter *f)
{
    size_t n = (size_t)w * (size_t)h;
    memset(acc, 0, n * sizeof(float));
    for (int t = 0; t < f->terms; t++) {
        filter(tmp2, plane, tmp, row, w, h, f->kernel[t], f->radius, f->kernel[t], f->radius);
        for (size_t i = 0; i < n; i++)
            acc[i] += f->weight[t] * tmp2[i];
    }
    memcpy(plane, acc, n * sizeof(float));
}

struct feature_filter {
    int radius;
    float edge[2 * MAX_RADIUS + 1], point[2 * MAX_RADIUS + 1], gauss[2 * MAX_RADIUS + 1];
};

static void make_features(struct feature_filter *f, double ppd)
{
    const double w = 0.082; /* degrees: peak to trough of the edge detector */
    double sd = 0.5 * w * ppd;
    f->radius = (int)ceil(3.0 * sd);
    if (f->radius > MAX_RADIUS)
        f->radius = MAX_RADIUS;
    double gsum = 0, epos = 0, ppos = 0, pneg = 0;
    double e[2 * MAX_RADIUS + 1], p[2 * MAX_RADIUS + 1], g[2 * MAX_RADIUS + 1];
    for (int i = -f->radius; i <= f->radius; i++) {
        double x = i, gx = exp(-x * x / (2.0 * sd * sd));
        g[i + f->radius] = gx;
        e[i + f->radius] = -x * gx;
        p[i + f->radius] = (x * x / (sd * sd) - 1.0) * gx;
        gsum += gx;
        if (e[i + f->radius] > 0)
            epos += e[i + f->radius];
        if (p[i + f->radius] > 0)
            ppos += p[i + f->radius];
        else
            pneg -= p[i + f->radius];
    }
    /* 2-D sums of the positive (negative) weights are the 1-D ones times the
     * Gaussian's sum, so normalising each factor normalises the kernel. */
    for (int i = 0; i <= 2 * f->radius; i++) {
        f->gauss[i] = (float)(g[i] / gsum);
        f->edge[i] = (float)(e[i] / epos); /* antisymmetric: |negative sum| = positive sum */
        f->point[i] = (float)(p[i] > 0 ? p[i] / ppos : p[i] / pneg);
    }
}

/* Edge and point magnitudes of a luminance plane. */
static void features(const float *y, float *edge, float *point, float *tmp, float *a, float *b,
                     float *row, int w, int h, const struct feature_filter *f)
{
    size_t n = (size_t)w * (size_t)h;
    int r = f->radius;
    filter(a, y, tmp, row, w, h, f->edge, r, f->gauss, r);
    filter(b, y, tmp, row, w, h, f->gauss, r, f->edge, r);
    for (size_t i = 0; i < n; i++)
        edge[i] = sqrtf(a[i] * a[i] + b[i] * b[i]);
    filter(a, y, tmp, row, w, h, f->point, r, f->gauss, r);
    filter(b, y, tmp, row, w, h, f->gauss, r, f->point, r);
    for (size_t i = 0; i < n; i++)
        point[i] = sqrtf(a[i] * a[i] + b[i] * b[i]);
}

/* Sorts non-negative floats: their bit patterns order as unsigned integers,
 * so two 16-bit radix passes do it in linear time. */
static bool sort_nonnegative(float *v, size_t n)
{
    uint32_t *a = (uint32_t *)v, *b = malloc(n * sizeof(uint32_t));
    size_t *count = calloc(65536, sizeof(size_t));
    if (!b || !count) {
        free(b);
        free(count);
        return false;
    }
    for (int pass = 0; pass < 2; pass++) {
        int shift = pass * 16;
        memset(count, 0, 65536 * sizeof(size_t));
        for (size_t i = 0; i < n; i++)
            count[(a[i] >> shift) & 0xffff]++;
        size_t pos = 0;
        for (size_t k = 0; k < 65536; k++) {
            size_t c = count[k];
            count[k] = pos;
            pos += c;
        }
        for (size_t i = 0; i < n; i++)
            b[count[(a[i] >> shift) & 0xffff]++] = a[i];
        memcpy(a, b, n * sizeof(uint32_t));
    }
    free(b);
    free(count);
    return true;
}

/* FLIP's weighted percentile: each error weighted by itself; the first
 * value, in ascending order, at which the running sum exceeds p of the total. */
static double weighted_percentile(const float *sorted, size_t n, double total, double p)
{
    double run = 0;
    for (size_t i = 0; i < n; i++) {
        run += sorted[i];
        if (run > p * total)
            return sorted[i];
    }
    return n ? sorted[n - 1] : 0.0;
}

bool flip_compute(const struct image *ref, const struct image *test, double ppd,
                  bool keep_map, struct flip_result *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    if (ref->width != test->width || ref->height != test->height) {
        snprintf(err, errlen, "flip: image sizes differ");
        return false;
    }
    if (!(ppd > 0) || ppd > 1000) {
        snprintf(err, errlen, "flip: pixels_per_degree must be above 0 and at most 1000");
        return false;
    }
    int w = ref->width, h = ref->height;
    size_t n = (size_t)w * (size_t)h;
    /* planes: 3 colour + 1 luminance per image, error map, 4 scratch, a row */
    float *buf = malloc(n * sizeof(float) * 13 + ((size_t)w + 2 * MAX_RADIUS + 2) * sizeof(float));
    if (!buf) {
        snprintf(err, errlen, "flip: out of memory");
        return false;
    }
    float *img[2][4], *map = buf + n * 8, *s0 = map + n, *s1 = s0 + n, *s2 = s1 + n, *s3 = s2 + n;
    float *row = s3 + n;
    for (int k = 0; k < 2; k++)
        for (int c = 0; c < 4; c++)
            img[k][c] = buf + n * (size_t)(k * 4 + c);

    struct csf_filter csf[3];
    make_csf(&csf[0], ppd, 1.0, 0.0047, 0.0, 1e-5);
    make_csf(&csf[1], ppd, 1.0, 0.0053, 0.0, 1e-5);
    make_csf(&csf[2], ppd, 34.1, 0.04, 13.5, 0.025);
    struct feature_filter feat;
    make_features(&feat, ppd);

    double lut[256];
    for (int i = 0; i < 256; i++)
        lut[i] = srgb_to_linear(i / 255.0);
    const struct image *src[2] = {ref, test};
    for (int k = 0; k < 2; k++) {
        for (size_t i = 0; i < n; i++) {
            const uint8_t *p = src[k]->rgb + i * 3;
            double rgb[3] = {lut[p[0]], lut[p[1]], lut[p[2]]}, xyz[3];
            mat3(RGB2XYZ, rgb, xyz);
            double x = xyz[0] * INV_WHITE[0], y = xyz[1] * INV_WHITE[1], z = xyz[2] * INV_WHITE[2];
            img[k][0][i] = (float)(116.0 * y - 16.0); /* Yy */
            img[k][1][i] = (float)(500.0 * (x - y));  /* Cx */
            img[k][2][i] = (float)(200.0 * (y - z));  /* Cz */
            img[k][3][i] = (float)y;                  /* (Yy + 16) / 116 */
        }
        for (int c = 0; c < 3; c++)
            apply_csf(img[k][c], s0, s1, s2, row, w, h, &csf[c]);
    }

    /* Colour difference, written into map. */
    float lab_g[3], lab_b[3];
    linear_to_hunt_lab((double[3]){0, 1, 0}, lab_g);
    linear_to_hunt_lab((double[3]){0, 0, 1}, lab_b);
    const double qc = 0.7, qf = 0.5, pc = 0.4, pt = 0.95;
    const float cmax = powf(hyab(lab_g, lab_b), (float)qc), pccmax = (float)pc * cmax;
    for (size_t i = 0; i < n; i++) {
        /* Same filtered colour in both images: no colour error, and none in
         * the final value either (0 raised to 1 - feature error). */
        if (img[0][0][i] == img[1][0][i] && img[0][1][i] == img[1][1][i] &&
            img[0][2][i] == img[1][2][i]) {
            map[i] = 0.0f;
            continue;
        }
        float lab[2][3];
        for (int k = 0; k < 2; k++) {
            double yv = (img[k][0][i] + 16.0) / 116.0;
            double xyz[3] = {(yv + img[k][1][i] / 500.0) * WHITE[0], yv * WHITE[1],
                             (yv - img[k][2][i] / 200.0) * WHITE[2]};
            double rgb[3];
            mat3(XYZ2RGB, xyz, rgb);
            for (int c = 0; c < 3; c++)
                rgb[c] = rgb[c] < 0 ? 0 : (rgb[c] > 1 ? 1 : rgb[c]);
            linear_to_hunt_lab(rgb, lab[k]);
        }
        float e = powf(hyab(lab[0], lab[1]), (float)qc);
        map[i] = e < pccmax ? (float)pt / pccmax * e
                            : (float)pt + (e - pccmax) / (cmax - pccmax) * (1.0f - (float)pt);
    }

    /* Feature difference; the colour planes of both images are free now. */
    float *edge_r = img[0][0], *point_r = img[0][1], *edge_t = img[1][0], *point_t = img[1][1];
    features(img[0][3], edge_r, point_r, s0, s1, s2, row, w, h, &feat);
    features(img[1][3], edge_t, point_t, s0, s1, s2, row, w, h, &feat);
    double sum = 0;
    out->min = INFINITY;
    out->max = 0;
    for (size_t i = 0; i < n; i++) {
        if (map[i] == 0.0f) {
            out->min = 0.0;
            continue;
        }
        float de = fabsf(edge_r[i] - edge_t[i]), dp = fabsf(point_r[i] - point_t[i]);
        float f = powf((de > dp ? de : dp) * (float)M_SQRT1_2, (float)qf);
        double v = powf(map[i], 1.0f - f);
        map[i] = (float)v;
        sum += v;
        out->min = v < out->min ? v : out->min;
        out->max = v > out->max ? v : out->max;
    }
    out->mean = sum / (double)n;
    /* Zeros weigh nothing in the weighted percentiles: sort the rest only. */
    size_t nonzero = 0;
    for (size_t i = 0; i < n; i++)
        if (map[i] > 0.0f)
            s3[nonzero++] = map[i];
    if (!sort_nonnegative(s3, nonzero)) {
        snprintf(err, errlen, "flip: out of memory");
        free(buf);
        return false;
    }
    out->weighted_q1 = weighted_percentile(s3, nonzero, sum, 0.25);
    out->weighted_median = weighted_percentile(s3, nonzero, sum, 0.50);
    out->weighted_q3 = weighted_percentile(s3, nonzero, sum, 0.75);
    if (keep_map) {
        out->map = malloc(n * sizeof(float));
        if (out->map)
            memcpy(out->map, map, n * sizeof(float));
    }
    free(buf);
    return true;
}
