#define _POSIX_C_SOURCE 200809L
#include "common/png_io.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool write_rows(const char *path, png_bytep *rows, int width, int height,
                       char *err, size_t errlen)
{
    char tmp[4096];
    snprintf(tmp, sizeof(tmp), "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        snprintf(err, errlen, "cannot write %s: %s", tmp, strerror(errno));
        return false;
    }
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        snprintf(err, errlen, "libpng failed writing %s", path);
        png_destroy_write_struct(&png, &info);
        fclose(f);
        remove(tmp);
        return false;
    }
    png_init_io(png, f);
    /* Captures are written once and read often; fast filtering, modest zlib level. */
    png_set_compression_level(png, 3);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    if (fclose(f) != 0 || rename(tmp, path) != 0) {
        snprintf(err, errlen, "cannot finish %s: %s", path, strerror(errno));
        remove(tmp);
        return false;
    }
    return true;
}

bool png_write_gl_rgba(const char *path, const uint8_t *rgba, int width,
                       int height, char *err, size_t errlen)
{
    uint8_t *rgb = malloc((size_t)width * (size_t)height * 3);
    png_bytep *rows = malloc((size_t)height * sizeof(*rows));
    bool ok = false;
    if (!rgb || !rows) {
        snprintf(err, errlen, "out of memory encoding %s", path);
        goto out;
    }
    for (int y = 0; y < height; y++) {
        const uint8_t *src = rgba + (size_t)(height - 1 - y) * (size_t)width * 4;
        uint8_t *dst = rgb + (size_t)y * (size_t)width * 3;
        for (int x = 0; x < width; x++) {
            dst[x * 3 + 0] = src[x * 4 + 0];
            dst[x * 3 + 1] = src[x * 4 + 1];
            dst[x * 3 + 2] = src[x * 4 + 2];
        }
        rows[y] = dst;
    }
    ok = write_rows(path, rows, width, height, err, errlen);
out:
    free(rows);
    free(rgb);
    return ok;
}

bool png_write_rgb(const char *path, const struct image *img, char *err, size_t errlen)
{
    png_bytep *rows = malloc((size_t)img->height * sizeof(*rows));
    if (!rows) {
        snprintf(err, errlen, "out of memory encoding %s", path);
        return false;
    }
    for (int y = 0; y < img->height; y++)
        rows[y] = img->rgb + (size_t)y * (size_t)img->width * 3;
    bool ok = write_rows(path, rows, img->width, img->height, err, errlen);
    free(rows);
    return ok;
}

bool png_read_rgb(const char *path, struct image *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open", path);
        return false;
    }
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    png_bytep *rows = NULL;
    uint8_t *rgba = NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        snprintf(err, errlen, "%s: not a readable PNG", path);
        goto fail;
    }
    png_init_io(png, f);
    png_read_info(png, info);
    int depth = png_get_bit_depth(png, info), type = png_get_color_type(png, info);
    if (depth != 8 || (type != PNG_COLOR_TYPE_RGB && type != PNG_COLOR_TYPE_RGBA)) {
        snprintf(err, errlen, "%s: must be 8-bit RGB or RGBA (bit depth %d, colour type %d)",
                 path, depth, type);
        goto fail;
    }
    int w = (int)png_get_image_width(png, info), h = (int)png_get_image_height(png, info);
    int channels = type == PNG_COLOR_TYPE_RGBA ? 4 : 3;
    rgba = malloc((size_t)w * (size_t)h * (size_t)channels);
    rows = malloc((size_t)h * sizeof(*rows));
    out->rgb = malloc((size_t)w * (size_t)h * 3);
    if (!rgba || !rows || !out->rgb) {
        snprintf(err, errlen, "%s: out of memory", path);
        goto fail;
    }
    for (int y = 0; y < h; y++)
        rows[y] = rgba + (size_t)y * (size_t)w * (size_t)channels;
    png_read_image(png, rows);
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++)
        memcpy(out->rgb + i * 3, rgba + i * (size_t)channels, 3);
    out->width = w;
    out->height = h;
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    free(rgba);
    fclose(f);
    return true;
fail:
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    free(rgba);
    image_finish(out);
    fclose(f);
    return false;
}

void image_finish(struct image *img)
{
    if (!img)
        return;
    free(img->rgb);
    memset(img, 0, sizeof(*img));
}

struct mem_sink {
    unsigned char *data;
    size_t len, cap;
    bool failed;
};

static void mem_write(png_structp png, png_bytep data, png_size_t length)
{
    struct mem_sink *m = png_get_io_ptr(png);
    if (m->len + length > m->cap) {
        size_t cap = (m->len + length) * 2;
        unsigned char *grown = realloc(m->data, cap);
        if (!grown) {
            m->failed = true;
            return;
        }
        m->data = grown;
        m->cap = cap;
    }
    memcpy(m->data + m->len, data, length);
    m->len += length;
}

static void mem_flush(png_structp png) { (void)png; }

unsigned char *png_encode_thumbnail(const struct image *img, int max_width, size_t *len)
{
    int factor = 1;
    while (img->width / factor > max_width)
        factor++;
    int w = img->width / factor, h = img->height / factor;
    if (w < 1 || h < 1)
        return NULL;
    uint8_t *small = malloc((size_t)w * (size_t)h * 3);
    png_bytep *rows = malloc((size_t)h * sizeof(*rows));
    struct mem_sink sink = {0};
    png_structp png = NULL;
    png_infop info = NULL;
    if (!small || !rows)
        goto fail;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) {
                unsigned sum = 0;
                for (int dy = 0; dy < factor; dy++)
                    for (int dx = 0; dx < factor; dx++)
                        sum += img->rgb[((size_t)(y * factor + dy) * (size_t)img->width +
                                         (size_t)(x * factor + dx)) * 3 + (size_t)c];
                small[((size_t)y * (size_t)w + (size_t)x) * 3 + (size_t)c] =
                    (uint8_t)(sum / (unsigned)(factor * factor));
            }
        rows[y] = small + (size_t)y * (size_t)w * 3;
    }
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png)))
        goto fail;
    png_set_write_fn(png, &sink, mem_write, mem_flush);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(rows);
    free(small);
    if (sink.failed) {
        free(sink.data);
        return NULL;
    }
    *len = sink.len;
    return sink.data;
fail:
    png_destroy_write_struct(&png, &info);
    free(rows);
    free(small);
    free(sink.data);
    return NULL;
}
