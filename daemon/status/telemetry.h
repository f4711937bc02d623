#ifndef SHADEBENCH_TELEMETRY_H
#define SHADEBENCH_TELEMETRY_H

/* Process-wide counters for /metrics: frames rendered, render-thread busy
 * time and metrics-stage time. Written by the render and metrics threads,
 * read by the HTTP threads; lock-free (C11 atomics), any thread. GL-free. */

struct telemetry {
    unsigned long long frames;
    double render_busy_s;
    double metrics_s;
    unsigned long long captures_scored;
};

void telemetry_frames(unsigned n);
void telemetry_render_busy(double seconds);
void telemetry_metrics(double seconds, unsigned captures);
void telemetry_read(struct telemetry *out);

/* The process's resident set now (bytes, from /proc/self/statm; 0 when it
 * cannot be read): the driver's allocations included, which llvmpipe makes
 * in the daemon's own memory. */
double telemetry_rss_bytes(void);

#endif
