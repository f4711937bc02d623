/* ab: two jobs (or one job on two daemons) run alternately, paired, and
 * compared as the ratio B/A with its confidence interval. Alternating keeps
 * the ratio meaningful when the machine's speed drifts: each pair sees the
 * same conditions, and the order within a pair flips every time (A B, B A,
 * A B, ...) so that a steady drift favours neither side. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/client.h"
#include "client/gate.h"
#include "client/junit.h"
#include "client/verdicts.h"
#include "common/fsutil.h"
#include "common/result_keys.h"

/* A pair is noisy when its two runs saw different conditions: other
 * processes left one of them more than the tolerance more or less CPU than
 * the other (or, without figures, the daemon flagged either). */
static void mark_pairs(struct run_set *sa, struct run_set *sb, double tolerance)
{
    for (size_t i = 0; i < sa->n && i < sb->n; i++) {
        struct gate_run *a = &sa->runs[i], *b = &sb->runs[i];
        a->noisy = b->noisy = false;
        a->why[0] = b->why[0] = '\0';
        if (a->has_share && b->has_share &&
            fabs(gate_cpu_left_change(b->other_share, a->other_share)) > tolerance) {
            snprintf(a->why, sizeof(a->why), "other processes used %.0f%% of the CPU during A "
                     "and %.0f%% during B", 100 * a->other_share, 100 * b->other_share);
            a->noisy = b->noisy = true;
        } else if ((!a->has_share || !b->has_share) && (a->daemon_noisy || b->daemon_noisy)) {
            snprintf(a->why, sizeof(a->why), "the daemon marked the %s run noisy",
                     a->daemon_noisy ? "A" : "B");
            a->noisy = b->noisy = true;
        }
        if (b->noisy)
            snprintf(b->why, sizeof(b->why), "%s", a->why);
    }
}

static size_t clean_pairs(const struct run_set *sa, const struct run_set *sb, double *a, double *b)
{
    size_t k = 0;
    for (size_t i = 0; i < sa->n && i < sb->n; i++)
        if (!sa->runs[i].noisy) {
            a[k] = sa->runs[i].ms;
            b[k++] = sb->runs[i].ms;
        }
    return k;
}

/* With too few clean pairs to decide, the noisy ones still decide when the CPU their
 * runs were short of cannot explain the difference: a regression if B/A
 * stays one with every B bounded down by its pair's CPU change, a pass if it
 * stays one with every B bounded up. (A 20-fold slowdown is not made
 * undecidable by a busy machine.) Uses va and vb (sa->n each) as scratch;
 * false when neither holds. */
static bool bounded_verdict(const struct run_set *sa, const struct run_set *sb,
                            const struct options *o, double *va, double *vb,
                            struct gate_verdict *v)
{
    for (int upper = 0; upper <= 1; upper++) {
        size_t m = 0;
        for (size_t i = 0; i < sa->n && i < sb->n; i++) {
            const struct gate_run *a = &sa->runs[i], *b = &sb->runs[i];
            if (!a->has_share || !b->has_share)
                continue;
            va[m] = a->ms;
            vb[m++] = gate_pair_bound_ms(a, b, upper);
        }
        struct ratio_interval r;
        if (m < 2 || !paired_log_ratio(va, vb, m, o->confidence, &r))
            return false;
        struct gate_verdict bounded;
        gate_decide_sides(&r, o->max_slowdown, &GATE_SIDES_AB, &bounded);
        if (bounded.outcome == (upper ? GATE_PASS : GATE_REGRESSION)) {
            *v = bounded;
            size_t used = strlen(v->why);
            snprintf(v->why + used, sizeof(v->why) - used,
                     " (over %zu pairs, noisy ones included, each B's time %s by as much as "
                     "the CPU its run %s could explain)", m, upper ? "raised" : "lowered",
                     upper ? "had over A's" : "lacked against A's");
            return true;
        }
    }
    return false;
}

