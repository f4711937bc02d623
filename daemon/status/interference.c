#define _POSIX_C_SOURCE 200809L
#include "daemon/status/interference.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/clock.h"

bool interference_parse_stat(const char *text, struct cpu_times *out)
{
    unsigned long long v[10] = {0};
    memset(out, 0, sizeof(*out));
    if (strncmp(text, "cpu ", 4) != 0)
        return false;
    /* user nice system idle iowait irq softirq steal guest guest_nice; old
     * kernels stop after fewer fields, so missing ones count as zero. */
    int n = sscanf(text + 4, "%llu %llu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1],
                   &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]);
    if (n < 4)
        return false;
    /* guest and guest_nice are already inside user and nice. */
    for (int i = 0; i < 8; i++)
        out->total += v[i];
    out->idle = v[3] + v[4];
    for (const char *line = strchr(text, '\n'); line; line = strchr(line, '\n')) {
        line++;
        if (strncmp(line, "cpu", 3) != 0)
            break;
        if (line[3] >= '0' && line[3] <= '9')
            out->cpus++;
    }
    return out->cpus > 0 && out->total > 0;
}

bool interference_parse_self_stat(const char *text, unsigned long long *ticks,
                                  unsigned long long *minor_faults)
{
    /* Field 2 is "(comm)", and comm may hold anything: the fields after it
     * start after the last ')'. */
    const char *p = strrchr(text, ')');
    if (!p)
        return false;
    p++;
    /* Fields 3 (state) to 9 (flags), then minflt, cminflt, majflt, cmajflt,
     * utime and stime. */
    for (int field = 3; field <= 9; field++) {
        while (*p == ' ')
            p++;
        if (!*p)
            return false;
        while (*p && *p != ' ')
            p++;
    }
    unsigned long long minflt, cminflt, majflt, cmajflt, utime, stime;
    if (sscanf(p, " %llu %llu %llu %llu %llu %llu", &minflt, &cminflt, &majflt, &cmajflt, &utime,
               &stime) != 6)
        return false;
    *ticks = utime + stime;
    *minor_faults = minflt;
    return true;
}

bool interference_parse_loadavg(const char *text, double load[3])
{
    return sscanf(text, "%lf %lf %lf", &load[0], &load[1], &load[2]) == 3 && load[0] >= 0 &&
           load[1] >= 0 && load[2] >= 0;
}

/* Reads the start of a /proc file into buf (NUL-terminated). */
static bool read_proc(const char *path, char *buf, size_t cap, char *err, size_t errlen)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        snprintf(err, errlen, "cannot open %s: %s", path, strerror(errno));
        return false;
    }
    size_t used = 0;
    while (used + 1 < cap) {
        ssize_t n = read(fd, buf + used, cap - 1 - used);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            snprintf(err, errlen, "cannot read %s: %s", path, strerror(errno));
            close(fd);
            return false;
        }
        if (n == 0)
            break;
        used += (size_t)n;
    }
    close(fd);
    buf[used] = '\0';
    return true;
}

void interference_sample(struct interference_sample *s)
{
    /* /proc/stat lists every CPU before its long interrupt lines: 64 KiB
     * holds the CPU lines of about a thousand CPUs. */
    enum { STAT_BYTES = 64 * 1024 };
    char small[1024];
    char *stat = malloc(STAT_BYTES);
    memset(s, 0, sizeof(*s));
    s->unix_s = clock_unix_s();
    s->mono_s = clock_mono_s();
    if (!stat) {
        snprintf(s->error, sizeof(s->error), "out of memory reading /proc/stat");
        return;
    }
    if (!read_proc("/proc/stat", stat, STAT_BYTES, s->error, sizeof(s->error)))
        goto out;
    if (!interference_parse_stat(stat, &s->cpu)) {
        snprintf(s->error, sizeof(s->error), "/proc/stat has no aggregate cpu line");
        goto out;
    }
    if (!read_proc("/proc/self/stat", small, sizeof(small), s->error, sizeof(s->error)))
        goto out;
    if (!interference_parse_self_stat(small, &s->self_ticks, &s->self_minor_faults)) {
        snprintf(s->error, sizeof(s->error), "/proc/self/stat has no utime and stime");
        goto out;
    }
    if (!read_proc("/proc/loadavg", small, sizeof(small), s->error, sizeof(s->error)))
        goto out;
    if (!interference_parse_loadavg(small, s->loadavg)) {
        snprintf(s->error, sizeof(s->error), "/proc/loadavg has no load averages");
        goto out;
    }
    s->ok = true;
out:
    free(stat);
}

