#ifndef SHADEBENCH_PNG_IO_H
#define SHADEBENCH_PNG_IO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct image {
    int width, height;
    uint8_t *rgb; /* width * height * 3, top row first */
};

/* Writes an 8-bit RGB PNG from RGBA pixels as glReadPixels returns them
 * (bottom row first). Writes to a temporary name and renames, so a reader
 * never sees half a file. */
bool png_write_gl_rgba(const char *path, const uint8_t *rgba, int width,
                       int height, char *err, size_t errlen);

/* Writes RGB pixels, top row first. */
bool png_write_rgb(const char *path, const struct image *img, char *err, size_t errlen);

/* Reads an 8-bit RGB or RGBA PNG (alpha dropped). Other formats are
 * rejected with a message. */
bool png_read_rgb(const char *path, struct image *out, char *err, size_t errlen);
void image_finish(struct image *img);

/* Encodes img, shrunk by a box filter to at most max_width pixels wide, as a
 * PNG in memory (for thumbnails in report pages). malloc'ed; NULL on failure. */
unsigned char *png_encode_thumbnail(const struct image *img, int max_width, size_t *len);

#endif
