#ifndef SHADEBENCH_GATE_H
#define SHADEBENCH_GATE_H

/* The timing gate: is this build slower than its baseline? Decided on runs,
 * not frames: each side is a set of run medians (frames within one run are
 * not independent, and whole runs move far more than frames within a run on
 * a shared machine), compared as a ratio with its confidence interval
 * (client/stats_test.h), against a minimum effect. Three outcomes:
 *   regression:   slower by more than the minimum effect, and the interval
 *                 lies wholly above no change;
 *   pass:         the interval lies wholly below 1 + minimum effect (a
 *                 slowdown that large is ruled out);
 *   inconclusive: neither; too noisy to tell, so the caller reruns.
 * Also the checks that make a comparison meaningful: the same job (spec
 * minus the fields that do not change what is timed) on the same device,
 * and runs disturbed by other processes marked noisy from the daemon's
 * interference figures.
 * GL-free and free of I/O; pure functions on JSON, any thread; unit-tested
 * in tests/unit/test_gate.c. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "client/stats_test.h"
#include "common/noise.h"

enum gate_outcome { GATE_PASS, GATE_REGRESSION, GATE_INCONCLUSIVE };

/* The fewest pairs an ab verdict may rest on: below it the paired interval
 * has 1 degree of freedom or none, and a "pass" over 1 pair says nothing. */
#define GATE_MIN_PAIRS 3

struct gate_verdict {
    enum gate_outcome outcome;
    struct ratio_interval r;
    double min_effect; /* 0.05: slower by more than 5% counts */
    char why[640];     /* one sentence: why this outcome */
    /* What it rests on: the runs of each side (ab: pairs, both the same)
     * that entered the interval, and whether noisy ones entered it bounded
     * by their CPU change (else only clean ones did). 0 and 0 when no
     * interval could be made. */
    size_t used_old, used_new;
    size_t clean_old, clean_new;
    bool bounded;
};

const char *gate_outcome_name(enum gate_outcome o);

/* How a verdict's sentence names the two sides: the baseline gate compares
 * "the baseline" with the runs "here"; ab compares "A" with "B" and has no
 * baseline to speak of. */
struct gate_sides {
    const char *old_side;  /* "in the baseline", "in A" */
    const char *new_side;  /* "here", "in B" */
};
extern const struct gate_sides GATE_SIDES_BASELINE, GATE_SIDES_AB;

/* Decides from an interval (ratio = new / baseline), its sentence in the
 * baseline gate's words. */
void gate_decide(const struct ratio_interval *r, double min_effect, struct gate_verdict *out);

/* The same with the sides named as asked (B / A for ab). */
void gate_decide_sides(const struct ratio_interval *r, double min_effect,
                       const struct gate_sides *sides, struct gate_verdict *out);

/* Welch on log run medians, then gate_decide. With too few runs (fewer than
 * 2 on the new side, or 3 in all) the outcome is inconclusive, and why says
 * so. */
void gate_compare(const double *baseline, size_t nb, const double *current, size_t nc,
                  double confidence, double min_effect, struct gate_verdict *out);

/* One run as the gate sees it. */
struct gate_run {
    char job[24];
    double ms;           /* the run's median of the chosen series */
    bool has_share;      /* the result carried interference figures */
    double other_share;  /* other processes' share of the machine's CPU, 0..1 */
    double load_start, load_end; /* 1-minute load average, NAN when absent */
    bool daemon_noisy;   /* the daemon's own flag */
    bool noisy_alone;    /* noisy against an idle machine (common/noise.h): what
                            history, reports and a single job call noisy */
    bool noisy;          /* left out of the comparison: noisy against what it is
                            compared with */
    char why[200];       /* why it is left out */
    double elapsed_s;    /* submission to end (runs the client ran), else 0 */
};

/* The runs a result holds, for series ("frame_ms", "gpu_ms", "cpu_ms"):
 * "gate_runs" (a result written by this client for several runs), else
 * "runs" of a repeated job, else the result itself as one run. Interference
 * comes from each run's "interference" when it has one, else the result's.
 * Runs recorded as noisy in gate_runs stay noisy. Returns the count (0 when
 * the series is absent) and a malloc'ed array in *out. */
size_t gate_runs_from_result(const json_t *result, const char *series, struct gate_run **out);

/* Fills one run from a single-run result (a job run by the gate). */
bool gate_run_from_result(const json_t *result, const char *job_id, const char *series,
                          struct gate_run *out);

/* The median other-process CPU share of the runs not already noisy; false
 * when none has interference figures. */
bool gate_typical_share(const struct gate_run *runs, size_t n, double *share);

/* A run's time as it might have been with the reference's CPU share: a
 * renderer is at most CPU-bound, so its time scales by at most
 * (1 + noise_cpu_left_change(share, reference)). upper = false gives the
 * smaller of the measured and the fully scaled time, upper = true the
 * larger: a slowdown that survives the new runs bounded down and the
 * baseline bounded up is one the CPU difference cannot explain. Without
 * interference figures, the measured time. */
double gate_run_bound_ms(const struct gate_run *r, bool have_reference, double reference,
                         bool upper);

/* Marks runs noisy (left out) by the noise rule (common/noise.h) against
 * what they are compared with: the CPU other processes left them differs
 * from the reference's by more than tolerance (NOISE_TOLERANCE, or
 * --noise-tolerance), either way. Without a reference share, a run the
 * daemon flagged noisy is marked. Runs without figures are kept (older
 * results). Returns the noisy count. */
size_t gate_mark_noisy(struct gate_run *runs, size_t n, bool have_reference, double reference,
                       double tolerance);

/* Copies the ms of the runs not marked noisy into values (capacity n);
 * returns how many. */
