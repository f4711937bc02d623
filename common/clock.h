#ifndef SHADEBENCH_CLOCK_H
#define SHADEBENCH_CLOCK_H

/* Wall-clock time for records and waits (never for measurements: those use
 * CLOCK_MONOTONIC where they are taken). */

#include <time.h>

double clock_unix_s(void);

/* The CLOCK_REALTIME instant wait_s from now, for pthread_cond_timedwait. */
struct timespec clock_deadline(double wait_s);

#endif
