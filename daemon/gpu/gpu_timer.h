#ifndef SHADEBENCH_GPU_TIMER_H
#define SHADEBENCH_GPU_TIMER_H

/* GPU frame timing: a frame is split into consecutive sections (the passes;
 * one begins where the one before ends, so no work between them goes
 * untimed), a section entered again in a frame adds to its time, and the
 * frame's time is their sum. Where the driver answers GL_TIMESTAMP (GL 3.3
 * core: every driver here), a timestamp is written at each section's start
 * and at the frame's end, and a section is the time from its start to the
 * next one's: the sections add up to the frame's GPU span exactly, however
 * the device overlaps them (llvmpipe rasterises one pass's bins while
 * another thread still draws the pass before, and GL_TIME_ELAPSED sections
 * summed to 1.5 times the span there). Else each section is a
 * GL_TIME_ELAPSED query (never nested, as GL requires). Results are read
 * back once the ring comes round, so the pipeline never stalls on a query
 * unless the GPU is more than a ring's worth of frames behind (counted in
 * stalls). */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stdint.h>

#define GPU_TIMER_MAX_SECTIONS 32
#define GPU_TIMER_RING 8

struct gpu_timer;

/* frames: how many frames will be timed in all (results are kept per frame). */
struct gpu_timer *gpu_timer_create(int sections, int64_t frames);
void gpu_timer_destroy(struct gpu_timer *t);

/* Starts a frame: no section runs until gpu_timer_section. */
void gpu_timer_begin_frame(struct gpu_timer *t);
/* Ends the running section and starts section s (no-op when already in it;
 * a section begun earlier in the frame adds a second entry). */
void gpu_timer_section(struct gpu_timer *t, int s);
void gpu_timer_end_frame(struct gpu_timer *t);

/* Reads every outstanding query (call after glFinish). */
void gpu_timer_drain(struct gpu_timer *t);
/* Forgets the frames timed so far (after a glFinish): the next frame is
 * frame `next` (the harness's measuring frames, untimed, may stand for the
 * first warm-up frames). */
void gpu_timer_restart(struct gpu_timer *t, int64_t next);

/* Milliseconds of frame f (0-based, in submission order), section s or the
 * whole frame with s < 0. */
double gpu_timer_ms(const struct gpu_timer *t, int64_t f, int s);
/* While paused, the timer opens no query (the harness's measuring frames,
 * whose tiles time themselves): begin and end of frame and sections do
 * nothing. */
void gpu_timer_pause(struct gpu_timer *t, bool paused);

/* Whether sections are timestamp differences (else GL_TIME_ELAPSED). */
bool gpu_timer_timestamps(const struct gpu_timer *t);
int64_t gpu_timer_stalls(const struct gpu_timer *t);
/* The section begun last (-1 before any): where a frame was abandoned. */
int gpu_timer_last_section(const struct gpu_timer *t);
/* Sections of frames from_frame on whose elapsed time exceeded the time
 * since the timer was created: impossible, so a driver's fault (llvmpipe
 * answers the first query of a context, and OSL's first raster pass after
 * its compute work, with the time since boot). Recorded as 0 ms. */
int64_t gpu_timer_implausible(const struct gpu_timer *t, int64_t from_frame);

/* Once per context, before any timer: runs and reads one query, so that a
 * driver whose first answer is wrong gives it here. */
void gpu_timer_prime(void);

#endif
