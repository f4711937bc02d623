#define _POSIX_C_SOURCE 200809L
#include "daemon/status/telemetry.h"

#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <time.h>
#include <unistd.h>

/* Seconds are kept as nanoseconds so that they add up atomically. */
static atomic_ullong frames, render_ns, metrics_ns, captures;

void telemetry_frames(unsigned n) { atomic_fetch_add(&frames, n); }

void telemetry_render_busy(double seconds)
{
    if (seconds > 0)
        atomic_fetch_add(&render_ns, (unsigned long long)(seconds * 1e9));
}

void telemetry_metrics(double seconds, unsigned n)
{
    if (seconds > 0)
        atomic_fetch_add(&metrics_ns, (unsigned long long)(seconds * 1e9));
    atomic_fetch_add(&captures, n);
}

void telemetry_read(struct telemetry *out)
{
    out->frames = atomic_load(&frames);
    out->render_busy_s = (double)atomic_load(&render_ns) / 1e9;
    out->metrics_s = (double)atomic_load(&metrics_ns) / 1e9;
    out->captures_scored = atomic_load(&captures);
}

double telemetry_rss_bytes(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0, resident = 0;
    bool ok = f && fscanf(f, "%llu %llu", &size, &resident) == 2;
    if (f)
        fclose(f);
    return ok ? (double)resident * (double)sysconf(_SC_PAGESIZE) : 0;
}
