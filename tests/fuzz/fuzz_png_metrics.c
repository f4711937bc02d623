/* The PNG reader on any bytes, then every metric on what it decodes (against
 * a copy altered by the input's tail). Invariants: nothing crashes or
 * leaks; a refusal says why; the figures stay in their ranges; identical
 * images score as identical; a stop request ends each metric at once. */
#define _GNU_SOURCE /* fmemopen */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "common/png_io.h"
#include "daemon/quality/metrics.h"
#include "tests/fuzz/fuzz.h"

/* Small enough that every metric runs many times a second. */
enum { MAX_PIXELS = 96 * 96 };

static bool always(void *ctx)
{
    (void)ctx;
    return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    struct image ref;
    char err[512] = "";
    bool ok = png_read_rgb_stream(f, "input", MAX_PIXELS, &ref, err, sizeof(err));
    fclose(f);
    if (!ok) {
        FUZZ_ASSERT(err[0] != '\0' && ref.rgb == NULL);
        return 0;
    }
    FUZZ_ASSERT(ref.width > 0 && ref.height > 0 && (long long)ref.width * ref.height <= MAX_PIXELS);
    size_t n = (size_t)ref.width * (size_t)ref.height * 3;
    struct image test = ref;
    test.rgb = malloc(n);
    FUZZ_ASSERT(test.rgb != NULL);
    memcpy(test.rgb, ref.rgb, n);
    /* The last bytes of the input (inside the PNG's own tail) pick pixels to change. */
    for (size_t i = 0; i < 16 && i < size; i++)
        test.rgb[(data[size - 1 - i] * 131u + i * 977u) % n] ^= data[size - 1 - i] | 1;

    struct metrics_options o;
    metrics_options_defaults(&o);
    o.flip_ppd = 1.0 + (double)(data[0] % 200);
    o.pdiff.fov = 1.0 + (double)(data[size / 2] % 170);
    json_t *m = metrics_compare(&ref, &test, &o, NULL, NULL, NULL, err, sizeof(err));
    if (ref.width >= SSIM_WINDOW && ref.height >= SSIM_WINDOW) {
        FUZZ_ASSERT(m != NULL);
        double ssim = json_real_value(json_object_get(m, "ssim"));
        FUZZ_ASSERT(ssim >= -1.0 - 1e-6 && ssim <= 1.0 + 1e-6);
        json_t *flip = json_object_get(m, "flip");
        double fmin = json_real_value(json_object_get(flip, "min"));
        double fmax = json_real_value(json_object_get(flip, "max"));
        double fmean = json_real_value(json_object_get(flip, "mean"));
        FUZZ_ASSERT(fmin >= 0 && fmin <= fmean + 1e-12 && fmean <= fmax + 1e-12 && fmax <= 1.0);
        double q1 = json_real_value(json_object_get(flip, "weighted_q1"));
        double q3 = json_real_value(json_object_get(flip, "weighted_q3"));
        FUZZ_ASSERT(q1 <= q3 && q3 <= fmax);
        long failing = (long)json_integer_value(json_object_get(json_object_get(m, "pdiff"), "failing_pixels"));
        FUZZ_ASSERT(failing >= 0 && failing <= (long)ref.width * ref.height);
    } else {
        /* SSIM needs 11x11: the comparison is refused, the rest still run. */
        FUZZ_ASSERT(m == NULL && strstr(err, "smaller than") != NULL);
        struct pdiff_result p;
        FUZZ_ASSERT(pdiff_compute(&ref, &test, &o.pdiff, NULL, &p, err, sizeof(err)));
        FUZZ_ASSERT(p.failing_pixels >= 0 && p.failing_pixels <= (long)ref.width * ref.height);
        struct flip_result fr;
        FUZZ_ASSERT(flip_compute(&ref, &test, o.flip_ppd, false, NULL, &fr, err, sizeof(err)));
        FUZZ_ASSERT(fr.min >= 0 && fr.max <= 1.0);
    }
    json_decref(m);

    /* Identical images. */
    struct pdiff_result same;
    FUZZ_ASSERT(pdiff_compute(&ref, &ref, &o.pdiff, NULL, &same, err, sizeof(err)) && same.identical);
    struct psnr_result ps;
    FUZZ_ASSERT(psnr_compute(&ref, &ref, &ps, err, sizeof(err)) && ps.identical);
    struct flip_result fr;
    FUZZ_ASSERT(flip_compute(&ref, &ref, o.flip_ppd, true, NULL, &fr, err, sizeof(err)));
    FUZZ_ASSERT(fr.mean == 0.0 && fr.max == 0.0 && fr.map != NULL);
    free(fr.map);

    /* A stop request ends the comparison with "stopped". */
    struct metrics_stop stop = {always, NULL};
    if (ref.width >= SSIM_WINDOW && ref.height >= SSIM_WINDOW) {
        FUZZ_ASSERT(metrics_compare(&ref, &test, &o, NULL, NULL, &stop, err, sizeof(err)) == NULL);
        FUZZ_ASSERT(strcmp(err, "stopped") == 0);
    }
    image_finish(&test);
    image_finish(&ref);
    return 0;
}
