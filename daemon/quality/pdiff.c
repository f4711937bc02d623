/* PerceptualDiff: H. Yee, "A perceptual metric for production testing",
 * Journal of Graphics Tools 9(4), 2004, as implemented in Yee's
 * perceptualdiff (metric.cpp, lpyramid.cpp), whose float arithmetic this
 * follows step by step:
 *  - RGB is linearised with pow(c / 255, gamma) and taken as Adobe RGB (1998)
 *    with a D65 white, converted to XYZ with Lindbloom's matrix and to CIE
 *    L*a*b*; luminance is Y times the display luminance (cd/m^2);
 *  - an 8-level "Laplacian pyramid" at full resolution: each level is the
 *    previous one blurred by the 5x5 kernel [0.05 0.25 0.4 0.25 0.05] x the
 *    same with mirrored borders, summed tap by tap in perceptualdiff's order
 *    (a separable blur rounds otherwise, and moved 1 failing pixel of
 *    20,109 on its fish pair);
 *  - contrast sensitivity is Barten's CSF (SPIE 1989), visual masking Daly's
 *    (1993), the threshold-versus-intensity curve Ward Larson's (1997);
 *  - a pixel fails when its luminance difference exceeds factor * TVI, or its
 *    colour difference (a*, b* squared, times color_factor) exceeds factor,
 *    the colour test being off in scotopic regions (adaptation < 10 cd/m^2);
 *  - the images pass when fewer than threshold_pixels pixels fail;
 *  - a translucent image (img->alpha) is premultiplied by its alpha in
 *    float before the gamma, pow(c / 255 * a / 255, gamma), as perceptualdiff
 *    does: an alpha difference shows where the colour is not black. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/metrics.h"

enum { LEVELS = 8 }; /* MAX_PYR_LEVELS in perceptualdiff */

static const float PI_F = 3.14159265f;

void pdiff_defaults(struct pdiff_options *o)
{
    o->fov = 22.6;        /* the thesis: 20 cm wide image seen from 50 cm */
    o->threshold_pixels = 100;
    o->gamma = 2.2;
    o->luminance = 100.0;
    o->color_factor = 1.0;
    o->luminance_only = false;
}

/* Threshold versus intensity, Ward Larson, SIGGRAPH 1997 (cd/m^2). */
static float tvi(float adaptation)
{
    float log_a = log10f(adaptation), r;
    if (log_a < -3.94f)
        r = -2.86f;
    else if (log_a < -1.44f)
        r = powf(0.405f * log_a + 1.6f, 2.18f) - 2.86f;
    else if (log_a < -0.0184f)
        r = log_a - 0.395f;
    else if (log_a < 1.9f)
        r = powf(0.249f * log_a + 0.65f, 2.7f) - 0.72f;
    else
        r = log_a - 1.255f;
    return powf(10.0f, r);
}

/* Contrast sensitivity, Barten, SPIE 1989: cycles per degree, luminance. */
static float csf(float cpd, float lum)
{
    float a = 440.0f * powf(1.0f + 0.7f / lum, -0.2f);
    float b = 0.3f * powf(1.0f + 100.0f / lum, 0.15f);
    return a * cpd * expf(-b * cpd) * sqrtf(1.0f + 0.06f * expf(b * cpd));
}

/* Visual masking, Daly 1993. */
static float mask(float contrast)
{
    float a = powf(392.498f * contrast, 0.7f);
    float b = powf(0.0153f * a, 4.0f);
    return powf(1.0f + b, 0.25f);
}

/* Adobe RGB (1998), D65, to XYZ (matrix from brucelindbloom.com). */
static void adobe_rgb_to_xyz(float r, float g, float b, float *x, float *y, float *z)
{
    *x = r * 0.576700f + g * 0.185556f + b * 0.188212f;
    *y = r * 0.297361f + g * 0.627355f + b * 0.0752847f;
    *z = r * 0.0270328f + g * 0.0706879f + b * 0.991248f;
}

static void xyz_to_ab(float x, float y, float z, float *a, float *b)
{
    /* Computed per call (a few multiplies) rather than cached in a static,
     * which concurrent comparisons would race on. */
    float white[3];
    adobe_rgb_to_xyz(1, 1, 1, &white[0], &white[1], &white[2]);
    const float epsilon = 216.0f / 24389.0f, kappa = 24389.0f / 27.0f;
    float r[3] = {x / white[0], y / white[1], z / white[2]}, f[3];
    for (int i = 0; i < 3; i++)
        f[i] = r[i] > epsilon ? powf(r[i], 1.0f / 3.0f) : (kappa * r[i] + 16.0f) / 116.0f;
    *a = 500.0f * (f[0] - f[1]);
    *b = 200.0f * (f[1] - f[2]);
}

