#ifndef SHADEBENCH_INTERFERENCE_H
#define SHADEBENCH_INTERFERENCE_H

/* What could have disturbed a timed run: the machine's load average at the
 * start and end of the timed region, and how the machine's CPU time was
 * shared during it, between this daemon and everything else (from
 * /proc/stat against the daemon's own utime + stime in /proc/self/stat).
 * Every result carries it as result.interference, so a user can tell a
 * quiet run from a noisy one.
 *
 * GL-free. The parsers and the arithmetic take text and numbers, so they
 * are unit-tested on canned /proc text; interference_sample reads /proc.
 * Any thread (the render thread samples, just outside the timed region:
 * three small reads, no lock). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/noise.h"

/* The aggregate "cpu" line of /proc/stat, in clock ticks summed over all
 * CPUs: total counts every state but guest time (already inside user time),
 * idle counts idle and iowait. Steal time is busy: another guest used the
 * CPU. cpus counts the "cpuN" lines. */
struct cpu_times {
    unsigned long long total, idle;
    int cpus;
};

bool interference_parse_stat(const char *text, struct cpu_times *out);
/* utime + stime (fields 14 and 15) of a /proc/PID/stat line, in clock
 * ticks, and the minor page faults (field 10); the command name may hold
 * spaces and parentheses. */
bool interference_parse_self_stat(const char *text, unsigned long long *ticks,
                                  unsigned long long *minor_faults);
/* The three load averages of /proc/loadavg. */
bool interference_parse_loadavg(const char *text, double load[3]);

/* One reading at one instant. The caller owns it; nothing to free. */
struct interference_sample {
    bool ok;
    char error[160];   /* when !ok: which file and why */
    double unix_s;     /* wall clock, for ordering against other records */
    double mono_s;     /* for the interval */
    double loadavg[3];
    struct cpu_times cpu;
    unsigned long long self_ticks;
    unsigned long long self_minor_faults;
};

void interference_sample(struct interference_sample *s);

/* The figures between two samples. */
struct interference_figures {
    double other_cpu_share;  /* busy ticks of the machine less the daemon's, over all ticks */
    double daemon_cpu_share; /* the daemon's ticks over all ticks */
    unsigned long long ticks; /* all CPUs' ticks in the interval: the resolution */
    bool noisy;
};

/* noisy follows the one noise rule (common/noise.h): other processes took
 * more than NOISE_TOLERANCE of the machine's CPU during the timed region. */
#define INTERFERENCE_RULE NOISE_RULE

void interference_compute(const struct interference_sample *start,
                          const struct interference_sample *end, struct interference_figures *f);

/* result.interference: loadavg_start, loadavg_end, other_cpu_share,
 * daemon_cpu_share, noisy, rule, plus cpus, interval_s, cpu_ticks, the
 * daemon's minor page faults (a heap that shrinks and grows back every
 * frame shows there) and the timed region's timed_start_unix and
 * timed_end_unix. When a sample failed,
 * the figures are null and error says why. New reference. */
json_t *interference_json(const struct interference_sample *start,
                          const struct interference_sample *end);

#endif
