/* The interference figures from canned /proc text: parsing, the CPU shares
 * and the noisy rule, and the JSON shape that results carry. */
#include <math.h>
#include <string.h>

#include "daemon/status/interference.h"
#include "tests/unit/check.h"

static const char *const STAT_A =
    "cpu  1000 10 500 8000 100 0 20 30 7 0\n"
    "cpu0 500 5 250 4000 50 0 10 15 7 0\n"
    "cpu1 500 5 250 4000 50 0 10 15 0 0\n"
    "intr 123456 0 0 0 0\n"
    "ctxt 99999\n";

/* 100 ticks later on 2 CPUs (200 ticks in all): 40 busy, 160 idle. */
static const char *const STAT_B =
    "cpu  1030 10 505 8150 110 0 20 35 9 0\n"
    "cpu0 515 5 252 4075 55 0 10 17 9 0\n"
    "cpu1 515 5 253 4075 55 0 10 18 0 0\n"
    "intr 123999 0 0 0 0\n";

static void sample_from(struct interference_sample *s, const char *stat, const char *self,
                        const char *load, double t)
{
    memset(s, 0, sizeof(*s));
    s->ok = interference_parse_stat(stat, &s->cpu) &&
            interference_parse_self_stat(self, &s->self_ticks, &s->self_minor_faults) &&
            interference_parse_loadavg(load, s->loadavg);
    s->unix_s = 1700000000.0 + t;
    s->mono_s = 100.0 + t;
}