void interference_compute(const struct interference_sample *start,
                          const struct interference_sample *end, struct interference_figures *f)
{
    memset(f, 0, sizeof(*f));
    /* Counters only grow; a decrease would be a wrapped or reset counter. */
    unsigned long long ticks = end->cpu.total > start->cpu.total ? end->cpu.total - start->cpu.total : 0;
    unsigned long long idle = end->cpu.idle > start->cpu.idle ? end->cpu.idle - start->cpu.idle : 0;
    unsigned long long self =
        end->self_ticks > start->self_ticks ? end->self_ticks - start->self_ticks : 0;
    unsigned long long busy = idle < ticks ? ticks - idle : 0;
    f->ticks = ticks;
    if (ticks > 0) {
        /* The daemon's and the machine's counters tick separately, so the
         * daemon's share can exceed the busy time by a tick: clamp. */
        double other = busy > self ? (double)(busy - self) : 0.0;
        f->other_cpu_share = other / (double)ticks;
        f->daemon_cpu_share = self < ticks ? (double)self / (double)ticks : 1.0;
    }
    /* Alone, a run is measured against an idle machine. */
    f->noisy = noise_exceeds(f->other_cpu_share, 0.0, NOISE_TOLERANCE);
}

json_t *interference_json(const struct interference_sample *start,
                          const struct interference_sample *end)
{
    json_t *o = json_pack("{s:s, s:f, s:f, s:f}", "rule", INTERFERENCE_RULE, "timed_start_unix",
                          start->unix_s, "timed_end_unix", end->unix_s, "interval_s",
                          end->mono_s - start->mono_s);
    if (!o)
        return NULL;
    if (!start->ok || !end->ok) {
        json_object_set_new(o, "error", json_string(!start->ok ? start->error : end->error));
        static const char *const unknown[] = {"loadavg_start", "loadavg_end", "other_cpu_share",
                                              "daemon_cpu_share", "noisy", "cpus", "cpu_ticks",
                                              "daemon_minor_faults"};
        for (size_t i = 0; i < sizeof(unknown) / sizeof(unknown[0]); i++)
            json_object_set_new(o, unknown[i], json_null());
        return o;
    }
    struct interference_figures f;
    interference_compute(start, end, &f);
    json_object_set_new(o, "loadavg_start", json_pack("[f, f, f]", start->loadavg[0],
                                                      start->loadavg[1], start->loadavg[2]));
    json_object_set_new(o, "loadavg_end",
                        json_pack("[f, f, f]", end->loadavg[0], end->loadavg[1], end->loadavg[2]));
    json_object_set_new(o, "other_cpu_share", json_real(f.other_cpu_share));
    json_object_set_new(o, "daemon_cpu_share", json_real(f.daemon_cpu_share));
    json_object_set_new(o, "noisy", json_boolean(f.noisy));
    json_object_set_new(o, "cpus", json_integer(start->cpu.cpus));
    json_object_set_new(o, "cpu_ticks", json_integer((json_int_t)f.ticks));
    json_object_set_new(o, "daemon_minor_faults",
                        json_integer(end->self_minor_faults >= start->self_minor_faults
                                         ? (json_int_t)(end->self_minor_faults -
                                                        start->self_minor_faults)
                                         : 0));
    return o;
}
