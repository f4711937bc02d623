#ifndef SHADEBENCH_GPU_TIMER_H
#define SHADEBENCH_GPU_TIMER_H

/* GPU frame timing from a ring of GL_TIME_ELAPSED queries. A frame may be
 * split into consecutive sections (never nested, as GL requires); the
 * frame's time is their sum. Results are read back once the ring comes
 * round, so the pipeline never stalls on a query unless the GPU is more
 * than a ring's worth of frames behind (counted in stalls). */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stdint.h>

#define GPU_TIMER_MAX_SECTIONS 32
#define GPU_TIMER_RING 8

struct gpu_timer;

/* frames: how many frames will be timed in all (results are kept per frame). */
struct gpu_timer *gpu_timer_create(int sections, int64_t frames);
void gpu_timer_destroy(struct gpu_timer *t);

void gpu_timer_begin_frame(struct gpu_timer *t);
/* Ends the running section and starts section s (no-op when already in it). */
void gpu_timer_section(struct gpu_timer *t, int s);
void gpu_timer_end_frame(struct gpu_timer *t);

/* Reads every outstanding query (call after glFinish). */
void gpu_timer_drain(struct gpu_timer *t);

/* Milliseconds of frame f (0-based, in submission order), section s or the
 * whole frame with s < 0. */
double gpu_timer_ms(const struct gpu_timer *t, int64_t f, int s);
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