int main(void)
{
    struct cpu_times ct;
    CHECK(interference_parse_stat(STAT_A, &ct));
    /* Guest time (7) is inside user already, so it is not added again. */
    CHECK(ct.total == 1000 + 10 + 500 + 8000 + 100 + 0 + 20 + 30);
    CHECK(ct.idle == 8100);
    CHECK(ct.cpus == 2);
    /* Old kernels with four fields; no per-CPU lines is refused. */
    CHECK(interference_parse_stat("cpu  1 2 3 4\ncpu0 1 2 3 4\n", &ct) && ct.total == 10 &&
          ct.cpus == 1);
    CHECK(!interference_parse_stat("cpu  1 2 3 4\n", &ct));
    CHECK(!interference_parse_stat("intr 1 2 3\n", &ct));
    CHECK(!interference_parse_stat("", &ct));

    /* A command name with spaces and parentheses does not shift the fields. */
    unsigned long long ticks = 0, faults = 0;
    const char *self =
        "4242 (shade (bench) d) S 1 4242 4242 0 -1 4194560 900 0 0 0 1234 567 0 0 20 0 9 0 "
        "113618 3133440 365 18446744073709551615\n";
    CHECK(interference_parse_self_stat(self, &ticks, &faults) && ticks == 1234 + 567 &&
          faults == 900);
    CHECK(!interference_parse_self_stat("4242 (x) S 1 2 3", &ticks, &faults));
    CHECK(!interference_parse_self_stat("no parenthesis", &ticks, &faults));

    double load[3];
    CHECK(interference_parse_loadavg("1.61 0.99 0.72 3/115 884\n", load) && load[0] == 1.61 &&
          load[1] == 0.99 && load[2] == 0.72);
    CHECK(!interference_parse_loadavg("garbage", load));

    /* 200 ticks: 40 busy, of which the daemon took 30: the others took 10
     * (5%, not above the limit), the daemon 15%. */
    struct interference_sample a, b;
    struct interference_figures f;
    sample_from(&a, STAT_A, "1 (d) S 1 1 1 0 -1 0 0 0 0 0 100 50 0", "0.50 0.40 0.30 1/1 1", 0);
    sample_from(&b, STAT_B, "1 (d) S 1 1 1 0 -1 0 0 0 0 0 120 60 0", "0.90 0.50 0.30 1/1 1", 1);
    CHECK(a.ok && b.ok);
    interference_compute(&a, &b, &f);
    CHECK(f.ticks == 200);
    CHECK_NEAR(f.other_cpu_share, 10.0 / 200.0, 1e-12);
    CHECK_NEAR(f.daemon_cpu_share, 30.0 / 200.0, 1e-12);
    CHECK(!f.noisy);

    /* The daemon took less: the rest is someone else's, and over 10% is
     * noisy (the one rule, common/noise.h: 12.5% less CPU left than an idle
     * machine leaves). */
    sample_from(&b, STAT_B, "1 (d) S 1 1 1 0 -1 0 0 0 0 0 110 55 0", "0.90 0.50 0.30 1/1 1", 1);
    interference_compute(&a, &b, &f);
    CHECK_NEAR(f.other_cpu_share, 25.0 / 200.0, 1e-12);
    CHECK(f.noisy);

    /* The daemon's counter ran a tick ahead of the machine's: no negative share. */
    sample_from(&b, STAT_B, "1 (d) S 1 1 1 0 -1 0 0 0 0 0 130 61 0", "0.90 0.50 0.30 1/1 1", 1);
    interference_compute(&a, &b, &f);
    CHECK(f.other_cpu_share == 0.0 && f.daemon_cpu_share == 41.0 / 200.0 && !f.noisy);

    /* A quiet interval after a busy minute: the load average (which counts
     * the daemon's own threads, and the minute before the run) never makes
     * it noisy; the CPU the others took during it decides. */
    sample_from(&a, STAT_A, "1 (d) S 1 1 1 0 -1 0 7 0 0 0 100 50 0", "4.00 2.00 1.00 1/1 1", 0);
    sample_from(&b, STAT_B, "1 (d) S 1 1 1 0 -1 0 19 0 0 0 120 60 0", "4.00 2.00 1.00 1/1 1", 1);
    interference_compute(&a, &b, &f);
    CHECK(!f.noisy);
    a.loadavg[0] = 40.0;
    interference_compute(&a, &b, &f);
    CHECK(!f.noisy);

    /* The threshold: exactly 10% is not noisy, more is; the same function
     * the client's gate applies against its typical run. */
    CHECK(!noise_exceeds(0.10, 0.0, NOISE_TOLERANCE) && noise_exceeds(0.105, 0.0, NOISE_TOLERANCE));
    CHECK(!noise_exceeds(0.76, 0.75, NOISE_TOLERANCE) && noise_exceeds(0.80, 0.75, NOISE_TOLERANCE));
    CHECK_NEAR(noise_cpu_left_change(0.85, 0.80), -0.25, 1e-12);
    CHECK(strstr(INTERFERENCE_RULE, "10%") != NULL);
    /* A result stored under the old rule (5%, or the load average) reads by
     * this one from its figures; its flag counts only without figures. */
    json_t *old = json_pack("{s:f, s:b}", "other_cpu_share", 0.07, "noisy", 1);
    CHECK(!noise_interference_noisy(old));
    json_object_set_new(old, "other_cpu_share", json_real(0.2));
    json_object_set_new(old, "noisy", json_false());
    CHECK(noise_interference_noisy(old));
    json_object_del(old, "other_cpu_share");
    json_object_set_new(old, "noisy", json_true());
    CHECK(noise_interference_noisy(old) && !noise_interference_noisy(NULL));
    json_decref(old);

    /* No time passed: shares are zero, not a division by zero. */
    interference_compute(&a, &a, &f);
    CHECK(f.ticks == 0 && f.other_cpu_share == 0.0 && f.daemon_cpu_share == 0.0);

    /* The shape results carry. */
    a.loadavg[0] = 0.5;
    json_t *j = interference_json(&a, &b);
    CHECK(json_is_array(json_object_get(j, "loadavg_start")) &&
          json_array_size(json_object_get(j, "loadavg_start")) == 3);
    CHECK(json_real_value(json_array_get(json_object_get(j, "loadavg_end"), 0)) == 4.0);
    CHECK(json_is_real(json_object_get(j, "other_cpu_share")));
    CHECK(json_is_real(json_object_get(j, "daemon_cpu_share")));
    CHECK(json_is_boolean(json_object_get(j, "noisy")));
    CHECK(json_string_value(json_object_get(j, "rule")) &&
          strstr(json_string_value(json_object_get(j, "rule")), "0.10"));
    CHECK(json_integer_value(json_object_get(j, "cpus")) == 2);
    CHECK(json_integer_value(json_object_get(j, "cpu_ticks")) == 200);
    CHECK(json_integer_value(json_object_get(j, "daemon_minor_faults")) == 12);
    CHECK_NEAR(json_real_value(json_object_get(j, "interval_s")), 1.0, 1e-9);
    CHECK(json_real_value(json_object_get(j, "timed_end_unix")) >
          json_real_value(json_object_get(j, "timed_start_unix")));
    json_decref(j);

    /* A failed sample: the figures are null and the error says why. */
    b.ok = false;
    snprintf(b.error, sizeof(b.error), "cannot open /proc/stat: No such file or directory");
    j = interference_json(&a, &b);
    CHECK(json_is_null(json_object_get(j, "other_cpu_share")) &&
          json_is_null(json_object_get(j, "noisy")));
    CHECK(strstr(json_string_value(json_object_get(j, "error")), "/proc/stat") != NULL);
    json_decref(j);

    /* And the real thing on this machine. */
    struct interference_sample live0, live1;
    interference_sample(&live0);
    volatile double spin = 0;
    for (int i = 0; i < 20000000; i++)
        spin += i * 0.5;
    interference_sample(&live1);
    CHECK(live0.ok && live1.ok);
    if (!live0.ok)
        fprintf(stderr, "  sample: %s\n", live0.error);
    interference_compute(&live0, &live1, &f);
    CHECK(live1.self_ticks >= live0.self_ticks && live0.cpu.cpus >= 1);
    CHECK(f.other_cpu_share >= 0 && f.other_cpu_share <= 1 && f.daemon_cpu_share >= 0 &&
          f.daemon_cpu_share <= 1);
    return check_finish("test_interference");
}
