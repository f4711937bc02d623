#ifndef SHADEBENCH_NOISE_H
#define SHADEBENCH_NOISE_H

/* The noise rule, defined once, for every place that calls a timed run
 * noisy: the daemon (result.interference.noisy, and the reports and charts
 * that show it), the client's gate and ab, history, and a plain
 * `submit --wait`.
 *
 * A CPU-bound renderer (llvmpipe, a driver's submission thread) runs at the
 * speed of the CPU that other processes leave it. So a run is noisy when
 * the CPU other processes left it during its timed region differs by more
 * than NOISE_TOLERANCE (10%) from the CPU left to what it is measured
 * against:
 *   - alone (the daemon's flag, history, reports, one job): against an
 *     idle machine, so other processes took more than 10% of the machine's
 *     CPU time;
 *   - compared (the gate, ab): against what it is compared with, so that
 *     runs measured under like conditions are compared, whatever those
 *     conditions were: in the gate a new run against the baseline's
 *     typical run; in ab B's run of a pair against A's, each from its own
 *     side's typical run.
 * One threshold, one measure (the relative change of the CPU left), two
 * references, each named where a verdict is printed.
 *
 * GL-free and free of I/O; any thread. Unit-tested in
 * tests/unit/test_interference.c and test_gate.c. */

#include <jansson.h>
#include <stdbool.h>

/* 10%: the gate's tolerance since it began marking noise. The daemon used
 * to flag runs above 5% of others' CPU (or a load average above twice the
 * CPUs, which counts the daemon's own threads and a minute before the run),
 * so that one run read "NOISY 76%" in history and kept as clean by the
 * gate; now both apply this. */
#define NOISE_TOLERANCE 0.10

#define NOISE_RULE                                                                             \
    "noisy when the CPU other processes left the timed region differs by more than 10% from "  \
    "the CPU left to what it is measured against: alone, an idle machine (other_cpu_share > "   \
    "0.10); in the client's gate, the baseline's typical run; in ab, the other run of the pair"

/* How much more (> 0) or less (< 0) CPU other processes left than in the
 * reference, relatively: (1 - share) / (1 - reference) - 1. 0.85 against
 * 0.80 (15% left instead of 20%) is -25%; 0.05 against 0.02 is -3%; 0.12
 * against an idle machine (0) is -12%. */
double noise_cpu_left_change(double share, double reference);

/* True when share, against reference, breaks tolerance (NOISE_TOLERANCE
 * unless a caller was asked for another). */
bool noise_exceeds(double share, double reference, double tolerance);

/* A result's "interference" judged alone by this rule from its
 * other_cpu_share, so that a result stored under an older rule reads as a
 * new one does; its own "noisy" flag only where it has no figures. */
bool noise_interference_noisy(const json_t *interference);

#endif
