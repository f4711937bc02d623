#ifndef SHADEBENCH_DEADLINE_H
#define SHADEBENCH_DEADLINE_H

/* A job's running time against its timeout_s, counted from when it started
 * running (time in the queue is free). Checked by the render thread once a
 * frame and by the metrics thread once a tile; GL-free, any thread. */

#include <stdbool.h>
#include <stdio.h>

#include "common/clock.h"
#include "daemon/jobs/queue.h"

static inline bool job_timed_out(const struct job *job)
{
    return job->spec.timeout_s > 0 && job->started > 0 &&
           clock_unix_s() - job->started > job->spec.timeout_s;
}

/* The failure message, naming the phase the job was in and, where known,
 * more of where (detail: "" or " at frame 3, in the shading pass"). */
static inline void job_timeout_message(const struct job *job, const char *phase,
                                       const char *detail, char *out, size_t cap)
{
    snprintf(out, cap, "timeout: the job ran longer than its timeout_s of %g s and was stopped "
                       "in the %s phase%s", job->spec.timeout_s, phase, detail);
}

#endif
