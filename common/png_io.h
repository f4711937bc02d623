#ifndef SHADEBENCH_PNG_IO_H
#define SHADEBENCH_PNG_IO_H

/* PNG files in and out, 8-bit RGB in memory. GL-free; any thread. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

struct image {
    int width, height;
    uint8_t *rgb;   /* width * height * 3, top row first */
    uint8_t *alpha; /* width * height straight (not premultiplied) alpha, top row
                       first, or NULL: opaque. Only png_read_rgba keeps it; the
                       daemon's frames are opaque. */
};

/* Writes an 8-bit RGB PNG from RGBA pixels as glReadPixels returns them
 * (bottom row first). Writes to a temporary name and renames, so a reader
 * never sees half a file. */
bool png_write_gl_rgba(const char *path, const uint8_t *rgba, int width,
                       int height, char *err, size_t errlen);

/* Writes an RGB PNG whose rows come from row(ctx, y, rgb) (width * 3 bytes,
 * top row first), so that an image never has to exist whole in memory. */
typedef void (*png_row_fn)(void *ctx, int y, uint8_t *rgb);
bool png_write_by_rows(const char *path, int width, int height, png_row_fn row, void *ctx,
                    char *err, size_t errlen);

/* The largest image read or compared: 8192x8192, the largest frame a job can
 * render. Its RGB copy is 192 MiB. */
#define IMAGE_MAX_PIXELS (8192LL * 8192LL)

/* Reads an 8-bit RGB or RGBA PNG (alpha dropped). Other formats, and images
 * of more than max_pixels pixels (checked before anything is allocated), are
 * rejected with a message. png_read_rgb uses IMAGE_MAX_PIXELS. */
bool png_read_rgb_limit(const char *path, long long max_pixels, struct image *out, char *err,
                        size_t errlen);
bool png_read_rgb(const char *path, struct image *out, char *err, size_t errlen);
/* The same from an open stream (left open); path only names it in errors. */
bool png_read_rgb_stream(FILE *f, const char *path, long long max_pixels, struct image *out,
                         char *err, size_t errlen);
/* The same, keeping an RGBA PNG's alpha in img->alpha (NULL when every
 * pixel is opaque), for shadebench-compare: the metrics judge a translucent
 * image as perceptualdiff does, premultiplied by its alpha. */
bool png_read_rgba(const char *path, struct image *out, char *err, size_t errlen);
void image_finish(struct image *img);

/* Encodes img, shrunk by a box filter to at most max_width pixels wide, as a
 * PNG in memory (for thumbnails in report pages). malloc'ed; NULL on failure. */
unsigned char *png_encode_thumbnail(const struct image *img, int max_width, size_t *len);

#endif
