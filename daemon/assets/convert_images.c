#define _POSIX_C_SOURCE 200809L
/* The images (convert_internal.h): signatures and sizes read from the
 * headers for the checks, and decoding with libpng and libjpeg from the
 * bytes the checks passed. */
#include "daemon/assets/convert_internal.h"

#include <jpeglib.h>
/* After jpeglib.h, which it needs. */
#include <jerror.h>
#include <png.h>
#include <inttypes.h>
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

/* The first JPEG frame header (SOFn): its marker, height and width. */
static bool jpeg_frame(struct span s, uint8_t *marker, uint32_t *w, uint32_t *h)
{
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
            *marker = m;
            *h = (uint32_t)s.data[i + 5] << 8 | s.data[i + 6];
            *w = (uint32_t)s.data[i + 7] << 8 | s.data[i + 8];
            return true;
        }
        i += 2 + seg;
    }
    return false;
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
    uint8_t marker;
    return jpeg_frame(s, &marker, w, h);
}

/* deflate's best ratio (a run of one byte: 258 bytes a 2-bit code, plus the
 * block headers): no honest PNG holds more raw bytes per stored byte. */
#define DEFLATE_MAX_RATIO 1032

bool image_size_honest(struct span s, uint32_t w, uint32_t h, char *why, size_t cap)
{
    uint64_t can_hold; /* pixels the bytes can hold, as a width at most w */
    if (is_png(s)) {
        /* The filtered rows: a filter byte and the row's bits, each row. */
        uint8_t depth = s.len > 24 ? s.data[24] : 8, type = s.len > 25 ? s.data[25] : 6;
        unsigned channels = type == 2 ? 3 : type == 4 ? 2 : type == 6 ? 4 : 1;
        uint64_t row = 1 + ((uint64_t)w * channels * (depth ? depth : 8) + 7) / 8;
        uint64_t raw = row * h, most = s.len * (uint64_t)DEFLATE_MAX_RATIO;
        if (raw <= most)
            return true;
        can_hold = most / row * w;
        snprintf(why, cap, "the PNG's header says %ux%u, but its %" PRIu64 " bytes can inflate "
                 "to at most %" PRIu64 " of its %" PRIu64 " bytes of rows (deflate's best is "
                 "%d:1): about %" PRIu64 " pixels", w, h, s.len, most, raw, DEFLATE_MAX_RATIO,
                 can_hold);
        return false;
    }
    uint8_t marker = 0;
    uint32_t fw, fh;
    if (!jpeg_frame(s, &marker, &fw, &fh))
        return true; /* image_size refuses it */
    /* Arithmetic coding (SOF9 and up) could describe a flat image of any
     * size in a few bytes, lossless and hierarchical frames are not what
     * glTF viewers read: baseline, extended and progressive Huffman only. */
    if (marker != 0xC0 && marker != 0xC1 && marker != 0xC2) {
        snprintf(why, cap, "JPEG frame type SOF%d is not supported (baseline and progressive "
                 "Huffman-coded JPEG only, as browsers read them)", marker - 0xC0);
        return false;
    }
    /* Huffman coding spends at least one bit on each 8x8 block's DC term,
     * in every frame type it has, and the component of the largest
     * sampling factors has a block for each 8x8 pixels. */
    uint64_t blocks = ((uint64_t)w + 7) / 8 * (((uint64_t)h + 7) / 8);
    if (blocks <= s.len * 8)
        return true;
    snprintf(why, cap, "the JPEG's header says %ux%u (%" PRIu64 " blocks of 8x8), but its %"
             PRIu64 " bytes can code at most %" PRIu64 " blocks (a bit each at the least)", w, h,
             blocks, s.len, s.len * 8);
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

/* Warnings are quiet, but for data that ends before the image does:
 * libjpeg would pad the missing scans and hand back a whole image of what
 * the file never held. */
static void jpeg_quiet(j_common_ptr cinfo, int level)
{
    int code = cinfo->err->msg_code;
    if (level < 0 && (code == JWRN_JPEG_EOF || code == JWRN_HIT_MARKER))
        jpeg_fail(cinfo);
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
