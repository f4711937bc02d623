#ifndef SHADEBENCH_HISTORY_H
#define SHADEBENCH_HISTORY_H

/* A workload's history, for GET /v1/jobs/ID/history and the dashboard:
 * which jobs are the same measurement, and the changes between them that
 * the client's timing gate would flag.
 *
 *  - Two jobs are one workload when their specs (as the daemon stored
 *    them, every default filled in) are equal but for the fields that do
 *    not change what is timed: those the gate ignores (labels, repeat,
 *    capture_interval, reference, metrics, timeout_s, reference_look, as
 *    client/gate.c's gate_nonsemantic_field lists them) and the options of
 *    techniques other than the job's own (a reference's). Numbers compare
 *    by value.
 *  - A change is judged between each point and the one before it, noisy
 *    points left out as the gate leaves noisy runs out, on the ratio of
 *    their medians (later / earlier) with an interval from their 95%
 *    intervals, [lo_b / hi_a, hi_b / lo_a], by the gate's rule with its
 *    minimum effect of 5%: "slower" when the interval lies wholly above 1
 *    and the ratio above 1.05 (what the gate calls a regression), "faster"
 *    when it lies wholly below 1 and the ratio below 1 / 1.05.
 *
 * GL-free, no I/O; pure functions on JSON, any thread; unit-tested in
 * tests/unit/test_history.c. */

#include <jansson.h>
#include <stdbool.h>

/* The gate's minimum effect: slower by more than 5% counts. */
#define HISTORY_MIN_EFFECT 0.05

/* Is the top-level spec key one that does not change what is timed?
 * other_technique: the key names a technique that is not the job's. */
bool history_ignored_field(const char *key, bool other_technique);

/* Are specs a and b one workload? is_technique(ctx, key) tells which keys
 * are technique names (their options). */
bool history_same_workload(const json_t *a, const json_t *b,
                           bool (*is_technique)(void *ctx, const char *key), void *ctx);

/* The changes along points (oldest first, each {"id", "median", "ci95":
 * [lo, hi], "noisy"}): [{"from", "to", "ratio", "ratio_ci": [lo, hi],
 * "change": "slower" | "faster"}], only where one is flagged. New
 * reference. */
json_t *history_changes(const json_t *points, double min_effect);

#endif
