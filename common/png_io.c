#define _POSIX_C_SOURCE 200809L
#include "common/png_io.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* libpng reports errors through a callback that must not return: keep the
 * message for the caller and jump back to the setjmp of the current call. */
struct png_errors {
    char message[200];
};

static void on_png_error(png_structp png, png_const_charp msg)
{
    struct png_errors *e = png_get_error_ptr(png);
    if (e)
        snprintf(e->message, sizeof(e->message), "%s", msg);
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp msg)
{
    (void)png, (void)msg; /* warnings never stop a read or a write */
}

bool png_write_by_rows(const char *path, int width, int height, png_row_fn row, void *ctx,
                    char *err, size_t errlen)
{
    char tmp[4096];
    snprintf(tmp, sizeof(tmp), "%s.tmp", path);
    struct png_errors perr = {""};
    uint8_t *line = malloc((size_t)width * 3);
    FILE *f = line ? fopen(tmp, "wb") : NULL;
    if (!f) {
        if (line)
            snprintf(err, errlen, "cannot write %s: %s", tmp, strerror(errno));
        else
            snprintf(err, errlen, "out of memory encoding %s", tmp);
        free(line);
        return false;
    }
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &perr, on_png_error,
                                              on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        snprintf(err, errlen, "libpng failed writing %s%s%s", path, perr.message[0] ? ": " : "",
                 perr.message);
        png_destroy_write_struct(&png, &info);
        fclose(f);
        remove(tmp);
        free(line);
        return false;
    }
    png_init_io(png, f);
    /* Captures are written once and read often; fast filtering, modest zlib level. */
    png_set_compression_level(png, 3);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < height; y++) {
        row(ctx, y, line);
        png_write_row(png, line);
    }
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(line);
    if (fclose(f) != 0 || rename(tmp, path) != 0) {
        snprintf(err, errlen, "cannot finish %s: %s", path, strerror(errno));
        remove(tmp);
        return false;
    }
    return true;
}

struct gl_rows {
    const uint8_t *rgba;
    int width, height;
};

static void gl_row(void *ctx, int y, uint8_t *rgb)
{
    const struct gl_rows *g = ctx;
    const uint8_t *src = g->rgba + (size_t)(g->height - 1 - y) * (size_t)g->width * 4;
    for (int x = 0; x < g->width; x++) {
        rgb[x * 3 + 0] = src[x * 4 + 0];
        rgb[x * 3 + 1] = src[x * 4 + 1];
        rgb[x * 3 + 2] = src[x * 4 + 2];
    }
}

bool png_write_gl_rgba(const char *path, const uint8_t *rgba, int width,
                       int height, char *err, size_t errlen)
{
    struct gl_rows g = {rgba, width, height};
    return png_write_by_rows(path, width, height, gl_row, &g, err, errlen);
}

static bool read_stream(FILE *f, const char *path, long long max_pixels, bool keep_alpha,
                        struct image *out, char *err, size_t errlen);

bool png_read_rgb_limit(const char *path, long long max_pixels, struct image *out, char *err,
                        size_t errlen)
{
    memset(out, 0, sizeof(*out));
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open", path);
        return false;
    }
    bool ok = png_read_rgb_stream(f, path, max_pixels, out, err, errlen);
    fclose(f);
    return ok;
}

bool png_read_rgb_stream(FILE *f, const char *path, long long max_pixels, struct image *out,
                         char *err, size_t errlen)
{
    return read_stream(f, path, max_pixels, false, out, err, errlen);
}

bool png_read_rgba(const char *path, struct image *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open", path);
        return false;
    }
    bool ok = read_stream(f, path, IMAGE_MAX_PIXELS, true, out, err, errlen);
    fclose(f);
    return ok;
}

/* Splits RGBA pixels, in place, into RGB (the buffer's first 3 n bytes) and
 * alpha: pixel i's colour moves to 3 i, at or before where it was (4 i), so
 * that no pixel is overwritten before it is read. Returns the alpha plane,
 * or NULL when every pixel is opaque (or out of memory: *oom set). */
static uint8_t *split_alpha(uint8_t *rgba, size_t n, bool *oom)
{
    bool opaque = true;
    for (size_t i = 0; i < n && opaque; i++)
        opaque = rgba[4 * i + 3] == 255;
    uint8_t *alpha = opaque ? NULL : malloc(n ? n : 1);
    *oom = !opaque && !alpha;
    for (size_t i = 0; i < n; i++) {
        if (alpha)
            alpha[i] = rgba[4 * i + 3];
        memmove(rgba + 3 * i, rgba + 4 * i, 3);
    }
    return alpha;
}

static bool read_stream(FILE *f, const char *path, long long max_pixels, bool keep_alpha,
                        struct image *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    struct png_errors perr = {""};
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &perr, on_png_error,
                                             on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    /* Assigned after setjmp and read after a longjmp back to it: volatile,
     * or an optimising compiler may hand the error path a stale copy (NULL)
     * and leak the buffer. */
    png_bytep *volatile rows = NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        snprintf(err, errlen, "%s: not a readable PNG%s%s", path, perr.message[0] ? ": " : "",
                 perr.message);
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
    png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    /* Before any allocation: a small file can declare a huge image. */
    if ((long long)w * (long long)h > max_pixels) {
        snprintf(err, errlen, "%s: %ux%u is %lld pixels, over the limit of %lld", path,
                 (unsigned)w, (unsigned)h, (long long)w * (long long)h, max_pixels);
        goto fail;
    }
    bool rgba = type == PNG_COLOR_TYPE_RGBA && keep_alpha;
    if (type == PNG_COLOR_TYPE_RGBA && !keep_alpha)
        png_set_strip_alpha(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    size_t channels = rgba ? 4 : 3;
    rows = malloc((size_t)h * sizeof(*rows));
    out->rgb = malloc((size_t)w * (size_t)h * channels);
    if (!rows || !out->rgb) {
        snprintf(err, errlen, "%s: out of memory", path);
        goto fail;
    }
    for (png_uint_32 y = 0; y < h; y++)
        rows[y] = out->rgb + (size_t)y * (size_t)w * channels;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    if (rgba) {
        bool oom;
        out->alpha = split_alpha(out->rgb, (size_t)w * (size_t)h, &oom);
        uint8_t *shrunk = realloc(out->rgb, (size_t)w * (size_t)h * 3 + 1);
        if (shrunk)
            out->rgb = shrunk;
        if (oom) {
            snprintf(err, errlen, "%s: out of memory", path);
            goto fail;
        }
    }
    out->width = (int)w;
    out->height = (int)h;
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    return true;
fail:
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    image_finish(out);
    return false;
}

bool png_read_rgb(const char *path, struct image *out, char *err, size_t errlen)
{
    return png_read_rgb_limit(path, IMAGE_MAX_PIXELS, out, err, errlen);
}

void image_finish(struct image *img)
{
    if (!img)
        return;
    free(img->rgb);
    free(img->alpha);
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
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, on_png_error, on_png_warning);
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
