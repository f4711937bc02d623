#ifndef SHADEBENCH_GHOSTING_H
#define SHADEBENCH_GHOSTING_H

/* Ghosting behind a moving object: a temporal method (TAA) that keeps a
 * stale history leaves a trail where the object was. Measured against the
 * reference frame by frame: the error (mean |T - R| on luma in [0, 1], the
 * luma of flicker.h) over the band of pixels the object covered in the
 * GHOSTING_TRAIL frames before but does not cover now, beside the error
 * over the rest of the frame (what the method costs anyway). The band is
 * built from the object's silhouette discs (centre and radius in pixels).
 * GL-free and thread-safe. */

#include <stddef.h>
#include <stdint.h>

/* Frames of the object's past the band covers. */
#define GHOSTING_TRAIL 8

enum ghosting_mask { GHOSTING_REST = 0, GHOSTING_BAND = 1, GHOSTING_OBJECT = 2 };

/* mask (w x h, rows from the bottom as GL reads them): GHOSTING_OBJECT
 * inside now's disc grown by a pixel, GHOSTING_BAND inside any of the past
 * discs (count of them) and not the object, else GHOSTING_REST. A disc is
 * x, y, radius in pixels, pixel (i, j)'s centre at (i + 0.5, j + 0.5). */
void ghosting_band(uint8_t *mask, int w, int h, const float (*past)[3], int count,
                   const float now[3]);

struct ghosting_result {
    int frames;
    double band_pixels; /* summed over frames */
    double band_error;  /* summed over frames, each the frame's mean over its band */
    double rest_error;  /* the same over the rest */
};

void ghosting_init(struct ghosting_result *r);
/* One frame: test and ref are w x h of `channels` 8-bit values (RGB
 * first). A frame with an empty band adds nothing. */
void ghosting_add(struct ghosting_result *r, const uint8_t *test, const uint8_t *ref,
                  const uint8_t *mask, size_t pixels, int channels);

#endif
