/* An uploaded Radiance .hdr into an environment image, and an image back
 * into a Radiance file: see env_convert.h.
 * The format (Greg Ward's RGBE, as stb_image reads it): text header lines
 * from "#?RADIANCE" (or "#?RGBE") to an empty line, then "-Y H +X W", then
 * H scanlines of W pixels, each either flat (4 bytes a pixel) or, when the
 * first one starts 2, 2, W >> 8, W & 255, run-length coded channel by
 * channel (a count byte over 128 is a run of one value, else that many
 * literal bytes). */
#define _POSIX_C_SOURCE 200809L
#include "daemon/assets/env_convert.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stb_image.h>

#include "daemon/assets/env_exr.h"

bool env_fail(struct asset_convert_error *e, int status, const char *field, const char *fmt, ...)
{
    e->status = status;
    snprintf(e->field, sizeof(e->field), "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->message, sizeof(e->message), fmt, ap);
    va_end(ap);
    return false;
}

static bool is_hdr(const uint8_t *data, size_t len)
{
    return len >= 2 && data[0] == '#' && data[1] == '?';
}

const char *env_convert_format(const uint8_t *data, size_t len)
{
    return is_hdr(data, len) ? "radiance_hdr" : env_exr_is(data, len) ? "openexr" : NULL;
}

/* One header line at *pos (without its newline) into line; false at the
 * end of data or past 512 bytes. */
static bool next_line(const uint8_t *data, size_t len, size_t *pos, char line[513])
{
    size_t n = 0;
    while (*pos < len && data[*pos] != '\n') {
        if (n == 512)
            return false;
        line[n++] = (char)data[(*pos)++];
    }
    if (*pos >= len)
        return false;
    (*pos)++;
    line[n] = '\0';
    return true;
}

/* The header: width, height and where the pixels start. */
static bool read_header(const uint8_t *data, size_t len, uint32_t *w, uint32_t *h,
                        size_t *start, struct asset_convert_error *e)
{
    char line[513];
    size_t pos = 0;
    if (!next_line(data, len, &pos, line) ||
        (strcmp(line, "#?RADIANCE") != 0 && strcmp(line, "#?RGBE") != 0))
        return env_fail(e, 422, "body", "not a Radiance HDR image: the first line must be "
                    "#?RADIANCE or #?RGBE");
    for (;;) {
        if (!next_line(data, len, &pos, line))
            return env_fail(e, 422, "body", "the Radiance header ends before its empty line (a "
                        "truncated file, or a header line over 512 bytes)");
        if (!line[0])
            break;
        if (strncmp(line, "FORMAT=", 7) == 0 && strcmp(line + 7, "32-bit_rle_rgbe") != 0)
            return env_fail(e, 422, "body", "FORMAT=%.64s: only 32-bit_rle_rgbe is read",
                        line + 7);
    }
    long hh = 0, ww = 0;
    char tail;
    if (!next_line(data, len, &pos, line) ||
        sscanf(line, "-Y %ld +X %ld%c", &hh, &ww, &tail) != 2)
        return env_fail(e, 422, "body", "the resolution line must be \"-Y height +X width\" (the "
                    "usual orientation; others are not read)");
    if (hh <= 0 || ww <= 0 || hh > 0x7fffffffL || ww > 0x7fffffffL)
        return env_fail(e, 422, "body", "the resolution line gives %ld x %ld pixels", ww, hh);
    *w = (uint32_t)ww;
    *h = (uint32_t)hh;
    *start = pos;
    return true;
}

/* Walks the pixel data; false naming the scanline where it ends early or
 * breaks. */
static bool walk_pixels(const uint8_t *data, size_t len, size_t pos, uint32_t w, uint32_t h,
                        struct asset_convert_error *e)
{
    bool rle = w >= 8 && w < 32768 && len - pos >= 4 && data[pos] == 2 &&
               data[pos + 1] == 2 && !(data[pos + 2] & 0x80) &&
               ((uint32_t)data[pos + 2] << 8 | data[pos + 3]) == w;
    for (uint32_t y = 0; y < h; y++) {
        if (!rle) {
            if (len - pos < (size_t)w * 4)
                return env_fail(e, 422, "body", "truncated: the pixels end in scanline %u of %u "
                            "(%zu bytes short)", y + 1, h, (size_t)w * 4 - (len - pos));
            pos += (size_t)w * 4;
            continue;
        }
        if (len - pos < 4)
            return env_fail(e, 422, "body", "truncated: the pixels end before scanline %u of %u",
                        y + 1, h);
        if (data[pos] != 2 || data[pos + 1] != 2 ||
            ((uint32_t)data[pos + 2] << 8 | data[pos + 3]) != w)
            return env_fail(e, 422, "body", "corrupt: scanline %u of %u does not start as a "
                        "run-length coded one", y + 1, h);
        pos += 4;
        for (int channel = 0; channel < 4; channel++)
            for (uint32_t x = 0; x < w;) {
                if (pos >= len)
                    return env_fail(e, 422, "body", "truncated: the pixels end in scanline %u of "
                                "%u", y + 1, h);
                unsigned count = data[pos++];
                bool run = count > 128;
                if (run)
                    count -= 128;
                if (count == 0 || x + count > w)
                    return env_fail(e, 422, "body", "corrupt: a run in scanline %u of %u goes past "
                                "its %u pixels", y + 1, h, w);
                size_t bytes = run ? 1 : count;
                if (len - pos < bytes)
                    return env_fail(e, 422, "body", "truncated: the pixels end in scanline %u of "
                                "%u", y + 1, h);
                pos += bytes;
                x += count;
            }
    }
    return true;
}

bool env_convert_buffer(const uint8_t *data, size_t len, const struct environment_limits *lim,
                        struct environment_image *out, struct asset_convert_error *e)
{
    if (env_exr_is(data, len))
        return env_exr_decode(data, len, lim, out, e);
    memset(out, 0, sizeof(*out));
    memset(e, 0, sizeof(*e));
    uint32_t w, h;
    size_t start;
    if (!read_header(data, len, &w, &h, &start, e))
        return false;
    /* The limits from the header, before a byte is decoded. */
    if (w > lim->max_edge || h > lim->max_edge)
        return env_fail(e, 422, "limits.max_environment_edge", "%u x %u pixels: an environment's "
                    "width and height must be at most %u", w, h, lim->max_edge);
    if ((uint64_t)w * h > lim->max_pixels)
        return env_fail(e, 422, "limits.max_environment_pixels", "%u x %u is %llu pixels (%llu "
                    "bytes decoded): the limit is %llu pixels", w, h,
                    (unsigned long long)w * h, (unsigned long long)w * h * 12,
                    (unsigned long long)lim->max_pixels);
    if (len > (size_t)0x7fffffff)
        return env_fail(e, 422, "body", "the file is over 2 GiB");
    if (!walk_pixels(data, len, start, w, h, e))
        return false;
    int x = 0, y = 0, comp = 0;
    float *rgb = stbi_loadf_from_memory(data, (int)len, &x, &y, &comp, 3);
    if (!rgb)
        return env_fail(e, 422, "body", "the Radiance image does not decode: %s",
                    stbi_failure_reason() ? stbi_failure_reason() : "unknown reason");
    if ((uint32_t)x != w || (uint32_t)y != h) {
        stbi_image_free(rgb);
        return env_fail(e, 422, "body", "the decoder read %d x %d pixels where the header says "
                    "%u x %u", x, y, w, h);
    }
    size_t n = (size_t)w * h * 3;
    if (!(out->rgb = malloc(n * sizeof(float)))) {
        stbi_image_free(rgb);
        return env_fail(e, 500, "body", "out of memory for %u x %u pixels", w, h);
    }
    for (size_t i = 0; i < n; i++)
        out->rgb[i] = isfinite(rgb[i]) && rgb[i] > 0 ? rgb[i] : 0.0f;
    stbi_image_free(rgb);
    out->width = w;
    out->height = h;
    return true;
}

/* One pixel as RGBE: the largest channel's exponent shared (frexp), each
 * mantissa to 8 bits, as Ward's float2rgbe. */
static void rgbe(const float *p, uint8_t out[4])
{
    float v = p[0] > p[1] ? p[0] : p[1];
    v = v > p[2] ? v : p[2];
    if (!(v > 1e-32f)) {
        memset(out, 0, 4);
        return;
    }
    int ex;
    float scale = frexpf(v, &ex) * 256.0f / v;
    for (int c = 0; c < 3; c++)
        out[c] = (uint8_t)(p[c] * scale);
    out[3] = (uint8_t)(ex + 128);
}

/* One channel of a scanline, run-length coded: runs of 3 or more equal
 * bytes as runs, the rest as literals (at most 128 a record). */
static void rle_channel(const uint8_t *v, uint32_t n, FILE *f)
{
    uint32_t i = 0;
    while (i < n) {
        uint32_t j = i;
        while (j < n && v[j] == v[i] && j - i < 127)
            j++;
        if (j - i >= 3) {
            fputc(128 + (int)(j - i), f);
            fputc(v[i], f);
            i = j;
            continue;
        }
        uint32_t k = i;
        while (k < n && k - i < 128 && !(k + 2 < n && v[k] == v[k + 1] && v[k] == v[k + 2]))
            k++;
        fputc((int)(k - i), f);
        fwrite(v + i, 1, k - i, f);
        i = k;
    }
}

bool env_convert_write_radiance(const struct environment_image *img, const char *path, char *err,
                                size_t errlen)
{
    FILE *f = fopen(path, "wb");
    uint8_t *line = malloc((size_t)img->width * 4), *chan = malloc(img->width);
    if (!f || !line || !chan) {
        snprintf(err, errlen, "cannot write %s: %s", path, f ? "out of memory" : strerror(errno));
        if (f)
            fclose(f);
        free(line);
        free(chan);
        return false;
    }
    fprintf(f, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %u +X %u\n", img->height, img->width);
    bool rle = img->width >= 8 && img->width < 32768;
    for (uint32_t y = 0; y < img->height; y++) {
        for (uint32_t x = 0; x < img->width; x++)
            rgbe(img->rgb + ((size_t)y * img->width + x) * 3, line + (size_t)x * 4);
        if (!rle) {
            fwrite(line, 4, img->width, f);
            continue;
        }
        uint8_t head[4] = {2, 2, (uint8_t)(img->width >> 8), (uint8_t)(img->width & 255)};
        fwrite(head, 1, 4, f);
        for (int c = 0; c < 4; c++) {
            for (uint32_t x = 0; x < img->width; x++)
                chan[x] = line[(size_t)x * 4 + (size_t)c];
            rle_channel(chan, img->width, f);
        }
    }
    free(line);
    free(chan);
    bool ok = fflush(f) == 0 && !ferror(f) && fsync(fileno(f)) == 0;
    ok = fclose(f) == 0 && ok;
    if (!ok)
        snprintf(err, errlen, "cannot write %s: %s", path, strerror(errno));
    return ok;
}
