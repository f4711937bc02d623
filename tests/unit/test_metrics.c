#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/metrics.h"
#include "tests/unit/check.h"

static struct image make(int w, int h, uint8_t r, uint8_t g, uint8_t b)
{
    struct image img = {w, h, malloc((size_t)w * (size_t)h * 3), NULL};
    for (int i = 0; i < w * h; i++)
        img.rgb[i * 3] = r, img.rgb[i * 3 + 1] = g, img.rgb[i * 3 + 2] = b;
    return img;
}

static struct image copy(const struct image *src)
{
    struct image img = *src;
    img.rgb = malloc((size_t)src->width * (size_t)src->height * 3);
    memcpy(img.rgb, src->rgb, (size_t)src->width * (size_t)src->height * 3);
    return img;
}

/* A smooth test pattern with some structure. */
static struct image pattern(int w, int h)
{
    struct image img = make(w, h, 0, 0, 0);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            uint8_t *p = img.rgb + ((size_t)y * (size_t)w + (size_t)x) * 3;
            p[0] = (uint8_t)(128 + 100 * sin(x * 0.07));
            p[1] = (uint8_t)(128 + 100 * cos(y * 0.05));
            p[2] = (uint8_t)((x + y) % 256);
        }
    return img;
}

static struct image noisy(const struct image *src, int amplitude, unsigned seed)
{
    struct image img = copy(src);
    for (size_t i = 0; i < (size_t)src->width * (size_t)src->height * 3; i++) {
        seed = seed * 1103515245u + 12345u;
        int v = img.rgb[i] + (int)((seed >> 16) % (unsigned)(2 * amplitude + 1)) - amplitude;
        img.rgb[i] = (uint8_t)(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
    return img;
}

static void test_ssim(void)
{
    char err[256];
    struct ssim_result s;
    struct image a = pattern(64, 48), b = copy(&a);
    CHECK(ssim_compute(&a, &b, true, NULL, &s, err, sizeof(err)));
    CHECK(s.luma == 1.0 && s.rgb == 1.0 && s.min == 1.0);
    CHECK(s.map && s.map_w == 54 && s.map_h == 38);
    free(s.map);

    /* Flat images: only the luminance term is left (float accumulation: the
     * scikit-image agreement test bounds the error at 1e-4; flat images are
     * the worst case, measured at 3.4e-5). */
    struct image f1 = make(20, 20, 200, 200, 200), f2 = make(20, 20, 190, 190, 190);
    CHECK(ssim_compute(&f1, &f2, false, NULL, &s, err, sizeof(err)));
    double c1 = 2.55 * 2.55;
    CHECK_NEAR(s.luma, (2.0 * 200 * 190 + c1) / (200.0 * 200 + 190.0 * 190 + c1), 5e-5);

    /* Symmetric, and falling as the difference grows. */
    struct image n1 = noisy(&a, 5, 1), n2 = noisy(&a, 25, 2), n3 = noisy(&a, 80, 3);
    struct ssim_result s1, s2, s3, back;
    CHECK(ssim_compute(&a, &n1, false, NULL, &s1, err, sizeof(err)));
    CHECK(ssim_compute(&n1, &a, false, NULL, &back, err, sizeof(err)));
    CHECK_NEAR(s1.luma, back.luma, 1e-6);
    CHECK(ssim_compute(&a, &n2, false, NULL, &s2, err, sizeof(err)));
    CHECK(ssim_compute(&a, &n3, false, NULL, &s3, err, sizeof(err)));
    CHECK(1.0 > s1.luma && s1.luma > s2.luma && s2.luma > s3.luma);
    CHECK(s3.min <= s3.luma && s3.min_x >= 5 && s3.min_y >= 5);

    /* Smaller than the window, or sizes that differ: a clear error. */
    struct image tiny = make(10, 30, 1, 2, 3);
    CHECK(!ssim_compute(&tiny, &tiny, false, NULL, &s, err, sizeof(err)));
    CHECK(strstr(err, "smaller than the 11x11 window") != NULL);
    CHECK(!ssim_compute(&a, &f1, false, NULL, &s, err, sizeof(err)));
    free(a.rgb), free(b.rgb), free(f1.rgb), free(f2.rgb), free(n1.rgb), free(n2.rgb);
    free(n3.rgb), free(tiny.rgb);
}

static void test_psnr(void)
{
    char err[256];
    struct psnr_result p;
    struct image a = pattern(32, 32), b = copy(&a);
    CHECK(psnr_compute(&a, &b, &p, err, sizeof(err)));
    CHECK(p.identical && isinf(p.overall));
    for (size_t i = 0; i < 32 * 32 * 3; i++)
        b.rgb[i] = (uint8_t)(a.rgb[i] < 255 ? a.rgb[i] + 1 : a.rgb[i] - 1);
    CHECK(psnr_compute(&a, &b, &p, err, sizeof(err)));
    /* MSE 1: 10 log10(255^2) = 48.1308 dB. */
    CHECK(!p.identical);
    CHECK_NEAR(p.overall, 20.0 * log10(255.0), 1e-9);
    CHECK_NEAR(p.channel[1], 20.0 * log10(255.0), 1e-9);
    free(a.rgb), free(b.rgb);
}

static void test_pdiff(void)
{
    char err[256];
    struct pdiff_options o;
    pdiff_defaults(&o);
    CHECK(o.fov == 22.6 && o.threshold_pixels == 100 && o.gamma == 2.2 && o.luminance == 100);
    struct pdiff_result r;
    struct image a = pattern(128, 96), b = copy(&a);
    CHECK(pdiff_compute(&a, &b, &o, NULL, &r, err, sizeof(err)));
    CHECK(r.pass && r.failing_pixels == 0 && r.identical);

    /* One step of 8-bit rounding on some pixels: below threshold, passes. */
    for (size_t i = 0; i < 128 * 96 * 3; i += 7)
        b.rgb[i] = (uint8_t)(b.rgb[i] ? b.rgb[i] - 1 : 1);
    CHECK(pdiff_compute(&a, &b, &o, NULL, &r, err, sizeof(err)));
    CHECK(r.pass && r.failing_pixels < 100);

    /* A visible block: fails, and every failing pixel is counted. */
    struct image c = copy(&a);
    for (int y = 30; y < 70; y++)
        for (int x = 40; x < 90; x++) {
            uint8_t *p = c.rgb + ((size_t)y * 128 + (size_t)x) * 3;
            p[0] = 255, p[1] = 20, p[2] = 20;
        }
    CHECK(pdiff_compute(&a, &c, &o, NULL, &r, err, sizeof(err)));
    CHECK(!r.pass && r.failing_pixels >= 1000);
    long visible = r.failing_pixels;
    /* The pass rule is "fewer than threshold_pixels fail". */
    o.threshold_pixels = visible + 1;
    CHECK(pdiff_compute(&a, &c, &o, NULL, &r, err, sizeof(err)) && r.pass);
    o.threshold_pixels = visible;
    CHECK(pdiff_compute(&a, &c, &o, NULL, &r, err, sizeof(err)) && !r.pass);

    /* Fine noise is harder to see from farther away: a wider field of view
     * (more degrees across the same pixels) hides more of it. */
    pdiff_defaults(&o);
    struct image n = noisy(&a, 12, 9);
    struct pdiff_result near, far;
    o.fov = 5;
    CHECK(pdiff_compute(&a, &n, &o, NULL, &near, err, sizeof(err)));
    o.fov = 90;
    CHECK(pdiff_compute(&a, &n, &o, NULL, &far, err, sizeof(err)));
    CHECK(near.failing_pixels != far.failing_pixels);
    free(a.rgb), free(b.rgb), free(c.rgb), free(n.rgb);
}

/* Images narrower or lower than the 5-tap pyramid kernel: perceptualdiff's
 * mirror used to index -1 there, before the buffer on a 1-pixel-wide image
 * (the --enable-sanitizers build of this test stops on that read). A 1-row
 * image and the same row doubled blur to the same values, so every failing
 * pixel is counted twice in the doubled one. */
static void test_pdiff_tiny(void)
{
    char err[256];
    struct pdiff_options o;
    pdiff_defaults(&o);
    o.threshold_pixels = 1;
    struct pdiff_result r, r2;
    for (int w = 1; w <= 4; w++)
        for (int h = 1; h <= 4; h++) {
            struct image a = pattern(w, h), b = noisy(&a, 90, (unsigned)(w * 7 + h));
            CHECK(pdiff_compute(&a, &b, &o, NULL, &r, err, sizeof(err)));
            CHECK(r.failing_pixels >= 0 && r.failing_pixels <= (long)w * h);
            free(a.rgb), free(b.rgb);
        }
    for (int w = 1; w <= 64; w *= 4) {
        struct image a = pattern(w, 1), b = noisy(&a, 90, (unsigned)w);
        struct image a2 = make(w, 2, 0, 0, 0), b2 = make(w, 2, 0, 0, 0);
        for (int y = 0; y < 2; y++) {
            memcpy(a2.rgb + (size_t)y * (size_t)w * 3, a.rgb, (size_t)w * 3);
            memcpy(b2.rgb + (size_t)y * (size_t)w * 3, b.rgb, (size_t)w * 3);
        }
        CHECK(pdiff_compute(&a, &b, &o, NULL, &r, err, sizeof(err)));
        CHECK(pdiff_compute(&a2, &b2, &o, NULL, &r2, err, sizeof(err)));
        CHECK(r2.failing_pixels == 2 * r.failing_pixels);
        CHECK(w < 16 || r.failing_pixels > 0);
        free(a.rgb), free(b.rgb), free(a2.rgb), free(b2.rgb);
    }
}

static void test_flip(void)
{
    char err[256];
    struct flip_result f;
    CHECK_NEAR(flip_default_ppd(), 67.0206, 1e-3);
    struct image a = pattern(96, 64), b = copy(&a);
    CHECK(flip_compute(&a, &b, flip_default_ppd(), true, NULL, &f, err, sizeof(err)));
    CHECK(f.mean == 0.0 && f.max == 0.0 && f.map);
    free(f.map);

    /* Grows with the difference and stays in [0, 1]. */
    double last = 0;
    for (int amp = 4; amp <= 64; amp *= 4) {
        struct image n = noisy(&a, amp, (unsigned)amp);
        CHECK(flip_compute(&a, &n, flip_default_ppd(), false, NULL, &f, err, sizeof(err)));
        CHECK(f.mean > last && f.min >= 0.0 && f.max <= 1.0);
        CHECK(f.weighted_q1 <= f.weighted_median && f.weighted_median <= f.weighted_q3);
        last = f.mean;
        free(n.rgb);
    }
    /* Black against white is close to the largest error FLIP gives. */
    struct image black = make(32, 32, 0, 0, 0), white = make(32, 32, 255, 255, 255);
    CHECK(flip_compute(&black, &white, flip_default_ppd(), false, NULL, &f, err, sizeof(err)));
    CHECK(f.mean > 0.9 && f.max <= 1.0);
    CHECK(!flip_compute(&a, &black, flip_default_ppd(), false, NULL, &f, err, sizeof(err)));
    CHECK(!flip_compute(&a, &b, 0.0, false, NULL, &f, err, sizeof(err)));
    free(a.rgb), free(b.rgb), free(black.rgb), free(white.rgb);
}

int main(void)
{
    test_ssim();
    test_psnr();
    test_pdiff();
    test_pdiff_tiny();
    test_flip();
    return check_finish("test_metrics");
}
