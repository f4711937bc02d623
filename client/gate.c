#define _POSIX_C_SOURCE 200809L
#include "client/gate.h"
#include "common/result_keys.h"
#include "common/timing_series.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *gate_outcome_name(enum gate_outcome o)
{
    switch (o) {
    case GATE_PASS: return "pass";
    case GATE_REGRESSION: return "regression";
    default: return "inconclusive";
    }
}

const struct gate_sides GATE_SIDES_BASELINE = {"in the baseline", "here"};
const struct gate_sides GATE_SIDES_AB = {"in A", "in B"};

void gate_decide(const struct ratio_interval *r, double min_effect, struct gate_verdict *out)
{
    gate_decide_sides(r, min_effect, &GATE_SIDES_BASELINE, out);
}

void gate_decide_sides(const struct ratio_interval *r, double min_effect,
                       const struct gate_sides *sides, struct gate_verdict *out)
{
    memset(out, 0, sizeof(*out));
    out->r = *r;
    out->min_effect = min_effect;
    out->used_old = out->clean_old = r->na;
    out->used_new = out->clean_new = r->nb;
    double limit = 1.0 + min_effect;
    int conf = (int)lround(r->confidence * 100);
    if (r->lo > 1.0 && r->ratio > limit) {
        out->outcome = GATE_REGRESSION;
        snprintf(out->why, sizeof(out->why),
                 "slower by %.1f%% (%d%% interval %+.1f%% to %+.1f%%), more than the %.1f%% allowed",
                 100 * (r->ratio - 1), conf, 100 * (r->lo - 1), 100 * (r->hi - 1),
                 100 * min_effect);
    } else if (r->hi <= limit) {
        out->outcome = GATE_PASS;
        snprintf(out->why, sizeof(out->why),
                 "%+.1f%% (%d%% interval %+.1f%% to %+.1f%%): a slowdown over %.1f%% is ruled out",
                 100 * (r->ratio - 1), conf, 100 * (r->lo - 1), 100 * (r->hi - 1),
                 100 * min_effect);
    } else {
        out->outcome = GATE_INCONCLUSIVE;
        if (r->ratio > limit)
            snprintf(out->why, sizeof(out->why),
                     "slower by %.1f%%, but the %d%% interval (%+.1f%% to %+.1f%%) reaches no "
                     "change: runs spread too much to tell (run-to-run spread %.1f%% %s, "
                     "%.1f%% %s)",
                     100 * (r->ratio - 1), conf, 100 * (r->lo - 1), 100 * (r->hi - 1),
                     100 * r->cv_a, sides->old_side, 100 * r->cv_b, sides->new_side);
        else
            snprintf(out->why, sizeof(out->why),
                     "%+.1f%%, but the %d%% interval reaches %+.1f%%: a slowdown over the %.1f%% "
                     "allowed is not ruled out (run-to-run spread %.1f%% %s, %.1f%% %s)",
                     100 * (r->ratio - 1), conf, 100 * (r->hi - 1), 100 * min_effect,
                     100 * r->cv_a, sides->old_side, 100 * r->cv_b, sides->new_side);
    }
}

void gate_compare(const double *baseline, size_t nb, const double *current, size_t nc,
                  double confidence, double min_effect, struct gate_verdict *out)
{
    struct ratio_interval r;
    if (nc < 2 || nb < 1 || !welch_log_ratio(baseline, nb, current, nc, confidence, &r)) {
        memset(out, 0, sizeof(*out));
        out->outcome = GATE_INCONCLUSIVE;
        out->min_effect = min_effect;
        out->r.na = nb;
        out->r.nb = nc;
        out->r.confidence = confidence;
        snprintf(out->why, sizeof(out->why),
                 "too few usable runs to compare (%zu in the baseline, %zu here; at least 1 and "
                 "2, and 3 in all)", nb, nc);
        out->clean_old = nb;
        out->clean_new = nc;
        return;
    }
    gate_decide(&r, min_effect, out);
}

