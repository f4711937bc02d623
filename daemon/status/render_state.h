#ifndef SHADEBENCH_RENDER_STATE_H
#define SHADEBENCH_RENDER_STATE_H

/* What the render thread is doing, for /healthz and /metrics: idle, or a
 * job (its id and phase), and when it last made progress (a frame went
 * round the timed loop, a slice of GPU work completed, a metric tile was
 * scored, a phase began). A render thread that makes no progress for longer
 * than the daemon's --stall-seconds is stalled, and /healthz says so with a
 * 503: a job that holds the GPU for minutes would otherwise look healthy.
 *
 * Process-wide, like telemetry.h: the daemon has one render thread. The
 * writers are the render thread (begin, phase, progress, end) and the
 * metrics thread (progress, while the render thread waits for it); any
 * thread reads. Lock-free: the job id sits behind a sequence lock (written
 * twice a job), the phase is one atomic pointer and progress one atomic
 * instant, so that render_progress_at, the call the timed loop makes, is a
 * single atomic store. GL-free. */

#include <stdbool.h>
#include <string.h>

#include "daemon/store/records.h"

struct render_state {
    bool alive;               /* the render thread runs (runner_state fills it) */
    bool busy;                /* a job is on the render thread */
    char job[RECORD_ID_LEN];  /* busy: its id */
    const char *phase;        /* busy: what it is doing, a string literal */
    double busy_s;            /* busy: seconds since the job began on the thread */
    double since_progress_s;  /* busy: seconds since the last progress; idle: idle time */
};

/* The phases of a job that ended early while what the GPU still has of it
 * finishes (runner.c): /healthz calls the thread "draining" then. */
#define RENDER_PHASE_DRAINING_CANCELLED "draining a cancelled job"
#define RENDER_PHASE_DRAINING_FAILED "draining a failed job"
static inline bool render_state_draining(const struct render_state *s)
{
    return s->busy && s->phase && strncmp(s->phase, "draining", 8) == 0;
}

/* Render thread: a job begins (phase: a string literal such as "setup"),
 * changes phase (counts as progress), ends (the thread is idle). */
void render_state_begin(const char *job_id, const char *phase);
void render_state_phase(const char *phase);
void render_state_end(void);

/* Progress now: reads the monotonic clock, then one atomic store. Render
 * or metrics thread, outside timed regions. */
void render_progress(void);
/* Progress at mono_s (clock_mono_s(), which the caller has already read):
 * one atomic store and nothing else, for the timed loop. */
void render_progress_at(double mono_s);

/* A consistent copy (alive left false: the runner knows that). Any thread. */
void render_state_read(struct render_state *out);

/* Stalled: alive and busy, with no progress for longer than bound_s (> 0;
 * 0 never stalls). */
bool render_state_stalled(const struct render_state *s, double bound_s);

#endif
