#define _POSIX_C_SOURCE 200809L
/* The images (convert_internal.h): signatures and sizes read from the
 * headers for the checks, and decoding with libpng and libjpeg from the
 * bytes the checks passed. */
#include "daemon/assets/convert_internal.h"

#include <jpeglib.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool is_png(struct span s)
{
    return s.len >= 24 && memcmp(s.data, "\x89PNG\r\n\x1a\n", 8) == 0;
}

bool is_jpeg(struct span s)
{
    return s.len >= 4 && s.data[0] == 0xFF && s.data[1] == 0xD8 && s.data[2] == 0xFF;
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* Width and height from the PNG IHDR or the first JPEG SOF marker. */
bool image_size(struct span s, uint32_t *w, uint32_t *h)
{
    if (is_png(s)) {
        if (memcmp(s.data + 12, "IHDR", 4) != 0)
            return false;
        *w = be32(s.data + 16);
        *h = be32(s.data + 20);
        return true;
    }
    size_t i = 2;
    while (i + 4 <= s.len) {
        if (s.data[i] != 0xFF)
            return false;
        uint8_t m = s.data[i + 1];
        if (m == 0xFF) {
            i++;
            continue;
        }
        if (m == 0xD8 || (m >= 0xD0 && m <= 0xD7) || m == 0x01) {
            i += 2;
            continue;
        }
        size_t seg = (size_t)s.data[i + 2] << 8 | s.data[i + 3];
        if (seg < 2)
            return false;
        bool sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
        if (sof) {
            if (i + 9 > s.len)
                return false;
            *h = (uint32_t)s.data[i + 5] << 8 | s.data[i + 6];
            *w = (uint32_t)s.data[i + 7] << 8 | s.data[i + 8];
            return true;
        }
        i += 2 + seg;
    }
    return false;
}
/* ---- images ---- */

static bool decode_png(struct ctx *c, struct span s, struct asset_image *im, const char *field)
{
    png_image p;
    memset(&p, 0, sizeof(p));
    p.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&p, s.data, (size_t)s.len))
        return fail(c, 400, field, "bad PNG: %s", p.message);
    p.format = PNG_FORMAT_RGBA;
    if (p.width != im->width || p.height != im->height) {
        png_image_free(&p);
        return fail(c, 400, field, "bad PNG: the size changed while reading");
    }
    /* Sized here in size_t: PNG_IMAGE_SIZE is 32-bit arithmetic. */
    im->rgba = malloc((size_t)im->width * im->height * 4);
    if (!im->rgba) {
        png_image_free(&p);
        return fail(c, 500, field, "out of memory");
    }
    if (!png_image_finish_read(&p, NULL, im->rgba, 0, NULL)) {
        png_image_free(&p);
        return fail(c, 400, field, "bad PNG: %s", p.message);
    }
    return true;
}

struct jpeg_err {
    struct jpeg_error_mgr mgr;
    jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

static void jpeg_fail(j_common_ptr cinfo)
{
    struct jpeg_err *e = (struct jpeg_err *)cinfo->err;
    cinfo->err->format_message(cinfo, e->message);
    longjmp(e->jump, 1);
}

static void jpeg_quiet(j_common_ptr cinfo, int level)
{
    (void)cinfo;
    (void)level;
}

static bool decode_jpeg(struct ctx *c, struct span s, struct asset_image *im, const char *field)
{
    struct jpeg_decompress_struct cinfo;
    struct jpeg_err jerr;
    memset(&cinfo, 0, sizeof(cinfo));
    cinfo.err = jpeg_std_error(&jerr.mgr);
    jerr.mgr.error_exit = jpeg_fail;
    jerr.mgr.emit_message = jpeg_quiet;
    jerr.message[0] = '\0';
    /* volatile: im->rgba is set after setjmp and freed on the longjmp path. */
    uint8_t *volatile rgba = NULL;
    if (setjmp(jerr.jump)) {
        jpeg_destroy_decompress(&cinfo);
        free(rgba);
        im->rgba = NULL;
        return fail(c, 400, field, "bad JPEG: %s", jerr.message);
    }
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, s.data, (unsigned long)s.len);
    jpeg_read_header(&cinfo, TRUE);
    if (cinfo.image_width != im->width || cinfo.image_height != im->height ||
        (cinfo.jpeg_color_space != JCS_GRAYSCALE && cinfo.jpeg_color_space != JCS_YCbCr &&
         cinfo.jpeg_color_space != JCS_RGB)) {
        jpeg_destroy_decompress(&cinfo);
        return fail(c, 400, field, "JPEG size or colour space (CMYK?) not supported");
    }
    cinfo.out_color_space = JCS_EXT_RGBA;
    jpeg_start_decompress(&cinfo);
    rgba = malloc((size_t)im->width * im->height * 4);
    if (!rgba) {
        jpeg_destroy_decompress(&cinfo);
        return fail(c, 500, field, "out of memory");
    }
    while (cinfo.output_scanline < cinfo.output_height) {
        JSAMPROW row = rgba + (size_t)cinfo.output_scanline * im->width * 4;
        jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    im->rgba = rgba;
    return true;
}

bool build_images(struct ctx *c, struct asset *a)
{
    if (!c->nimages)
        return true;
    if (!(a->images = calloc(c->nimages, sizeof(*a->images))))
        return fail(c, 500, "images", "out of memory");
    for (size_t i = 0; i < c->nimages; i++) {
        struct asset_image *im = &a->images[i];
        char field[64], fallback[32];
        snprintf(field, sizeof(field), "images[%zu]", i);
        snprintf(fallback, sizeof(fallback), "image%zu", i);
        copy_name(im->name, json_array_get(c->imgs, i), fallback);
        image_size(c->images[i], &im->width, &im->height);
        a->image_count = (uint32_t)i + 1;
        bool ok = is_png(c->images[i]) ? decode_png(c, c->images[i], im, field)
                                       : decode_jpeg(c, c->images[i], im, field);
        if (!ok)
            return false;
    }
    return true;
}
