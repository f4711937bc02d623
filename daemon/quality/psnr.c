#include <math.h>
#include <stdio.h>
#include <string.h>

#include "daemon/quality/metrics.h"

bool psnr_compute(const struct image *a, const struct image *b, struct psnr_result *out,
                  char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    if (a->width != b->width || a->height != b->height) {
        snprintf(err, errlen, "psnr: image sizes differ");
        return false;
    }
    size_t n = (size_t)a->width * (size_t)a->height;
    double se[3] = {0, 0, 0};
    for (size_t i = 0; i < n * 3; i++) {
        double d = (double)a->rgb[i] - (double)b->rgb[i];
        se[i % 3] += d * d;
    }
    /* PSNR = 10 log10(MAX^2 / MSE) with MAX = 255 for 8-bit samples. */
    double total = 0;
    for (int c = 0; c < 3; c++) {
        double mse = se[c] / (double)n;
        out->channel[c] = mse > 0 ? 10.0 * log10(255.0 * 255.0 / mse) : INFINITY;
        total += se[c];
    }
    out->mse = total / (3.0 * (double)n);
    out->identical = total == 0;
    out->overall = out->identical ? INFINITY : 10.0 * log10(255.0 * 255.0 / out->mse);
    return true;
}
