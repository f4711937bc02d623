#define _POSIX_C_SOURCE 200809L
#include "daemon/scene/environment.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;
static const char MAGIC[8] = {'S', 'B', 'E', 'N', 'V', '0', '0', '1'};

void environment_limits_defaults(struct environment_limits *lim)
{
    /* 4096 x 2048 (8 Mi pixels, 96 MiB decoded, 128 MiB on the GPU with
     * its mipmaps) is plenty for lighting and a background: a run-length
     * coded file of one colour that size is a few kilobytes, so the decoded
     * size is what bounds the cache and the GPU memory an upload may take. */
    lim->max_edge = 8192;
    lim->max_pixels = 4096ull * 2048ull;
}

json_t *environment_limits_to_json(const struct environment_limits *lim)
{
    return json_pack("{s:I, s:I, s:I}", "max_environment_edge", (json_int_t)lim->max_edge,
                     "max_environment_pixels", (json_int_t)lim->max_pixels,
                     "max_environment_decoded_bytes", (json_int_t)(lim->max_pixels * 12));
}

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof(u));
    return u;
}

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof(f));
    return f;
}

bool environment_file_write(const struct environment_image *e, const char *path, char *err,
                            size_t errlen)
{
    FILE *f = fopen(path, "wb");
    if (!f) {
        snprintf(err, errlen, "cannot write %s: %s", path, strerror(errno));
        return false;
    }
    unsigned char head[16];
    memcpy(head, MAGIC, 8);
    put_u32(head + 8, e->width);
    put_u32(head + 12, e->height);
    bool ok = fwrite(head, 1, sizeof(head), f) == sizeof(head);
    size_t n = (size_t)e->width * e->height * 3;
    unsigned char buf[4096];
    size_t used = 0;
    for (size_t i = 0; ok && i < n; i++) {
        put_u32(buf + used, float_bits(e->rgb[i]));
        used += 4;
        if (used == sizeof(buf) || i + 1 == n) {
            ok = fwrite(buf, 1, used, f) == used;
            used = 0;
        }
    }
    ok = fclose(f) == 0 && ok;
    if (!ok)
        snprintf(err, errlen, "cannot write %s: %s", path, strerror(errno));
    return ok;
}

bool environment_file_is(const char *path)
{
    FILE *f = fopen(path, "rb");
    char head[8];
    bool is = f && fread(head, 1, 8, f) == 8 && memcmp(head, MAGIC, 8) == 0;
    if (f)
        fclose(f);
    return is;
}

bool environment_file_read(struct environment_image *e, const char *path,
                           const struct environment_limits *lim, char *err, size_t errlen)
{
    memset(e, 0, sizeof(*e));
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "cannot read %s: %s", path, strerror(errno));
        return false;
    }
    unsigned char head[16];
    bool ok = false;
    if (fread(head, 1, sizeof(head), f) != sizeof(head) || memcmp(head, MAGIC, 8) != 0) {
        snprintf(err, errlen, "%s is not an environment cache file", path);
        goto out;
    }
    uint32_t w = get_u32(head + 8), h = get_u32(head + 12);
    if (!w || !h || w > lim->max_edge || h > lim->max_edge ||
        (uint64_t)w * h > lim->max_pixels) {
        snprintf(err, errlen, "%s: %ux%u is outside the environment limits (edge %u, %llu "
                 "pixels)", path, w, h, lim->max_edge, (unsigned long long)lim->max_pixels);
        goto out;
    }
    size_t n = (size_t)w * h * 3;
    if (!(e->rgb = malloc(n * sizeof(float)))) {
        snprintf(err, errlen, "out of memory for a %ux%u environment", w, h);
        goto out;
    }
    unsigned char buf[4096];
    for (size_t i = 0; i < n;) {
        size_t want = (n - i) * 4 < sizeof(buf) ? (n - i) * 4 : sizeof(buf);
        if (fread(buf, 1, want, f) != want) {
            snprintf(err, errlen, "%s: the pixels end early", path);
            goto out;
        }
        for (size_t k = 0; k < want; k += 4, i++) {
            float v = bits_float(get_u32(buf + k));
            if (!isfinite(v) || v < 0) {
                snprintf(err, errlen, "%s: pixel value %zu is not finite and >= 0", path, i);
                goto out;
            }
            e->rgb[i] = v;
        }
    }
    if (fgetc(f) != EOF) {
        snprintf(err, errlen, "%s: bytes after the pixels", path);
        goto out;
    }
    e->width = w;
    e->height = h;
    ok = true;
out:
    fclose(f);
    if (!ok)
        environment_image_finish(e);
    return ok;
}

void environment_image_finish(struct environment_image *e)
{
    if (!e)
        return;
    free(e->rgb);
    memset(e, 0, sizeof(*e));
}

json_t *environment_describe(const struct environment_image *e, const char *format)
{
    /* Luminance (Rec. 709) weighted by each row's solid angle (cos of its
     * latitude), so that the mean is the map's mean radiance over the
     * sphere, the uniform environment it would equal. */
    double sum = 0, weight = 0, peak = 0;
    for (uint32_t y = 0; y < e->height; y++) {
        double lat = PI * (0.5 - (y + 0.5) / e->height), wrow = cos(lat);
        for (uint32_t x = 0; x < e->width; x++) {
            const float *p = &e->rgb[((size_t)y * e->width + x) * 3];
            double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            sum += l * wrow;
            weight += wrow;
            peak = l > peak ? l : peak;
        }
    }
    return json_pack("{s:s, s:s, s:i, s:i, s:I, s:I, s:{s:f, s:f}, s:s}", "kind", "environment",
                     "format", format, "width", (int)e->width, "height", (int)e->height,
                     "pixels", (json_int_t)((uint64_t)e->width * e->height), "decoded_bytes",
                     (json_int_t)((uint64_t)e->width * e->height * 12), "luminance", "mean",
                     weight > 0 ? sum / weight : 0.0, "peak", peak, "projection",
                     "equirectangular (row 0 the +y pole)");
}