static void read_interference(const json_t *inter, struct gate_run *run)
{
    json_t *share = json_object_get(inter, "other_cpu_share");
    run->has_share = json_is_number(share);
    run->other_share = run->has_share ? json_number_value(share) : NAN;
    json_t *ls = json_array_get(json_object_get(inter, "loadavg_start"), 0);
    json_t *le = json_array_get(json_object_get(inter, "loadavg_end"), 0);
    run->load_start = json_is_number(ls) ? json_number_value(ls) : NAN;
    run->load_end = json_is_number(le) ? json_number_value(le) : NAN;
    run->daemon_noisy = json_is_true(json_object_get(inter, "noisy"));
    /* Alone, by the one rule; the daemon's flag where there are no figures
     * (a daemon from before the rule had its own). */
    run->noisy_alone = noise_interference_noisy(inter);
}

static double series_median(const json_t *holder, const char *series)
{
    json_t *m = json_object_get(json_object_get(holder, series), RK_MEDIAN);
    return json_is_number(m) ? json_number_value(m) : NAN;
}

bool gate_run_from_result(const json_t *result, const char *job_id, const char *series,
                          struct gate_run *out)
{
    memset(out, 0, sizeof(*out));
    snprintf(out->job, sizeof(out->job), "%s", job_id ? job_id : "");
    out->ms = series_median(result, series);
    read_interference(json_object_get(result, RK_INTERFERENCE), out);
    return isfinite(out->ms);
}

size_t gate_runs_from_result(const json_t *result, const char *series, struct gate_run **out)
{
    *out = NULL;
    json_t *gate_runs = json_object_get(result, "gate_runs");
    json_t *runs = json_object_get(result, RK_RUNS);
    json_t *list = json_array_size(gate_runs) ? gate_runs : json_array_size(runs) ? runs : NULL;
    size_t n = list ? json_array_size(list) : 1;
    struct gate_run *v = calloc(n, sizeof(*v));
    if (!v)
        return 0;
    size_t kept = 0;
    const char *result_job = json_string_value(json_object_get(result, "job_id"));
    if (!list) {
        if (gate_run_from_result(result, result_job, series, &v[0]))
            kept = 1;
    } else {
        json_t *job_inter = json_object_get(result, RK_INTERFERENCE);
        for (size_t i = 0; i < n; i++) {
            json_t *r = json_array_get(list, i);
            struct gate_run *g = &v[kept];
            memset(g, 0, sizeof(*g));
            /* gate_runs hold the median itself; a repeated job's runs hold
             * each series' statistics. */
            json_t *m = json_object_get(r, series);
            g->ms = json_is_number(m) ? json_number_value(m) : series_median(r, series);
            const char *job = json_string_value(json_object_get(r, "job"));
            snprintf(g->job, sizeof(g->job), "%s", job ? job : result_job ? result_job : "");
            json_t *inter = json_object_get(r, RK_INTERFERENCE);
            read_interference(inter ? inter : job_inter, g);
            if (json_is_true(json_object_get(r, "noisy"))) {
                g->noisy = true;
                const char *why = json_string_value(json_object_get(r, "why"));
                snprintf(g->why, sizeof(g->why), "%s", why ? why : "recorded as noisy");
            }
            if (isfinite(g->ms) && g->ms > 0)
                kept++;
        }
    }
    if (!kept) {
        free(v);
        return 0;
    }
    *out = v;
    return kept;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

bool gate_typical_share(const struct gate_run *runs, size_t n, double *share)
{
    double *v = malloc((n ? n : 1) * sizeof(double));
    size_t k = 0;
    for (size_t i = 0; v && i < n; i++)
        if (runs[i].has_share && !runs[i].noisy)
            v[k++] = runs[i].other_share;
    if (k) {
        qsort(v, k, sizeof(double), cmp_double);
        *share = k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
    }
    free(v);
    return k > 0;
}

double gate_run_bound_ms(const struct gate_run *r, bool have_reference, double reference,
                         bool upper)
{
    if (!r->has_share || !have_reference)
        return r->ms;
    double scaled = r->ms * (1.0 + noise_cpu_left_change(r->other_share, reference));
    return upper ? fmax(r->ms, scaled) : fmin(r->ms, scaled);
}

size_t gate_mark_noisy(struct gate_run *runs, size_t n, bool have_reference, double reference,
                       double tolerance)
{
    size_t noisy = 0;
    for (size_t i = 0; i < n; i++) {
        struct gate_run *r = &runs[i];
        double change = r->has_share ? noise_cpu_left_change(r->other_share, reference) : 0.0;
        if (!r->noisy && r->has_share && have_reference &&
            noise_exceeds(r->other_share, reference, tolerance)) {
            r->noisy = true;
            snprintf(r->why, sizeof(r->why),
                     "other processes used %.0f%% of the CPU during it, against %.0f%% for the "
                     "runs it is compared with: %.0f%% %s CPU left (tolerance %.0f%%)",
                     100 * r->other_share, 100 * reference, 100 * fabs(change),
                     change < 0 ? "less" : "more", 100 * tolerance);
        } else if (!r->noisy && !have_reference && r->daemon_noisy) {
            r->noisy = true;
            snprintf(r->why, sizeof(r->why), "the daemon marked it noisy (load %.2f to %.2f)",
                     r->load_start, r->load_end);
        }
        noisy += r->noisy;
    }
    return noisy;
}

size_t gate_clean_values(const struct gate_run *runs, size_t n, double *values)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (!runs[i].noisy)
            values[k++] = runs[i].ms;
    return k;
}

