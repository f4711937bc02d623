#ifndef SHADEBENCH_CLOCK_H
#define SHADEBENCH_CLOCK_H

/* The daemon's clocks, any thread: wall-clock time for records and waits,
 * and the one monotonic clock for every interval that is measured. */

#include <time.h>

/* CLOCK_REALTIME in seconds: timestamps in records, never for intervals. */
double clock_unix_s(void);

/* CLOCK_MONOTONIC in seconds: for measuring intervals. */
double clock_mono_s(void);

/* The CLOCK_REALTIME instant wait_s from now, for pthread_cond_timedwait. */
struct timespec clock_deadline(double wait_s);

#endif