size_t gate_clean_values(const struct gate_run *runs, size_t n, double *values);

/* Why runs were noisy, in one clause for the log and JUnit: "3 of 8 runs
 * here were noisy: other processes took 41% to 79% of the CPU during them,
 * against a typical 12%" (what names the runs: "runs here", "baseline
 * runs", "pairs"; reference < 0 when there is no typical share). Writes ""
 * and returns 0 when none was noisy; returns the noisy count. */
size_t gate_noise_text(const struct gate_run *runs, size_t n, const char *what,
                       double reference, char *out, size_t cap);

/* The baseline gate on the runs so far: the baseline's runs marked against
 * their own typical share, the new runs against the baseline's (the
 * conditions the baseline was measured under; their own without figures),
 * then Welch on the clean ones. When too few are clean, or the interval is
 * too wide while noisy ones were left out, all the runs still decide if the
 * CPU difference cannot explain the result: new runs bounded down and the
 * baseline's up for a regression, the other way for a pass (bounded). */
void gate_evaluate_baseline(struct gate_run *base, size_t nb, struct gate_run *runs, size_t n,
                            double confidence, double min_effect, double tolerance,
                            struct gate_verdict *v);

/* ab on n pairs (a[i] and b[i] run side by side, alternately): a pair is
 * noisy when B's run had more than the tolerance more or less CPU left
 * than A's, each measured from its own side's typical share (a short and a
 * long job see different shares of the same neighbours, so comparing the
 * raw shares called every pair of unlike jobs noisy; a drift of the whole
 * machine moves both runs of a pair alike and leaves it clean). Then the
 * paired interval over the clean pairs, at least GATE_MIN_PAIRS of them.
 * With fewer, or an interval too wide while pairs were left out, every
 * pair with figures may decide bounded: each B lowered (a regression) or
 * raised (a pass) by as much as that relative CPU change could explain.
 * Fewer than GATE_MIN_PAIRS in all: inconclusive, saying so. */
void gate_evaluate_ab(struct gate_run *a, struct gate_run *b, size_t n, double confidence,
                      double min_effect, double tolerance, struct gate_verdict *v);

/* How many of runs[from..n) the verdict rests on: the clean ones, or when
 * it came from bounds every one with figures. A regression is confirmed
 * only by fresh runs that entered its verdict. For ab, runs are A's and a
 * pair's flag is on both sides. */
size_t gate_runs_in_verdict(const struct gate_run *runs, size_t n, size_t from, bool bounded);

/* The rerun policy the gate and ab share. After each evaluation: replace
 * noisy runs (pairs) until `planned` are clean, run another set while the
 * verdict is unclear, and confirm a regression on a fresh set, which
 * confirms it only by entering its verdict (gate_runs_in_verdict): noisy
 * confirming runs are replaced, and a regression whose fresh runs never
 * entered its verdict when the budget is spent is not confirmed. Without a
 * verdict to reach (decide false: runs for a later baseline), only noisy
 * runs are replaced. */
struct gate_reruns {
    size_t planned;        /* clean runs (pairs) wanted */
    int budget;            /* extra runs (pairs) left */
    bool decide;           /* rerun for unclear verdicts and regressions too */
    bool confirming;       /* a regression found before confirm_from */
    size_t confirm_from, confirm_need;
    const char *unit;      /* "run", "pair" */
};

struct gate_step {
    size_t more;             /* to run now; 0: stop */
    char say[800];           /* the log line for running more, "" when stopping */
    bool wanted_more;        /* more runs were wanted (stopped short: budget or noise) */
    bool budget_spent;       /* stopped, or ran short, with more wanted and no budget left */
    bool unconfirmed;        /* stopped with a regression its fresh runs did not confirm */
    char unconfirmed_why[600]; /* then: the verdict's sentence in its place */
};

/* The next step, from the n runs so far (runs: the new side's, or A's for
 * ab, whose pairs are marked on both sides), the verdict on them, and
 * whether the last set was all noisy (stop: the machine is busier than
 * when the compared runs were measured). Updates r (budget, confirming). */
void gate_next(struct gate_reruns *r, const struct gate_run *runs, size_t n,
               const struct gate_verdict *v, bool batch_noisy, struct gate_step *step);

/* What a verdict rests on, for its headline: "over 7 pairs (none left out)",
 * "over 7 pairs (3 clean, 4 noisy ones bounded by their CPU change)", "over
 * 5 baseline runs and 4 runs here (1 noisy run left out)", or "on too few
 * pairs for an interval". */
void gate_basis_text(const struct gate_verdict *v, bool paired, size_t total_old,
                     size_t total_new, char *out, size_t cap);

/* Fields of a job spec that never change what is timed: labels (tags),
 * repeat (how many runs, the gate chooses), capture_interval (captures are
 * read back outside the timed figures), reference, reference_look and
 * metrics (rendered and scored after the timed run), timeout_s. Every other
 * field must match. */
bool gate_nonsemantic_field(const char *top_level_key);

/* True when the specs differ in a field that matters; field gets its dotted
 * path and the two values ("scene.lights: 10 in the baseline, 80 here"). */
bool gate_spec_differs(const json_t *baseline_spec, const json_t *spec, char *what, size_t cap);

/* True when the devices differ: GL_RENDERER and GL_VERSION must match. */
bool gate_device_differs(const json_t *baseline_device, const json_t *device, char *what,
                         size_t cap);

/* The series that means something on this device: frame_ms on software
 * renderers (llvmpipe's GL_TIME_ELAPSED covers rasterization only), gpu_ms
 * on GPUs. */
const char *gate_default_series(const json_t *device);

#endif