size_t gate_noise_text(const struct gate_run *runs, size_t n, const char *what,
                       double reference, char *out, size_t cap)
{
    size_t noisy = 0, with_share = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (!runs[i].noisy)
            continue;
        noisy++;
        if (runs[i].has_share) {
            with_share++;
            lo = fmin(lo, runs[i].other_share);
            hi = fmax(hi, runs[i].other_share);
        }
    }
    out[0] = '\0';
    if (!noisy)
        return 0;
    int used = snprintf(out, cap, "%zu of %zu %s %s noisy", noisy, n, what,
                        noisy == 1 ? "was" : "were");
    if (used < 0 || (size_t)used >= cap)
        return noisy;
    if (with_share) {
        char range[48];
        if (lround(100 * lo) == lround(100 * hi))
            snprintf(range, sizeof(range), "%.0f%%", 100 * hi);
        else
            snprintf(range, sizeof(range), "%.0f%% to %.0f%%", 100 * lo, 100 * hi);
        used += snprintf(out + used, cap - (size_t)used,
                         ": other processes took %s of the CPU during %s", range,
                         noisy == 1 ? "it" : "them");
        if (reference >= 0 && (size_t)used < cap)
            snprintf(out + used, cap - (size_t)used, ", against a typical %.0f%%",
                     100 * reference);
    } else {
        snprintf(out + used, cap - (size_t)used, ": the daemon flagged %s (no CPU figures)",
                 noisy == 1 ? "it" : "them");
    }
    return noisy;
}

/* How much more (> 0) or less CPU B's run of a pair had left than A's,
 * each relative to its side's typical share (ra, rb). */
static double ab_pair_change(const struct gate_run *a, double ra, const struct gate_run *b,
                             double rb)
{
    double left_a = (1.0 - a->other_share) / fmax(1.0 - ra, 0.01);
    double left_b = (1.0 - b->other_share) / fmax(1.0 - rb, 0.01);
    return left_b / fmax(left_a, 0.01) - 1.0;
}

/* Tries to settle an undecided comparison on every run with figures, each
 * bounded by its CPU change against its reference (what_old and what_new:
 * the typical shares), new runs down and old ones up for a regression, the
 * other way for a pass. paired: ab's pairs (a pair enters when both runs
 * have figures). True with v filled when one holds. */
