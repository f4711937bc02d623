/* Test helper: "png-tool info FILE" prints width, height and how many
 * distinct colours and non-black pixels it has; "png-tool diff A B" prints
 * per-channel mean absolute difference, the largest difference and the
 * count of differing pixels, as JSON. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/png_io.h"

static int info(const char *path)
{
    struct image img;
    char err[256];
    if (!png_read_rgb(path, &img, err, sizeof(err))) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    size_t n = (size_t)img.width * (size_t)img.height, lit = 0, distinct = 0;
    unsigned char *seen = calloc(1u << 21, 1);
    for (size_t i = 0; i < n; i++) {
        const unsigned char *p = img.rgb + i * 3;
        lit += p[0] || p[1] || p[2];
        unsigned key = ((unsigned)p[0] << 16 | (unsigned)p[1] << 8 | p[2]) >> 3;
        if (!(seen[key >> 3] & (1 << (key & 7)))) {
            seen[key >> 3] |= (unsigned char)(1 << (key & 7));
            distinct++;
        }
    }
    printf("{\"width\":%d,\"height\":%d,\"lit_pixels\":%zu,\"colours\":%zu}\n", img.width,
           img.height, lit, distinct);
    free(seen);
    image_finish(&img);
    return 0;
}

static int diff(const char *a_path, const char *b_path)
{
    struct image a, b;
    char err[256];
    if (!png_read_rgb(a_path, &a, err, sizeof(err)) || !png_read_rgb(b_path, &b, err, sizeof(err))) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    if (a.width != b.width || a.height != b.height) {
        fprintf(stderr, "size mismatch\n");
        return 2;
    }
    size_t n = (size_t)a.width * (size_t)a.height, differing = 0;
    double sum[3] = {0, 0, 0};
    int max = 0;
    for (size_t i = 0; i < n; i++) {
        int any = 0;
        for (int c = 0; c < 3; c++) {
            int d = abs((int)a.rgb[i * 3 + c] - (int)b.rgb[i * 3 + c]);
            sum[c] += d;
            max = d > max ? d : max;
            any |= d;
        }
        differing += any != 0;
    }
    printf("{\"mean_abs\":[%.6f,%.6f,%.6f],\"max_abs\":%d,\"differing_pixels\":%zu,"
           "\"pixels\":%zu}\n", sum[0] / n, sum[1] / n, sum[2] / n, max, differing, n);
    image_finish(&a);
    image_finish(&b);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "info") == 0)
        return info(argv[2]);
    if (argc == 4 && strcmp(argv[1], "diff") == 0)
        return diff(argv[2], argv[3]);
    fprintf(stderr, "usage: png-tool info FILE | png-tool diff A B\n");
    return 2;
}