int cmd_ab(struct conn *ca, struct conn *cb, const struct options *o, const char *file_a,
           const char *file_b)
{
    double t0 = clock_mono_s();
    char err[600];
    int rc = EXIT_ERROR;
    if (o->baseline) {
        fprintf(stderr, "shadebench: ab compares A with B; --baseline belongs to submit\n");
        return EXIT_ERROR;
    }
    if (o->out_dir && !out_dir_claim(o->out_dir, "ab.json", NULL, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    struct run_set sa, sb;
    run_set_init(&sa, ca, "A");
    run_set_init(&sb, cb, "B");
    struct junit j;
    junit_init(&j);
    char *ta = job_text_for_submit(file_a, o, 1, err, sizeof(err));
    char *tb = ta ? job_text_for_submit(file_b, o, 1, err, sizeof(err)) : NULL;
    json_t *info_a = NULL, *info_b = NULL, *summary = NULL;
    double *va = NULL, *vb = NULL;
    if (!ta || !tb) {
        fprintf(stderr, "shadebench: %s\n", err);
        goto out;
    }
    if (!(info_a = conn_json(ca, "GET", "/v1/info", NULL, NULL)) ||
        !(info_b = conn_json(cb, "GET", "/v1/info", NULL, NULL)))
        goto out;
    json_t *dev_a = json_object_get(info_a, "device"), *dev_b = json_object_get(info_b, "device");
    const char *series = o->series ? o->series : gate_default_series(dev_a);
    if (strcmp(gate_default_series(dev_a), gate_default_series(dev_b)) != 0 && !o->series)
        fprintf(stderr, "shadebench: warning: A and B run on different kinds of device; "
                "comparing %s\n", series);
    size_t planned = (size_t)(o->runs ? o->runs : 5), target = planned;
    int budget = o->max_reruns;
    bool confirmed = false;
    struct gate_verdict v;
    memset(&v, 0, sizeof(v));
    size_t nclean = 0;
    char stop_reason[160] = "";
    sa.planned = sb.planned = planned;
    sa.budget = sb.budget = budget;
    if (!o->quiet)
        fprintf(stderr, "A: %s on %s\nB: %s on %s\n%zu clean pairs wanted, alternating, judged on "
                "%s; at most %d extra pairs for noisy pairs, an unclear verdict or confirming "
                "that B is slower (--max-reruns)\n", file_a, ca->server, file_b, cb->server,
                planned, series, budget);
    for (;;) {
        while (sa.n < target && !sa.failed && !sb.failed) {
            /* A B, then B A: the order flips each pair. */
            bool a_first = sa.n % 2 == 0;
            struct run_set *first = a_first ? &sa : &sb, *second = a_first ? &sb : &sa;
            if (!run_set_add(first, o, a_first ? ta : tb, series, NULL, NULL) || first->failed ||
                !run_set_add(second, o, a_first ? tb : ta, series, NULL, NULL))
                goto out;
        }
        if (sa.failed || sb.failed)
            break;
        mark_pairs(&sa, &sb, o->noise_tolerance);
        free(va);
        free(vb);
        va = malloc(sa.n * sizeof(double));
        vb = malloc(sb.n * sizeof(double));
        if (!va || !vb)
            goto out;
        nclean = clean_pairs(&sa, &sb, va, vb);
        struct ratio_interval r;
        if (nclean >= 2 && paired_log_ratio(va, vb, nclean, o->confidence, &r)) {
            gate_decide_sides(&r, o->max_slowdown, &GATE_SIDES_AB, &v);
            /* Two or three clean pairs give an interval too wide to decide
             * on; the noisy ones, bounded, may still settle it. */
            if (v.outcome == GATE_INCONCLUSIVE && nclean < sa.n)
                bounded_verdict(&sa, &sb, o, va, vb, &v);
        } else if (!bounded_verdict(&sa, &sb, o, va, vb, &v)) {
            /* Too few clean pairs to decide; still report all the pairs. */
            memset(&v, 0, sizeof(v));
            v.outcome = GATE_INCONCLUSIVE;
            snprintf(v.why, sizeof(v.why), "too few clean pairs (%zu of %zu)", nclean, sa.n);
            for (size_t i = 0; i < sa.n; i++) {
                va[i] = sa.runs[i].ms;
                vb[i] = sb.runs[i].ms;
            }
            if (paired_log_ratio(va, vb, sa.n, o->confidence, &r)) {
                v.r = r;
                size_t used = strlen(v.why);
                snprintf(v.why + used, sizeof(v.why) - used,
                         "; over all pairs, noisy ones included: B/A %.4f [%.4f, %.4f], not a "
                         "verdict", r.ratio, r.lo, r.hi);
            }
        }
        if (budget <= 0) {
            if (nclean < planned || v.outcome == GATE_INCONCLUSIVE ||
                (v.outcome == GATE_REGRESSION && !confirmed))
                snprintf(stop_reason, sizeof(stop_reason),
                         "all %d extra pairs (--max-reruns) used", o->max_reruns);
            break;
        }
        size_t batch = planned < (size_t)budget ? planned : (size_t)budget;
        if (nclean < planned) {
            size_t need = planned - nclean < (size_t)budget ? planned - nclean : (size_t)budget;
            if (!o->quiet)
                fprintf(stderr, "%zu noisy pair(s) left out: running %zu more (%d extra left)\n",
                        sa.n - nclean, need, budget - (int)need);
            target += need;
            budget -= (int)need;
            continue;
        }
        if ((v.outcome == GATE_REGRESSION && !confirmed) || v.outcome == GATE_INCONCLUSIVE) {
            if (!o->quiet)
                fprintf(stderr, "%s (%s): running %zu more pairs (%d extra left)\n",
                        v.outcome == GATE_REGRESSION ? "B looks slower" : "inconclusive", v.why,
                        batch, budget - (int)batch);
            confirmed = confirmed || v.outcome == GATE_REGRESSION;
            target += batch;
            budget -= (int)batch;
            continue;
        }
        break;
    }

    json_t *ja = sa.n ? json_array_get(sa.jobs, 0) : sa.failed;
    json_t *jb = sb.n ? json_array_get(sb.jobs, 0) : sb.failed;
    /* Names from the job files as written (a daemon default renames
     * nothing). */
    json_t *spec_a = json_loads(ta, 0, NULL), *spec_b = json_loads(tb, 0, NULL);
    char name_a[320], name_b[320], cls[96], name[700];
    junit_job_name(spec_a, name_a, sizeof(name_a));
    junit_job_name(spec_b, name_b, sizeof(name_b));
    if (ca != cb) {
        snprintf(name_a + strlen(name_a), sizeof(name_a) - strlen(name_a), " on A");
        snprintf(name_b + strlen(name_b), sizeof(name_b) - strlen(name_b), " on B");
    }
    /* Each job case times its own (first) run; the comparison all of them. */
    job_classname(spec_a, cls, sizeof(cls));
    job_case(&j, cls, name_a, sa.failed ? sa.failed : ja, sa.n ? sa.runs[0].elapsed_s : sa.elapsed_s);
    job_classname(spec_b, cls, sizeof(cls));
    job_case(&j, cls, name_b, sb.failed ? sb.failed : jb, sb.n ? sb.runs[0].elapsed_s : sb.elapsed_s);
    json_decref(spec_a);
    json_decref(spec_b);
    snprintf(name, sizeof(name), "%s against %s: %s B/A", name_b, name_a, series);
    if (!sa.failed && !sb.failed) {
        /* Why pairs were noisy: the runs of both sides, together. */
        char noise[320] = "";
        struct gate_run *both = malloc((sa.n + sb.n + 1) * sizeof(*both));
        if (both) {
            memcpy(both, sa.runs, sa.n * sizeof(*both));
            memcpy(both + sa.n, sb.runs, sb.n * sizeof(*both));
            gate_noise_text(both, sa.n + sb.n, "runs", -1, noise, sizeof(noise));
            free(both);
        }
        if (noise[0]) {
            size_t used = strlen(noise);
            snprintf(noise + used, sizeof(noise) - used, " (%zu of %zu pairs)", sa.n - nclean, sa.n);
        }
        if (!o->quiet) {
            fprintf(stderr, "%zu pairs in all: %zu asked, %zu extra of at most %d "
                    "(--max-reruns)%s%s\n", sa.n, planned, sa.n > planned ? sa.n - planned : 0,
                    o->max_reruns, stop_reason[0] ? "; stopped: " : "", stop_reason);
            for (size_t i = 0; i < sa.n; i++)
                if (sa.runs[i].noisy)
                    fprintf(stderr, "  pair %zu (jobs %s and %s) left out: %s\n", i + 1,
                            sa.runs[i].job, sb.runs[i].job, sa.runs[i].why);
            if (noise[0])
                fprintf(stderr, "noise: %s\n", noise);
            fprintf(stderr, "B/A = %.4f, %.0f%% interval [%.4f, %.4f] over %zu pairs: %s (%s)\n",
                    v.r.ratio, 100 * o->confidence, v.r.lo, v.r.hi, nclean,
                    v.outcome == GATE_REGRESSION ? "B SLOWER"
                    : v.outcome == GATE_PASS     ? "pass: B is not slower"
                                                 : "INCONCLUSIVE",
                    v.why);
            if (v.outcome == GATE_INCONCLUSIVE)
                fprintf(stderr, "shadebench: warning: ab could not tell whether B is slower than "
                        "A within %d extra pairs%s%s\n", o->max_reruns, noise[0] ? "; " : "",
                        noise);
        }
        struct junit_case *t = junit_add(&j, "shadebench.ab", name);
        if (t) {
            t->time_s = clock_mono_s() - t0;
            junit_prop_str(t, "outcome", gate_outcome_name(v.outcome));
            junit_prop_str(t, "series", series);
            junit_prop_num(t, "ratio", v.r.ratio);
            junit_prop_num(t, "ci_low", v.r.lo);
            junit_prop_num(t, "ci_high", v.r.hi);
            junit_prop_num(t, "confidence", o->confidence);
            junit_prop_num(t, "pairs", (double)nclean);
            junit_prop_num(t, "noisy_pairs", (double)(sa.n - nclean));
            junit_prop_num(t, "extra_pairs", (double)(sa.n > planned ? sa.n - planned : 0));
            junit_out(t, "%s: %s", gate_outcome_name(v.outcome), v.why);
            if (v.outcome == GATE_REGRESSION)
                junit_fail(t, "B is slower than A: %s", v.why);
            else if (v.outcome == GATE_INCONCLUSIVE)
                junit_inconclusive(t, o->fail_inconclusive, "inconclusive%s: %s%s%s%s%s",
                                   o->fail_inconclusive ? " (--fail-inconclusive)" : "", v.why,
                                   noise[0] ? "; " : "", noise, stop_reason[0] ? "; stopped: " : "",
                                   stop_reason);
        }
        json_t *pairs = json_array();
        for (size_t i = 0; i < sa.n; i++)
            json_array_append_new(pairs, json_pack("{s:s, s:s, s:f, s:f, s:b, s:s}", "a",
                                                   sa.runs[i].job, "b", sb.runs[i].job, "a_ms",
                                                   sa.runs[i].ms, "b_ms", sb.runs[i].ms, "noisy",
                                                   sa.runs[i].noisy, "why", sa.runs[i].why));
        summary = json_pack("{s:s, s:s, s:s, s:s, s:s, s:f, s:f, s:f, s:f, s:I, s:s, s:o}", "a",
                            file_a, "b", file_b, "series", series, "outcome",
                            gate_outcome_name(v.outcome), "why", v.why, "ratio", v.r.ratio,
                            "ci_low", v.r.lo, "ci_high", v.r.hi, "confidence", o->confidence,
                            "pairs", (json_int_t)nclean, "server_b", cb->server, "runs", pairs);
    }
    rc = junit_conclude(o, &j, name, clock_mono_s() - t0);
    if (o->out_dir && summary) {
        char path[4096];
        snprintf(path, sizeof(path), "%s/A", o->out_dir);
        bool ok = run_set_write(&sa, path);
        snprintf(path, sizeof(path), "%s/B", o->out_dir);
        ok = run_set_write(&sb, path) && ok;
        snprintf(path, sizeof(path), "%s/ab.json", o->out_dir);
        ok = ok && fs_write_json_atomic(path, summary);
        if (!ok)
            rc = EXIT_ERROR;
        else if (!o->quiet)
            fprintf(stderr, "files in %s\n", o->out_dir);
    }
out:
    free(va);
    free(vb);
    free(ta);
    free(tb);
    json_decref(info_a);
    json_decref(info_b);
    json_decref(summary);
    run_set_finish(&sa);
    run_set_finish(&sb);
    junit_finish(&j);
    return rc;
}