static bool bounded_verdict(const struct gate_run *old, size_t nold, bool have_old,
                            double ref_old, const struct gate_run *cur, size_t ncur,
                            bool have_new, double ref_new, bool paired, double confidence,
                            double min_effect, struct gate_verdict *v)
{
    double *ov = malloc((nold + 1) * sizeof(double)), *nv = malloc((ncur + 1) * sizeof(double));
    bool settled = false;
    for (int upper = 0; ov && nv && upper <= 1 && !settled; upper++) {
        size_t no = 0, nn = 0;
        if (paired) {
            /* B's run bounded by its CPU change against A's run, each from
             * its side's typical share: a CPU-bound renderer at most slows
             * down in proportion. */
            for (size_t i = 0; i < nold && i < ncur; i++) {
                if (!old[i].has_share || !cur[i].has_share || !have_old || !have_new)
                    continue;
                double scaled =
                    cur[i].ms * (1.0 + ab_pair_change(&old[i], ref_old, &cur[i], ref_new));
                ov[no++] = old[i].ms;
                nv[nn++] = upper ? fmax(cur[i].ms, scaled) : fmin(cur[i].ms, scaled);
            }
        } else {
            if (!have_old && !have_new)
                break;
            for (size_t i = 0; i < nold; i++)
                ov[no++] = gate_run_bound_ms(&old[i], have_old, ref_old, !upper);
            for (size_t i = 0; i < ncur; i++)
                nv[nn++] = gate_run_bound_ms(&cur[i], have_new, ref_new, upper);
        }
        struct ratio_interval r;
        bool ok = paired ? no >= GATE_MIN_PAIRS && paired_log_ratio(ov, nv, no, confidence, &r)
                         : nn >= 2 && no + nn >= 3 &&
                               welch_log_ratio(ov, no, nv, nn, confidence, &r);
        if (!ok)
            continue;
        struct gate_verdict b;
        gate_decide_sides(&r, min_effect, paired ? &GATE_SIDES_AB : &GATE_SIDES_BASELINE, &b);
        if (b.outcome != (upper ? GATE_PASS : GATE_REGRESSION))
            continue;
        size_t clean_old = v->clean_old, clean_new = v->clean_new;
        *v = b;
        v->bounded = true;
        v->clean_old = clean_old;
        v->clean_new = clean_new;
        size_t used = strlen(v->why);
        if (paired)
            snprintf(v->why + used, sizeof(v->why) - used,
                     " (over all %zu pairs, noisy ones included, each B's time %s by as much as "
                     "the CPU its run %s against A's, each from its side's typical run, could "
                     "explain)", no, upper ? "raised" : "lowered",
                     upper ? "had in excess" : "lacked");
        else
            snprintf(v->why + used, sizeof(v->why) - used,
                     " (over all runs, noisy ones included, each bounded by as much as its "
                     "CPU change against the typical %.0f%% taken by other processes could "
                     "explain)", 100 * (have_old ? ref_old : ref_new));
        settled = true;
    }
    free(ov);
    free(nv);
    return settled;
}

void gate_evaluate_baseline(struct gate_run *base, size_t nb, struct gate_run *runs, size_t n,
                            double confidence, double min_effect, double tolerance,
                            struct gate_verdict *v)
{
    double ref = 0;
    bool have = gate_typical_share(base, nb, &ref);
    gate_mark_noisy(base, nb, have, ref, tolerance);
    for (size_t i = 0; i < n; i++) {
        runs[i].noisy = false;
        runs[i].why[0] = '\0';
    }
    if (!have)
        have = gate_typical_share(runs, n, &ref);
    gate_mark_noisy(runs, n, have, ref, tolerance);
    double *bv = malloc((nb + 1) * sizeof(double)), *cv = malloc((n + 1) * sizeof(double));
    size_t nbc = bv ? gate_clean_values(base, nb, bv) : 0;
    size_t ncc = cv ? gate_clean_values(runs, n, cv) : 0;
    gate_compare(bv, nbc, cv, ncc, confidence, min_effect, v);
    v->clean_old = nbc;
    v->clean_new = ncc;
    bool too_few = v->used_old == 0 && v->used_new == 0;
    bool undecided = v->outcome == GATE_INCONCLUSIVE && bv && cv;
    bool settled = undecided && (too_few || nbc < nb || ncc < n) &&
                   bounded_verdict(base, nb, have, ref, runs, n, have, ref, false, confidence,
                                   min_effect, v);
    if (too_few && !settled && bv && cv) {
        /* Too few clean runs to decide: still say what all the runs, noisy
         * ones included, say, so that the log is not empty. */
        for (size_t i = 0; i < nb; i++)
            bv[i] = base[i].ms;
        for (size_t i = 0; i < n; i++)
            cv[i] = runs[i].ms;
        struct ratio_interval all;
        if (welch_log_ratio(bv, nb, cv, n, confidence, &all)) {
            v->r = all;
            size_t used = strlen(v->why);
            snprintf(v->why + used, sizeof(v->why) - used,
                     "; over all runs, noisy ones included: %+.1f%% (%.0f%% interval %+.1f%% to "
                     "%+.1f%%), not a verdict", 100 * (all.ratio - 1), 100 * confidence,
                     100 * (all.lo - 1), 100 * (all.hi - 1));
        }
    }
    free(bv);
    free(cv);
}

