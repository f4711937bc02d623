/* The flicker measure and the supersampled reference's box filter
 * (daemon/quality/flicker.h) on synthetic frames. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/quality/flicker.h"
#include "tests/unit/check.h"

#define W 8
#define H 6
#define PIX (W * H)
#define K 5

/* A grey RGBA frame of level v (0 to 1). */
static void grey(uint8_t *f, double v)
{
    uint8_t b = (uint8_t)(v * 255.0 + 0.5);
    for (int i = 0; i < PIX; i++)
        f[i * 4] = f[i * 4 + 1] = f[i * 4 + 2] = b, f[i * 4 + 3] = 255;
}

static double run_flicker(const double *test, const double *ref, int n, struct flicker_result *r)
{
    static uint8_t t[K][PIX * 4], f[K][PIX * 4];
    for (int i = 0; i < n; i++)
        grey(t[i], test[i]), grey(f[i], ref[i]);
    flicker_init(r);
    for (int i = 1; i < n; i++)
        flicker_add(r, flicker_pair(t[i - 1], t[i], f[i - 1], f[i], PIX, 4));
    return r->mean;
}

static void test_measure(void)
{
    struct flicker_result r;
    /* A still image against itself, and against a still reference: 0. */
    double still[K] = {0.3, 0.3, 0.3, 0.3, 0.3};
    CHECK(run_flicker(still, still, K, &r) == 0.0);
    CHECK(r.pairs == K - 1 && r.max == 0.0);
    /* A reference fading 0 -> 1: following it exactly is 0, and so is
     * following it with a constant offset (a static error is not flicker). */
    double fade[K] = {0.0, 0.25, 0.5, 0.75, 1.0};
    double ramp[K] = {0.0, 0.2, 0.4, 0.6, 0.8}, offset[K] = {0.2, 0.4, 0.6, 0.8, 1.0};
    CHECK(run_flicker(fade, fade, K, &r) == 0.0);
    CHECK_NEAR(run_flicker(offset, ramp, K, &r), 0.0, 1e-12);
    /* Late but smooth (one frame behind) against a pop (held, then the
     * whole change at once): the pop scores worse, and its worst pair is
     * the jump. */
    double late[K] = {0.0, 0.0, 0.25, 0.5, 0.75};
    double pop[K] = {0.0, 0.0, 0.0, 0.0, 1.0};
    struct flicker_result rl, rp;
    double smooth = run_flicker(late, fade, K, &rl), popping = run_flicker(pop, fade, K, &rp);
    CHECK(smooth > 0.0);
    CHECK(popping > 2.0 * smooth);
    CHECK_NEAR(smooth, 0.0625, 0.005);
    CHECK_NEAR(popping, 0.375, 0.005);
    CHECK(rp.max_pair == K - 2);
    CHECK_NEAR(rp.max, 0.75, 0.005);
    /* A still technique against a still reference of another level: 0; a
     * technique that flickers against a still reference: its change. */
    double other[K] = {0.6, 0.6, 0.6, 0.6, 0.6};
    double blink[K] = {0.6, 0.4, 0.6, 0.4, 0.6};
    CHECK(run_flicker(other, still, K, &r) == 0.0);
    CHECK_NEAR(run_flicker(blink, still, K, &r), 0.2, 0.005);
    /* Symmetric in which sequence moves. */
    CHECK(run_flicker(blink, still, K, &r) == run_flicker(still, blink, K, &r));
    /* Only part of the image pops: its share of the pixels. */
    uint8_t a[PIX * 4], b[PIX * 4];
    grey(a, 0.0);
    grey(b, 0.0);
    for (int i = 0; i < PIX / 4; i++)
        b[i * 4] = b[i * 4 + 1] = b[i * 4 + 2] = 255;
    CHECK_NEAR(flicker_pair(a, b, a, a, PIX, 4), 0.25, 1e-9);
    /* RGB and RGBA agree; luma weights the channels. */
    uint8_t rgb0[3] = {0, 0, 0}, rgb1[3] = {255, 0, 0};
    CHECK_NEAR(flicker_pair(rgb0, rgb1, rgb0, rgb0, 1, 3), 0.299, 1e-9);
}

static void test_downsample(void)
{
    /* n == 1 copies. */
    uint8_t src[16 * 4], dst[16 * 4];
    for (int i = 0; i < 16 * 4; i++)
        src[i] = (uint8_t)(i * 7);
    flicker_box_downsample(src, 4, 4, 1, 4, dst);
    CHECK(memcmp(src, dst, sizeof(src)) == 0);
    /* A block of one colour stays that colour exactly, at every level. */
    for (int v = 0; v < 256; v++) {
        uint8_t blk[4 * 4 * 3], out[3];
        memset(blk, v, sizeof(blk));
        flicker_box_downsample(blk, 4, 4, 4, 3, out);
        CHECK(out[0] == v && out[1] == v && out[2] == v);
    }
    /* Half black, half white: the mean in linear light (0.5), encoded with
     * sRGB: 188, not the encoded mean 128. */
    uint8_t chk[2 * 2 * 4] = {0, 0, 0, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 255};
    uint8_t one[4];
    flicker_box_downsample(chk, 2, 2, 2, 4, one);
    CHECK(one[0] == 188 && one[1] == 188 && one[2] == 188 && one[3] == 255);
    /* Blocks land where they belong: a 6x4 image at n = 2 is 3x2, each
     * output pixel its own block's colour. */
    uint8_t big[6 * 4 * 3], small[3 * 2 * 3];
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 6; x++)
            for (int c = 0; c < 3; c++)
                big[(y * 6 + x) * 3 + c] = (uint8_t)(((y / 2) * 3 + x / 2) * 40 + c);
    flicker_box_downsample(big, 6, 4, 2, 3, small);
    int bad = 0;
    for (int i = 0; i < 6; i++)
        for (int c = 0; c < 3; c++)
            bad += small[i * 3 + c] != (uint8_t)(i * 40 + c);
    CHECK(bad == 0);
}

int main(void)
{
    test_measure();
    test_downsample();
    return check_finish("test_flicker");
}
