#ifndef SHADEBENCH_DIFF_VIEWS_H
#define SHADEBENCH_DIFF_VIEWS_H

/* A job's difference views for people, from its stored PNGs: what the
 * report shows under each capture and what the API serves for the
 * dashboard. PerceptualDiff's failing pixels as a mask (made from the
 * capture and its reference with the job's own options, so that it shows
 * exactly the pixels the job counted), the absolute difference, and the
 * SSIM and FLIP maps with their contrast stretched.
 * GL-free; any thread (each call works on its own images). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/png_io.h"
#include "daemon/quality/metrics.h"

/* The job's PerceptualDiff options (its spec's metrics.pdiff, every field
 * filled in by the daemon when it accepted the job) over the defaults. */
void diff_views_pdiff_options(const json_t *job, struct pdiff_options *o);

/* Did the job score capture frame with PerceptualDiff against a reference? */
bool diff_views_has_pdiff(const json_t *job, int frame);

/* The mask of capture frame (white where a pixel fails, else black) from
 * the job's directory dir, and the count. False with err when an image
 * cannot be read or memory runs out. */
bool diff_views_pdiff_mask(const json_t *job, const char *dir, int frame, struct image *mask,
                           long *failing, char *err, size_t errlen);

#endif