void gate_evaluate_ab(struct gate_run *a, struct gate_run *b, size_t n, double confidence,
                      double min_effect, double tolerance, struct gate_verdict *v)
{
    memset(v, 0, sizeof(*v));
    v->outcome = GATE_INCONCLUSIVE;
    v->min_effect = min_effect;
    v->r.confidence = confidence;
    snprintf(v->why, sizeof(v->why), "no interval: a run without a positive time");
    for (size_t i = 0; i < n; i++) {
        a[i].noisy = b[i].noisy = false;
        a[i].why[0] = b[i].why[0] = '\0';
    }
    /* The two runs of a pair against each other, each measured from its
     * own side's typical run: the pairs alternate on one machine, so both
     * sides meet the same neighbours, but a longer job measures a different
     * share of them than a shorter one (A steady at 10% and B at 50% is
     * like with like), and a drift of the whole machine moves both runs of
     * a pair alike. A pair is noisy when B's run had more than the
     * tolerance more or less CPU left than A's, relative to their sides. */
    double ra = 0, rb = 0;
    bool ha = gate_typical_share(a, n, &ra), hb = gate_typical_share(b, n, &rb);
    double *va = malloc((n + 1) * sizeof(double)), *vb = malloc((n + 1) * sizeof(double));
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        bool figures = a[i].has_share && b[i].has_share && ha && hb;
        double rel = figures ? ab_pair_change(&a[i], ra, &b[i], rb) : 0.0;
        if (figures && fabs(rel) > tolerance) {
            snprintf(a[i].why, sizeof(a[i].why),
                     "B's run had %.0f%% %s CPU left than A's, each against its side's typical "
                     "run (others took %.0f%% during A's, typically %.0f%%; %.0f%% during B's, "
                     "typically %.0f%%; tolerance %.0f%%)", 100 * fabs(rel),
                     rel < 0 ? "less" : "more", 100 * a[i].other_share, 100 * ra,
                     100 * b[i].other_share, 100 * rb, 100 * tolerance);
            a[i].noisy = b[i].noisy = true;
        } else if (!figures && (a[i].daemon_noisy || b[i].daemon_noisy)) {
            snprintf(a[i].why, sizeof(a[i].why), "the daemon marked %s's run noisy (no CPU "
                     "figures to compare)", a[i].daemon_noisy ? "A" : "B");
            a[i].noisy = b[i].noisy = true;
        }
        if (a[i].noisy) {
            snprintf(b[i].why, sizeof(b[i].why), "%s", a[i].why);
        } else if (va && vb) {
            va[k] = a[i].ms;
            vb[k++] = b[i].ms;
        }
    }
    struct ratio_interval r;
    bool decided = false;
    if (k >= GATE_MIN_PAIRS && paired_log_ratio(va, vb, k, confidence, &r)) {
        gate_decide_sides(&r, min_effect, &GATE_SIDES_AB, v);
        decided = v->outcome != GATE_INCONCLUSIVE || k == n;
    }
    if (!decided) {
        size_t clean = k;
        v->clean_old = v->clean_new = clean;
        if (!bounded_verdict(a, n, ha, ra, b, n, hb, rb, true, confidence, min_effect, v) &&
            k < GATE_MIN_PAIRS) {
            memset(v, 0, sizeof(*v));
            v->outcome = GATE_INCONCLUSIVE;
            v->min_effect = min_effect;
            v->r.confidence = confidence;
            v->clean_old = v->clean_new = clean;
            snprintf(v->why, sizeof(v->why),
                     "too few clean pairs to decide: %zu of %zu (a verdict needs at least %d)",
                     clean, n, GATE_MIN_PAIRS);
            for (size_t i = 0; va && vb && i < n; i++) {
                va[i] = a[i].ms;
                vb[i] = b[i].ms;
            }
            if (va && vb && n >= 2 && paired_log_ratio(va, vb, n, confidence, &r)) {
                v->r = r;
                v->r.na = v->r.nb = 0; /* not what a verdict rests on */
                size_t used = strlen(v->why);
                snprintf(v->why + used, sizeof(v->why) - used,
                         "; over all %zu pairs, noisy ones included: B/A %.4f [%.4f, %.4f], not a "
                         "verdict", n, r.ratio, r.lo, r.hi);
            }
        }
    }
    free(va);
    free(vb);
}