/* perceptualdiff's border rule (reflect about 0 on the left, about n - 0.5
 * on the right), repeated until the index lands inside: one reflection is
 * not enough when the image is narrower than the kernel (n < 3), and a
 * 1-pixel image maps everything to its only pixel. */
static int mirror(int v, int n)
{
    if (n <= 1)
        return 0;
    while (v < 0 || v >= n)
        v = v < 0 ? -v : 2 * n - v - 1;
    return v;
}

/* Tiles: TILE x TILE pixels judged at a time, with a halo of HALO pixels,
 * enough for the 7 blurs (2 pixels each) that build the top level. */
enum { TILE = 256, HALO = 2 * (LEVELS - 1) };

/* The extent of the tile starting at pos: the last one of a row or column
 * takes the rest, up to 1.5 tiles, so that no tile is narrower than its
 * halo (a mirrored halo at an image border reads across the tile). */
static int tile_span(int pos, int size)
{
    return size - pos <= TILE + TILE / 2 ? size - pos : TILE;
}

/* The widest tile_span over an extent of size. */
static int tile_max(int size)
{
    return size < TILE + TILE / 2 ? size : TILE + TILE / 2;
}

/* One tile's pyramids: plane l of image k at pyr[k][l], ew x eh floats
 * covering image columns ox .. ox + ew - 1 and rows oy .. oy + eh - 1. */
struct tile {
    int ox, oy, ew, eh;
    int w, h;        /* the image */
    float *pyr[2][LEVELS];
};

/* Out-of-image positions of a level copy the level at the mirrored
 * in-image position, exactly as the whole-image code reads them. */
static void refill_borders(const struct tile *t, float *p, int y0, int y1)
{
    int in_x0 = -t->ox > 0 ? -t->ox : 0, in_x1 = t->w - t->ox < t->ew ? t->w - t->ox : t->ew;
    int in_y0 = -t->oy > 0 ? -t->oy : 0, in_y1 = t->h - t->oy < t->eh ? t->h - t->oy : t->eh;
    for (int ey = y0; ey < y1; ey++) {
        if (ey < in_y0 || ey >= in_y1)
            continue;
        float *row = p + (size_t)ey * (size_t)t->ew;
        for (int ex = 0; ex < in_x0; ex++)
            row[ex] = row[mirror(t->ox + ex, t->w) - t->ox];
        for (int ex = in_x1; ex < t->ew; ex++)
            row[ex] = row[mirror(t->ox + ex, t->w) - t->ox];
    }
    for (int ey = 0; ey < t->eh; ey++)
        if (ey < in_y0 || ey >= in_y1)
            memcpy(p + (size_t)ey * (size_t)t->ew,
                   p + (size_t)(mirror(t->oy + ey, t->h) - t->oy) * (size_t)t->ew,
                   (size_t)t->ew * sizeof(float));
}

/* Level l+1 from level l over the window [x0, x1) x [y0, y1) of valid
 * values, which shrinks by the kernel's radius (2) on each side: the 5x5
 * kernel [0.05 0.25 0.4 0.25 0.05] x the same, applied as perceptualdiff's
 * LPyramid::convolve applies it, tap by tap in float (the weight kx * ky
 * times the value, x offsets outer, y offsets inner). */
METRICS_SIMD static void blur(float *dst, const float *src, int ew, int x0, int x1, int y0,
                              int y1)
{
    static const float k[5] = {0.05f, 0.25f, 0.4f, 0.25f, 0.05f};
    for (int y = y0 + 2; y < y1 - 2; y++) {
        float *out = dst + (size_t)y * (size_t)ew;
        for (int x = x0 + 2; x < x1 - 2; x++)
            out[x] = 0.0f;
        for (int i = 0; i < 5; i++)
            for (int j = 0; j < 5; j++) {
                const float w = k[i] * k[j];
                const float *in = src + (size_t)(y + j - 2) * (size_t)ew + (i - 2);
                for (int x = x0 + 2; x < x1 - 2; x++)
                    out[x] += w * in[x];
            }
    }
}

/* Builds both pyramids of the tile: level 0 (luminance) over the tile and
 * its halo, mirrored at the image's borders, then each level blurred from
 * the one below. Where the tile meets a border of the image, the halo is
 * refilled by mirroring after each blur, so the window of valid values only
 * shrinks on the sides that face other tiles. */
/* pow(c / 255 * alpha / 255, gamma) for every 8-bit value c: a row of 256
 * for each alpha when either image is translucent, else the one row of
 * alpha 255 (c / 255 * 1 is c / 255 exactly). */
struct linear_table {
    float *values;
    bool per_alpha;
};

/* The linear values of the 256 channel values at pixel px. */
static const float *linear_row(const struct linear_table *lt, const struct image *img, size_t px)
{
    return lt->per_alpha ? lt->values + 256 * (size_t)(img->alpha ? img->alpha[px] : 255)
                         : lt->values;
}

