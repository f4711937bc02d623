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

/* Separable filter of one tile: src is the tile with a halo of H pixels
 * (ew wide), whose out-of-image pixels repeat the nearest border pixel (the
 * replicated borders of the whole-image filter); dst gets the tw x th
 * interior. Taps run outermost so the inner loops vectorize, in the order
 * the whole-image filter adds them, so results match it bit for bit. */
METRICS_SIMD static void filter(float *dst, const float *src, float *tmp, int ew, int H, int tw,
                                int th, const float *kx, int rx, const float *ky, int ry)
{
    for (int y = H - ry; y < H + th + ry; y++) {
        const float *in = src + (size_t)y * (size_t)ew + H;
        float *out = tmp + (size_t)y * (size_t)ew + H;
        for (int x = 0; x < tw; x++)
            out[x] = 0.0f;
        for (int i = 0; i <= 2 * rx; i++) {
            const float k = kx[i], *r = in + i - rx;
            for (int x = 0; x < tw; x++)
                out[x] += k * r[x];
        }
    }
    for (int y = 0; y < th; y++) {
        float *out = dst + (size_t)y * (size_t)tw;
        for (int x = 0; x < tw; x++)
            out[x] = 0.0f;
        for (int j = -ry; j <= ry; j++) {
            const float *in = tmp + (size_t)(H + y + j) * (size_t)ew + H;
            const float k = ky[j + ry];
            for (int x = 0; x < tw; x++)
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

/* The CSF-filtered interior of one colour plane of a tile, into acc. */
static void apply_csf(float *acc, const float *plane, float *tmp, float *tmp2, int ew, int H,
                      int tw, int th, const struct csf_filter *f)
{
    size_t n = (size_t)tw * (size_t)th;
    memset(acc, 0, n * sizeof(float));
    for (int t = 0; t < f->terms; t++) {
        filter(tmp2, plane, tmp, ew, H, tw, th, f->kernel[t], f->radius, f->kernel[t], f->radius);
        for (size_t i = 0; i < n; i++)
            acc[i] += f->weight[t] * tmp2[i];
    }
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

/* Edge and point magnitudes of a tile's luminance plane (with its halo). */
static void features(const float *y, float *edge, float *point, float *tmp, float *a, float *b,
                     int ew, int H, int tw, int th, const struct feature_filter *f)
{
    size_t n = (size_t)tw * (size_t)th;
    int r = f->radius;
    filter(a, y, tmp, ew, H, tw, th, f->edge, r, f->gauss, r);
    filter(b, y, tmp, ew, H, tw, th, f->gauss, r, f->edge, r);
    for (size_t i = 0; i < n; i++)
        edge[i] = sqrtf(a[i] * a[i] + b[i] * b[i]);
    filter(a, y, tmp, ew, H, tw, th, f->point, r, f->gauss, r);
    filter(b, y, tmp, ew, H, tw, th, f->gauss, r, f->point, r);
    for (size_t i = 0; i < n; i++)
        point[i] = sqrtf(a[i] * a[i] + b[i] * b[i]);
}

/* FLIP's weighted percentiles: with the errors sorted ascending and each
 * weighted by itself, the first value at which the running sum exceeds p of
 * the total. The map is not sorted (that would double its memory): a
 * histogram of the upper 16 bits of the values' bit patterns (non-negative
 * floats order as their bits do) finds the bucket where the sum crosses,
 * and a histogram of that bucket's lower 16 bits the value itself. The
 * running sum adds bucket by bucket, so it may differ from a one-by-one sum
 * in its last bits; the value differs only if the sum lands that close to
 * the threshold. */
static bool weighted_percentiles(const float *map, size_t n, double total, const double *p,
                                 double *out, int count, float largest)
{
    enum { BUCKETS = 65536 };
    uint32_t *hi = calloc(BUCKETS, sizeof(uint32_t)), *lo = calloc(BUCKETS, sizeof(uint32_t));
    double *hi_sum = calloc(BUCKETS, sizeof(double));
    if (!hi || !lo || !hi_sum) {
        free(hi), free(lo), free(hi_sum);
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        if (map[i] <= 0.0f)
            continue;
        uint32_t bits;
        memcpy(&bits, &map[i], sizeof(bits));
        hi[bits >> 16]++;
        hi_sum[bits >> 16] += map[i];
    }
    for (int q = 0; q < count; q++) {
        double run = 0, threshold = p[q] * total;
        int bucket = -1;
        for (int b = 0; b < BUCKETS && bucket < 0; b++) {
            if (hi[b] && run + hi_sum[b] > threshold)
                bucket = b;
            else
                run += hi_sum[b];
        }
        out[q] = largest;
        if (bucket < 0)
            continue;
        memset(lo, 0, BUCKETS * sizeof(uint32_t));
        for (size_t i = 0; i < n; i++) {
            uint32_t bits;
            memcpy(&bits, &map[i], sizeof(bits));
            if (map[i] > 0.0f && (int)(bits >> 16) == bucket)
                lo[bits & 0xffff]++;
        }
        for (int l = 0; l < BUCKETS; l++) {
            if (!lo[l])
                continue;
            uint32_t bits = (uint32_t)bucket << 16 | (uint32_t)l;
            float v;
            memcpy(&v, &bits, sizeof(v));
            out[q] = v;
            run += (double)lo[l] * v;
            if (run > threshold)
                break;
        }
    }
    free(hi), free(lo), free(hi_sum);
    return true;
}

/* Tiles are TILE pixels square (the last of a row or column takes the rest,
 * up to 1.5 tiles), with a halo as wide as the widest filter. */
enum { TILE = 256 };

static int tile_span(int pos, int size)
{
    return size - pos <= TILE + TILE / 2 ? size - pos : TILE;
}

/* The widest tile_span over an extent of size. */
static int tile_max(int size)
{
    return size < TILE + TILE / 2 ? size : TILE + TILE / 2;
}

struct flip_buffers {
    float *ext[4];      /* Yy, Cx, Cz, normalised luminance: tile and halo */
    float *tmp;         /* the row pass, tile and halo */
    float *col[2][3];   /* filtered Yy, Cx, Cz of both images, interior */
    float *edge[2], *point[2];
    float *s0, *s1;     /* scratch, interior */
    float *block;
};

static bool buffers_init(struct flip_buffers *b, int w, int h, int H)
{
    size_t ext = (size_t)(tile_max(w) + 2 * H) * (size_t)(tile_max(h) + 2 * H);
    size_t in = (size_t)tile_max(w) * (size_t)tile_max(h);
    float *p = b->block = malloc((5 * ext + 12 * in) * sizeof(float));
    if (!p)
        return false;
    for (int c = 0; c < 4; c++, p += ext)
        b->ext[c] = p;
    b->tmp = p, p += ext;
    for (int k = 0; k < 2; k++) {
        for (int c = 0; c < 3; c++, p += in)
            b->col[k][c] = p;
        b->edge[k] = p, p += in;
        b->point[k] = p, p += in;
    }
    b->s0 = p, p += in;
    b->s1 = p;
    return true;
}

static int flip_halo(const struct csf_filter *csf, const struct feature_filter *feat)
{
    int H = feat->radius;
    for (int c = 0; c < 3; c++)
        H = csf[c].radius > H ? csf[c].radius : H;
    return H;
}

size_t flip_memory_bytes(int width, int height, double ppd)
{
    struct csf_filter csf[3];
    struct feature_filter feat;
    make_csf(&csf[0], ppd, 1.0, 0.0047, 0.0, 1e-5);
    csf[1] = csf[2] = csf[0];
    make_features(&feat, ppd);
    int H = flip_halo(csf, &feat);
    size_t ext = (size_t)(tile_max(width) + 2 * H) * (size_t)(tile_max(height) + 2 * H);
    size_t in = (size_t)tile_max(width) * (size_t)tile_max(height);
    return (5 * ext + 12 * in) * sizeof(float) + (size_t)width * (size_t)height * sizeof(float) +
           65536 * (2 * sizeof(uint32_t) + sizeof(double));
}

bool flip_compute(const struct image *ref, const struct image *test, double ppd,
                  bool keep_map, const struct metrics_stop *stop, struct flip_result *out,
                  char *err, size_t errlen)
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
    struct csf_filter csf[3];
    make_csf(&csf[0], ppd, 1.0, 0.0047, 0.0, 1e-5);
    make_csf(&csf[1], ppd, 1.0, 0.0053, 0.0, 1e-5);
    make_csf(&csf[2], ppd, 34.1, 0.04, 13.5, 0.025);
    struct feature_filter feat;
    make_features(&feat, ppd);
    const int H = flip_halo(csf, &feat);

    /* The error map is the one whole-image buffer: the weighted percentiles
     * need every value. */
    float *map = malloc(n * sizeof(float));
    struct flip_buffers buf = {0};
    if (!map || !buffers_init(&buf, w, h, H)) {
        free(map);
        free(buf.block);
        snprintf(err, errlen, "flip: out of memory");
        return false;
    }

    double lut[256];
    for (int i = 0; i < 256; i++)
        lut[i] = srgb_to_linear(i / 255.0);
    float lab_g[3], lab_b[3];
    linear_to_hunt_lab((double[3]){0, 1, 0}, lab_g);
    linear_to_hunt_lab((double[3]){0, 0, 1}, lab_b);
    const double qc = 0.7, qf = 0.5, pc = 0.4, pt = 0.95;
    const float cmax = powf(hyab(lab_g, lab_b), (float)qc), pccmax = (float)pc * cmax;
    const struct image *src[2] = {ref, test};

    for (int ty = 0, th; ty < h; ty += th) {
        th = tile_span(ty, h);
        for (int tx = 0, tw; tx < w; tx += tw) {
            tw = tile_span(tx, w);
            if (metrics_stopped(stop, err, errlen)) {
                free(map);
                free(buf.block);
                return false;
            }
            int ew = tw + 2 * H, eh = th + 2 * H;
            for (int k = 0; k < 2; k++) {
                for (int ey = 0; ey < eh; ey++) {
                    int y = ty - H + ey;
                    y = y < 0 ? 0 : (y >= h ? h - 1 : y);
                    for (int ex = 0; ex < ew; ex++) {
                        int x = tx - H + ex;
                        x = x < 0 ? 0 : (x >= w ? w - 1 : x);
                        const uint8_t *p = src[k]->rgb + ((size_t)y * (size_t)w + (size_t)x) * 3;
                        double rgb[3] = {lut[p[0]], lut[p[1]], lut[p[2]]}, xyz[3];
                        mat3(RGB2XYZ, rgb, xyz);
                        double X = xyz[0] * INV_WHITE[0], Y = xyz[1] * INV_WHITE[1],
                               Z = xyz[2] * INV_WHITE[2];
                        size_t e = (size_t)ey * (size_t)ew + (size_t)ex;
                        buf.ext[0][e] = (float)(116.0 * Y - 16.0); /* Yy */
                        buf.ext[1][e] = (float)(500.0 * (X - Y));  /* Cx */
                        buf.ext[2][e] = (float)(200.0 * (Y - Z));  /* Cz */
                        buf.ext[3][e] = (float)Y;                  /* (Yy + 16) / 116 */
                    }
                }
                for (int c = 0; c < 3; c++)
                    apply_csf(buf.col[k][c], buf.ext[c], buf.tmp, buf.s0, ew, H, tw, th, &csf[c]);
                features(buf.ext[3], buf.edge[k], buf.point[k], buf.tmp, buf.s0, buf.s1, ew, H, tw,
                         th, &feat);
            }
            for (int y = 0; y < th; y++)
                for (int x = 0; x < tw; x++) {
                    size_t i = (size_t)y * (size_t)tw + (size_t)x;
                    float *m = map + (size_t)(ty + y) * (size_t)w + (size_t)(tx + x);
                    /* Same filtered colour in both images: no colour error, and
                     * none in the final value either (0 raised to 1 - feature
                     * error). */
                    if (buf.col[0][0][i] == buf.col[1][0][i] &&
                        buf.col[0][1][i] == buf.col[1][1][i] &&
                        buf.col[0][2][i] == buf.col[1][2][i]) {
                        *m = 0.0f;
                        continue;
                    }
                    float lab[2][3];
                    for (int k = 0; k < 2; k++) {
                        double yv = (buf.col[k][0][i] + 16.0) / 116.0;
                        double xyz[3] = {(yv + buf.col[k][1][i] / 500.0) * WHITE[0], yv * WHITE[1],
                                         (yv - buf.col[k][2][i] / 200.0) * WHITE[2]};
                        double rgb[3];
                        mat3(XYZ2RGB, xyz, rgb);
                        for (int c = 0; c < 3; c++)
                            rgb[c] = rgb[c] < 0 ? 0 : (rgb[c] > 1 ? 1 : rgb[c]);
                        linear_to_hunt_lab(rgb, lab[k]);
                    }
                    float e = powf(hyab(lab[0], lab[1]), (float)qc);
                    float colour = e < pccmax ? (float)pt / pccmax * e
                                              : (float)pt + (e - pccmax) / (cmax - pccmax) *
                                                                (1.0f - (float)pt);
                    if (colour == 0.0f) {
                        *m = 0.0f;
                        continue;
                    }
                    float de = fabsf(buf.edge[0][i] - buf.edge[1][i]);
                    float dp = fabsf(buf.point[0][i] - buf.point[1][i]);
                    float f = powf((de > dp ? de : dp) * (float)M_SQRT1_2, (float)qf);
                    *m = powf(colour, 1.0f - f);
                }
        }
    }
    free(buf.block);

    /* The summary in raster order, as the whole-image pass adds it. */
    double sum = 0;
    float largest = 0;
    out->min = INFINITY;
    out->max = 0;
    for (size_t i = 0; i < n; i++) {
        double v = map[i];
        if (v == 0.0) {
            out->min = 0.0;
            continue;
        }
        sum += v;
        out->min = v < out->min ? v : out->min;
        out->max = v > out->max ? v : out->max;
        largest = map[i] > largest ? map[i] : largest;
    }
    out->mean = sum / (double)n;
    const double p[3] = {0.25, 0.50, 0.75};
    double q[3];
    if (!weighted_percentiles(map, n, sum, p, q, 3, largest)) {
        free(map);
        snprintf(err, errlen, "flip: out of memory");
        return false;
    }
    out->weighted_q1 = q[0];
    out->weighted_median = q[1];
    out->weighted_q3 = q[2];
    if (keep_map)
        out->map = map;
    else
        free(map);
    return true;
}