size_t gate_runs_in_verdict(const struct gate_run *runs, size_t n, size_t from, bool bounded)
{
    size_t k = 0;
    for (size_t i = from; i < n; i++)
        k += bounded ? runs[i].has_share || !runs[i].noisy : !runs[i].noisy;
    return k;
}

void gate_next(struct gate_reruns *r, const struct gate_run *runs, size_t n,
               const struct gate_verdict *v, bool batch_noisy, struct gate_step *step)
{
    memset(step, 0, sizeof(*step));
    size_t clean = 0;
    for (size_t i = 0; i < n; i++)
        clean += !runs[i].noisy;
    bool regression = r->decide && v->outcome == GATE_REGRESSION;
    size_t confirmed_by = r->confirming && regression
                              ? gate_runs_in_verdict(runs, n, r->confirm_from, v->bounded)
                              : 0;
    bool want_confirm = r->confirming && regression && confirmed_by < r->confirm_need;
    bool wants_more = clean < r->planned || want_confirm ||
                      (r->decide && (v->outcome == GATE_INCONCLUSIVE ||
                                     (regression && !r->confirming)));
    size_t budget = r->budget > 0 ? (size_t)r->budget : 0;
    step->wanted_more = wants_more;
    step->budget_spent = wants_more && budget == 0;
    if (want_confirm && (budget == 0 || batch_noisy)) {
        step->unconfirmed = true;
        snprintf(step->unconfirmed_why, sizeof(step->unconfirmed_why),
                 "a possible regression (%.360s) could not be confirmed: only %zu of the %zu %ss "
                 "made to confirm it entered the verdict (%zu wanted), the rest were noisy",
                 v->why, confirmed_by, n - r->confirm_from, r->unit, r->confirm_need);
        return;
    }
    if (budget == 0 || batch_noisy || !wants_more)
        return;
    size_t batch = r->planned < budget ? r->planned : budget, more;
    if (want_confirm) {
        more = r->confirm_need - confirmed_by;
        more = more < budget ? more : budget;
        snprintf(step->say, sizeof(step->say),
                 "%zu of the %ss confirming the regression were noisy: running %zu more (%zu "
                 "extra left)", n - r->confirm_from - confirmed_by, r->unit, more, budget - more);
    } else if (clean < r->planned && !(r->confirming && regression)) {
        more = r->planned - clean < budget ? r->planned - clean : budget;
        snprintf(step->say, sizeof(step->say),
                 "%zu noisy %s(s) left out: running %zu more (%zu extra left)", n - clean, r->unit,
                 more, budget - more);
    } else if (regression && !r->confirming) {
        /* A regression must hold on fresh runs too before it fails a
         * build: one unlucky set is not enough. */
        more = batch;
        r->confirming = true;
        r->confirm_from = n;
        r->confirm_need = batch;
        snprintf(step->say, sizeof(step->say), "possible regression (%.600s): confirming on %zu "
                 "more %ss", v->why, more, r->unit);
    } else if (r->decide && v->outcome == GATE_INCONCLUSIVE) {
        more = batch;
        snprintf(step->say, sizeof(step->say), "inconclusive (%.600s): running %zu more %ss (%zu "
                 "extra left)", v->why, more, r->unit, budget - more);
    } else {
        return;
    }
    step->more = more;
    r->budget -= (int)more;
}