static bool same_pixel(const struct image *a, const struct image *b, size_t px)
{
    const uint8_t *p = a->rgb + px * 3, *q = b->rgb + px * 3;
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2] &&
           (a->alpha ? a->alpha[px] : 255) == (b->alpha ? b->alpha[px] : 255);
}

static void build_pyramids(struct tile *t, const struct image *img[2],
                           const struct linear_table *linear, float lum)
{
    for (int k = 0; k < 2; k++) {
        float *l0 = t->pyr[k][0];
        for (int ey = 0; ey < t->eh; ey++) {
            int y = mirror(t->oy + ey, t->h);
            for (int ex = 0; ex < t->ew; ex++) {
                int x = mirror(t->ox + ex, t->w);
                size_t px = (size_t)y * (size_t)t->w + (size_t)x;
                const uint8_t *p = img[k]->rgb + px * 3;
                const float *lin = linear_row(linear, img[k], px);
                float X, Y, Z;
                adobe_rgb_to_xyz(lin[p[0]], lin[p[1]], lin[p[2]], &X, &Y, &Z);
                l0[(size_t)ey * (size_t)t->ew + (size_t)ex] = Y * lum;
            }
        }
        bool left = t->ox < 0, right = t->ox + t->ew > t->w;
        bool top = t->oy < 0, bottom = t->oy + t->eh > t->h;
        int x0 = 0, x1 = t->ew, y0 = 0, y1 = t->eh;
        for (int l = 1; l < LEVELS; l++) {
            blur(t->pyr[k][l], t->pyr[k][l - 1], t->ew, x0, x1, y0, y1);
            x0 += 2, x1 -= 2, y0 += 2, y1 -= 2;
            refill_borders(t, t->pyr[k][l], y0, y1);
            if (left)
                x0 = 0;
            if (right)
                x1 = t->ew;
            if (top)
                y0 = 0;
            if (bottom)
                y1 = t->eh;
        }
    }
}

bool pdiff_compute(const struct image *a, const struct image *b,
                   const struct pdiff_options *o, const struct metrics_stop *stop,
                   struct pdiff_result *out, char *err, size_t errlen)
{
    return pdiff_compute_mask(a, b, o, stop, out, NULL, err, errlen);
}

