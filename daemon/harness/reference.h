#ifndef SHADEBENCH_REFERENCE_H
#define SHADEBENCH_REFERENCE_H

/* The reference render of a job: the reference technique at exactly the
 * captured frames, after the timed runs, over the measured run's scene and
 * look stages, written as reference-NNNNNN.png beside the captures. With
 * reference.supersample N it renders at N times the width and height and
 * is box-filtered down to the job's size (quality/flicker.h). Its time is
 * in no figure. Also the frame source the temporal stage (temporal.h)
 * draws the technique's and the reference's frames in a row with. Render
 * thread only. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/harness/run.h"

/* run is the job's measured first run (its technique already destroyed).
 * On false, run->err says why and *status is JOB_CANCELLED when the job was
 * cancelled. */
bool reference_render(struct harness_run *run, enum job_status *status);

/* A technique drawn frame by frame outside the timing over the measured
 * run's scene and look stages, read back at the job's size. Open one at a
 * time: every source takes the pool's output targets. */
struct frame_source {
    struct harness_run rr;
    const char *what;  /* "reference" or "temporal": the phase its errors name */
    uint8_t *big;      /* scale > 1: the frame read back at scale times the size */
};

/* tech with options and look, at scale (1: the job's size). */
bool frame_source_open(struct harness_run *run, struct frame_source *src, const char *what,
                       const struct technique *tech, const void *options,
                       const struct look_spec *look, int scale);
/* Frame k into pixels (the job's width x height, RGBA, bottom row first as
 * GL reads). fresh: a new instance of the technique draws it (frame k is a
 * pure function of k); otherwise the instance of the frame before goes on. */
bool frame_source_frame(struct harness_run *run, struct frame_source *src, int64_t k, bool fresh,
                        uint8_t *pixels, enum job_status *status);
void frame_source_close(struct frame_source *src);

#endif