void gate_basis_text(const struct gate_verdict *v, bool paired, size_t total_old,
                     size_t total_new, char *out, size_t cap)
{
    if (!v->used_old && !v->used_new) {
        snprintf(out, cap, "on too few %s for an interval", paired ? "pairs" : "runs");
        return;
    }
    if (paired) {
        if (v->bounded)
            snprintf(out, cap, "over %zu pairs (%zu clean, %zu noisy ones bounded by their CPU "
                     "change)", v->used_new, v->clean_new, v->used_new - v->clean_new);
        else if (v->used_new < total_new)
            snprintf(out, cap, "over %zu pairs (%zu noisy pair%s left out)", v->used_new,
                     total_new - v->used_new, total_new - v->used_new == 1 ? "" : "s");
        else
            snprintf(out, cap, "over %zu pairs (none left out)", v->used_new);
        return;
    }
    size_t left_out = v->bounded ? 0 : (total_old - v->used_old) + (total_new - v->used_new);
    if (v->bounded)
        snprintf(out, cap, "over %zu baseline runs and %zu runs here (%zu noisy ones bounded by "
                 "their CPU change)", v->used_old, v->used_new,
                 (v->used_old - v->clean_old) + (v->used_new - v->clean_new));
    else if (left_out)
        snprintf(out, cap, "over %zu baseline runs and %zu runs here (%zu noisy run%s left out)",
                 v->used_old, v->used_new, left_out, left_out == 1 ? "" : "s");
    else
        snprintf(out, cap, "over %zu baseline runs and %zu runs here (none left out)", v->used_old,
                 v->used_new);
}

bool gate_nonsemantic_field(const char *key)
{
    static const char *const skip[] = {"labels", "repeat", "capture_interval", "reference",
                                       "metrics", "timeout_s", "reference_look", NULL};
    for (const char *const *s = skip; *s; s++)
        if (strcmp(*s, key) == 0)
            return true;
    return false;
}

static void value_text(const json_t *v, char *out, size_t cap)
{
    if (!v) {
        snprintf(out, cap, "absent");
        return;
    }
    char *t = json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT);
    snprintf(out, cap, "%.60s%s", t ? t : "?", t && strlen(t) > 60 ? "..." : "");
    free(t);
}

/* Numbers compare by value (the daemon may write 20 or 20.0). */
static bool same_value(const json_t *a, const json_t *b)
{
    if (json_is_number(a) && json_is_number(b))
        return json_number_value(a) == json_number_value(b);
    return json_equal((json_t *)a, (json_t *)b);
}

static bool differs(const json_t *a, const json_t *b, const char *path, bool top, char *what,
                    size_t cap)
{
    if (json_is_object(a) && json_is_object(b)) {
        const char *key;
        json_t *v;
        for (int pass = 0; pass < 2; pass++) {
            const json_t *one = pass ? b : a, *other = pass ? a : b;
            json_object_foreach((json_t *)one, key, v) {
                if (top && gate_nonsemantic_field(key))
                    continue;
                if (pass && json_object_get(other, key))
                    continue; /* compared in the first pass */
                char sub[160];
                snprintf(sub, sizeof(sub), "%s%s%s", path, path[0] ? "." : "", key);
                const json_t *x = pass ? json_object_get(other, key) : v;
                const json_t *y = pass ? v : json_object_get(other, key);
                if (differs(x, y, sub, false, what, cap))
                    return true;
            }
        }
        return false;
    }
    if (a && b && same_value(a, b))
        return false;
    char ta[80], tb[80];
    value_text(a, ta, sizeof(ta));
    value_text(b, tb, sizeof(tb));
    snprintf(what, cap, "%s: %s in the baseline, %s here", path[0] ? path : "spec", ta, tb);
    return true;
}

bool gate_spec_differs(const json_t *baseline_spec, const json_t *spec, char *what, size_t cap)
{
    what[0] = '\0';
    return differs(baseline_spec, spec, "", true, what, cap);
}

bool gate_device_differs(const json_t *baseline_device, const json_t *device, char *what,
                         size_t cap)
{
    static const char *const keys[] = {"gl_renderer", "gl_version"};
    for (int k = 0; k < 2; k++) {
        const char *a = json_string_value(json_object_get(baseline_device, keys[k]));
        const char *b = json_string_value(json_object_get(device, keys[k]));
        if (!a || !b || strcmp(a, b) != 0) {
            snprintf(what, cap, "%s: \"%s\" in the baseline, \"%s\" here", keys[k],
                     a ? a : "(none)", b ? b : "(none)");
            return true;
        }
    }
    what[0] = '\0';
    return false;
}

const char *gate_default_series(const json_t *device)
{
    return timing_series_for_renderer(json_string_value(json_object_get(device, "gl_renderer")));
}