bool pdiff_compute_mask(const struct image *a, const struct image *b,
                        const struct pdiff_options *o, const struct metrics_stop *stop,
                        struct pdiff_result *out, uint8_t *failing_mask, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    if (a->width != b->width || a->height != b->height) {
        snprintf(err, errlen, "pdiff: image sizes differ");
        return false;
    }
    int w = a->width, h = a->height;
    size_t n = (size_t)w * (size_t)h;
    /* Identical as perceptualdiff sees it: every byte of RGBA (an opaque
     * image's alpha is 255 everywhere, and png_read_rgba keeps no plane of
     * 255s, so one translucent and one opaque image always differ). */
    bool same_alpha = (!a->alpha && !b->alpha) ||
                      (a->alpha && b->alpha && memcmp(a->alpha, b->alpha, n) == 0);
    if (same_alpha && memcmp(a->rgb, b->rgb, n * 3) == 0) {
        out->pass = true;
        out->identical = true;
        return true;
    }
    /* Two pyramids of LEVELS planes, per tile. */
    struct tile t = {.w = w, .h = h};
    int tw_max = tile_max(w), th_max = tile_max(h);
    size_t plane = (size_t)(tw_max + 2 * HALO) * (size_t)(th_max + 2 * HALO);
    float *buf = malloc(plane * sizeof(float) * (2 * LEVELS));
    if (!buf) {
        snprintf(err, errlen, "pdiff: out of memory");
        return false;
    }
    for (int k = 0; k < 2; k++)
        for (int l = 0; l < LEVELS; l++)
            t.pyr[k][l] = buf + plane * (size_t)(k * LEVELS + l);
    /* The same float as computing pow per pixel, as perceptualdiff does. */
    struct linear_table linear = {.per_alpha = a->alpha || b->alpha};
    linear.values = malloc(sizeof(float) * 256 * (linear.per_alpha ? 256 : 1));
    if (!linear.values) {
        free(buf);
        snprintf(err, errlen, "pdiff: out of memory");
        return false;
    }
    for (int al = linear.per_alpha ? 0 : 255, row = 0; al < 256; al++, row++)
        for (int v = 0; v < 256; v++)
            linear.values[256 * row + v] = powf(v / 255.0f * (al / 255.0f), (float)o->gamma);
    const float lum = (float)o->luminance;

    /* Pixels spanning one degree at this field of view, and the pyramid level
     * whose blur matches that adaptation area. */
    float one_degree = 2.0f * tanf((float)o->fov * 0.5f * PI_F / 180.0f) * 180.0f / PI_F;
    float ppd = (float)w / one_degree;
    int adapt_level = 0;
    float npix = 1.0f;
    for (int i = 0; i < LEVELS; i++) {
        adapt_level = i;
        if (npix > one_degree)
            break;
        npix *= 2;
    }
    float cpd[LEVELS], f_freq[LEVELS - 2];
    cpd[0] = 0.5f * ppd;
    for (int i = 1; i < LEVELS; i++)
        cpd[i] = 0.5f * cpd[i - 1];
    float csf_max = csf(3.248f, 100.0f);
    for (int i = 0; i < LEVELS - 2; i++)
        f_freq[i] = csf_max / csf(cpd[i], 100.0f);

    const struct image *img[2] = {a, b};
    long failed = 0;
    for (int ty = 0, th; ty < h; ty += th) {
        th = tile_span(ty, h);
        for (int tx = 0, tw; tx < w; tx += tw) {
            tw = tile_span(tx, w);
            if (metrics_stopped(stop, err, errlen)) {
                free(buf);
                free(linear.values);
                return false;
            }
            t.ox = tx - HALO, t.oy = ty - HALO;
            t.ew = tw + 2 * HALO, t.eh = th + 2 * HALO;
            build_pyramids(&t, img, &linear, lum);
            for (int y = 0; y < th; y++)
                for (int x = 0; x < tw; x++) {
                    /* Identical colours give a zero luminance and colour difference,
                     * which pass both tests whatever the threshold: skip them. */
                    size_t src = (size_t)(ty + y) * (size_t)w + (size_t)(tx + x);
                    const uint8_t *p = a->rgb + src * 3, *q = b->rgb + src * 3;
                    if (same_pixel(a, b, src))
                        continue;
                    const float *lp = linear_row(&linear, a, src), *lq = linear_row(&linear, b, src);
                    size_t i = (size_t)(y + HALO) * (size_t)t.ew + (size_t)(x + HALO);
                    float *const *la = t.pyr[0], *const *lb = t.pyr[1];
                    float adapt = (la[adapt_level][i] + lb[adapt_level][i]) * 0.5f;
                    if (adapt < 1e-5f)
                        adapt = 1e-5f;
                    float sum_contrast = 0, factor = 0;
                    for (int l = 0; l < LEVELS - 2; l++) {
                        float n1 = fabsf(la[l][i] - la[l + 1][i]);
                        float n2 = fabsf(lb[l][i] - lb[l + 1][i]);
                        float numerator = n1 > n2 ? n1 : n2;
                        float d1 = fabsf(la[l + 2][i]), d2 = fabsf(lb[l + 2][i]);
                        float denominator = d1 > d2 ? d1 : d2;
                        if (denominator < 1e-5f)
                            denominator = 1e-5f;
                        float contrast = numerator / denominator;
                        factor += contrast * f_freq[l] * mask(contrast * csf(cpd[l], adapt));
                        sum_contrast += contrast;
                    }
                    if (sum_contrast < 1e-5f)
                        sum_contrast = 1e-5f;
                    factor /= sum_contrast;
                    factor = factor < 1.0f ? 1.0f : (factor > 10.0f ? 10.0f : factor);
                    float delta = fabsf(la[0][i] - lb[0][i]);
                    bool pass = delta <= factor * tvi(adapt);
                    if (!o->luminance_only) {
                        float color_scale = adapt < 10.0f ? 0.0f : (float)o->color_factor;
                        float X, Y, Z, aa, ab, ba, bb;
                        adobe_rgb_to_xyz(lp[p[0]], lp[p[1]], lp[p[2]], &X, &Y, &Z);
                        xyz_to_ab(X, Y, Z, &aa, &ab);
                        adobe_rgb_to_xyz(lq[q[0]], lq[q[1]], lq[q[2]], &X, &Y, &Z);
                        xyz_to_ab(X, Y, Z, &ba, &bb);
                        float da = aa - ba, db = ab - bb;
                        if ((da * da + db * db) * color_scale > factor)
                            pass = false;
                    }
                    failed += !pass;
                    if (failing_mask && !pass)
                        failing_mask[src] = 1;
                }
        }
    }
    free(buf);
    free(linear.values);
    out->failing_pixels = failed;
    out->pass = failed < o->threshold_pixels;
    return true;
}

size_t pdiff_memory_bytes(int width, int height)
{
    size_t tw = (size_t)tile_max(width) + 2 * HALO;
    size_t th = (size_t)tile_max(height) + 2 * HALO;
    /* The tile's pyramids, and the table of pow(c * alpha, gamma). */
    return tw * th * sizeof(float) * (2 * LEVELS) + 256 * 256 * sizeof(float);
}
