#define _POSIX_C_SOURCE 200809L /* mkdtemp */
/* The PNG reader on damaged and oversized files: every one is refused with
 * a message and nothing leaks (the sanitizer build checks the leaks, clang's
 * included, where a non-volatile local would lose its buffer after libpng's
 * longjmp). Also checks the row-streaming writer against the reader. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/png_io.h"
#include "tests/unit/check.h"

static char dir[] = "/tmp/test_png.XXXXXX";

static void path_of(char *out, size_t cap, const char *name)
{
    snprintf(out, cap, "%s/%s", dir, name);
}

static void spill(const char *path, const unsigned char *buf, size_t len)
{
    FILE *f = fopen(path, "wb");
    fwrite(buf, 1, len, f);
    fclose(f);
}

static void put32(unsigned char *p, unsigned long v)
{
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

static unsigned long crc(const unsigned char *p, size_t n)
{
    unsigned long c = 0xffffffffUL;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = c & 1 ? 0xedb88320UL ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xffffffffUL;
}

/* Rewrites IHDR's width and height and fixes its CRC, so that only the
 * declared size is wrong. */
static void set_size(unsigned char *png, unsigned long w, unsigned long h)
{
    put32(png + 16, w);
    put32(png + 20, h);
    put32(png + 29, crc(png + 12, 17));
}

static void refused(const char *name, const unsigned char *buf, size_t len, const char *why)
{
    char path[256], err[512] = "";
    path_of(path, sizeof(path), name);
    spill(path, buf, len);
    struct image img;
    bool ok = png_read_rgb(path, &img, err, sizeof(err));
    CHECK(!ok);
    CHECK(img.rgb == NULL && img.width == 0);
    CHECK(strstr(err, why) != NULL);
    if (ok || !strstr(err, why))
        fprintf(stderr, "%s: %s\n", name, err);
    if (ok)
        image_finish(&img);
}

static void row_of(void *ctx, int y, uint8_t *rgb)
{
    int w = *(int *)ctx;
    for (int x = 0; x < w; x++)
        rgb[x * 3] = (uint8_t)x, rgb[x * 3 + 1] = (uint8_t)y, rgb[x * 3 + 2] = (uint8_t)(x ^ y);
}

int main(void)
{
    if (!mkdtemp(dir))
        return 1;
    char path[256], err[512];
    int w = 37, h = 23;
    path_of(path, sizeof(path), "good.png");
    CHECK(png_write_by_rows(path, w, h, row_of, &w, err, sizeof(err)));
    struct image img;
    CHECK(png_read_rgb(path, &img, err, sizeof(err)));
    CHECK(img.width == w && img.height == h);
    bool same = img.rgb != NULL;
    for (int y = 0; same && y < h; y++)
        for (int x = 0; x < w; x++) {
            const uint8_t *p = img.rgb + ((size_t)y * (size_t)w + (size_t)x) * 3;
            same = same && p[0] == (uint8_t)x && p[1] == (uint8_t)y && p[2] == (uint8_t)(x ^ y);
        }
    CHECK(same);
    image_finish(&img);

    size_t len = 0;
    unsigned char *good = check_slurp(path, &len);
    CHECK(good && len > 60);
    unsigned char *bad = malloc(len);

    /* Cut inside the image data: the reader has allocated by then. */
    refused("truncated.png", good, len - 20, "not a readable PNG");
    refused("header-only.png", good, 40, "not a readable PNG");
    refused("empty.png", good, 0, "not a readable PNG");
    /* Image data that is not zlib. */
    memcpy(bad, good, len);
    for (size_t i = 45; i < len - 16; i++)
        bad[i] ^= 0x5a;
    refused("garbage.png", bad, len, "not a readable PNG");
    /* A larger size than the data holds: libpng fails mid-image. */
    memcpy(bad, good, len);
    set_size(bad, 37, 2000);
    refused("short-data.png", bad, len, "not a readable PNG");
    /* A huge declared image in a tiny file: refused before any allocation. */
    memcpy(bad, good, len);
    set_size(bad, 65536, 65536);
    refused("huge.png", bad, len, "over the limit");
    memcpy(bad, good, len);
    set_size(bad, 8193, 8192);
    refused("just-over.png", bad, len, "over the limit");

    /* The limit itself is a parameter. */
    CHECK(!png_read_rgb_limit(path, (long long)w * h - 1, &img, err, sizeof(err)));
    CHECK(strstr(err, "over the limit") != NULL);
    CHECK(png_read_rgb_limit(path, (long long)w * h, &img, err, sizeof(err)));
    image_finish(&img);

    free(good);
    free(bad);
    char cmd[300];
    snprintf(cmd, sizeof(cmd), "rm -rf %s", dir);
    CHECK(system(cmd) == 0);
    return check_finish("test_png");
}
