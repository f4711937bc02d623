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
#include "client/term.h"
#include "client/verdicts.h"
#include "common/fsutil.h"
#include "common/result_keys.h"

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
    struct gate_reruns plan = {.planned = planned, .budget = o->max_reruns, .decide = true,
                               .unit = "pair"};
    struct gate_verdict v;
    memset(&v, 0, sizeof(v));
    char stop_reason[200] = "";
    sa.planned = sb.planned = planned;
    sa.budget = sb.budget = o->max_reruns;
    if (!o->quiet)
        fprintf(stderr, "A: %s on %s\nB: %s on %s\n%zu clean pairs wanted, alternating, judged on "
                "%s; at most %d extra pairs for noisy pairs, an unclear verdict or confirming "
                "that B is slower (--max-reruns)\n", file_a, ca->server, file_b, cb->server,
                planned, series, o->max_reruns);
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
        gate_evaluate_ab(sa.runs, sb.runs, sa.n, o->confidence, o->max_slowdown,
                         o->noise_tolerance, &v);
        struct gate_step step;
        gate_next(&plan, sa.runs, sa.n, &v, false, &step);
        if (step.more) {
            if (!o->quiet)
                fprintf(stderr, "%s\n", step.say);
            target += step.more;
            continue;
        }
        if (step.budget_spent)
            snprintf(stop_reason, sizeof(stop_reason), "all %d extra pairs (--max-reruns) used",
                     o->max_reruns);
        if (step.unconfirmed && v.outcome == GATE_REGRESSION) {
            /* Not a verdict: what was seen, and why it stands unconfirmed. */
            v.outcome = GATE_INCONCLUSIVE;
            snprintf(v.why, sizeof(v.why), "%s", step.unconfirmed_why);
        }
        break;
    }

    json_t *ja = sa.n ? json_array_get(sa.jobs, 0) : sa.failed;
    json_t *jb = sb.n ? json_array_get(sb.jobs, 0) : sb.failed;
    /* Names from the job files as written (a daemon default renames
     * nothing), each side's marked, so that A against A has unique cases. */
    json_t *spec_a = json_loads(ta, 0, NULL), *spec_b = json_loads(tb, 0, NULL);
    char name_a[400], name_b[400], cls[96], name[900];
    junit_job_name(spec_a, name_a, sizeof(name_a));
    junit_job_name(spec_b, name_b, sizeof(name_b));
    const char *how = ca != cb ? "on" : "as";
    snprintf(name_a + strlen(name_a), sizeof(name_a) - strlen(name_a), " %s A", how);
    snprintf(name_b + strlen(name_b), sizeof(name_b) - strlen(name_b), " %s B", how);
    /* Each job case times its own (first) run; the comparison all of them. */
    job_classname(spec_a, cls, sizeof(cls));
    job_case(&j, cls, name_a, sa.failed ? sa.failed : ja, sa.n ? sa.runs[0].elapsed_s : sa.elapsed_s);
    job_classname(spec_b, cls, sizeof(cls));
    job_case(&j, cls, name_b, sb.failed ? sb.failed : jb, sb.n ? sb.runs[0].elapsed_s : sb.elapsed_s);
    json_decref(spec_a);
    json_decref(spec_b);
    snprintf(name, sizeof(name), "%s against %s: %s B/A", name_b, name_a, series);
    if (!sa.failed && !sb.failed) {
        size_t nclean = v.clean_new;
        /* Why pairs were noisy: the runs of both sides, together. */
        char noise[400] = "", basis[200];
        struct gate_run *both = malloc((sa.n + sb.n + 1) * sizeof(*both));
        if (both) {
            memcpy(both, sa.runs, sa.n * sizeof(*both));
            memcpy(both + sa.n, sb.runs, sb.n * sizeof(*both));
            for (size_t i = 0; i < sa.n + sb.n; i++)
                both[i].noisy = both[i].noisy && strstr(both[i].why, i < sa.n ? "A's" : "B's");
            gate_noise_text(both, sa.n + sb.n, "runs", -1, noise, sizeof(noise));
            free(both);
        }
        if (noise[0]) {
            size_t used = strlen(noise);
            snprintf(noise + used, sizeof(noise) - used, ", each against its own side's typical "
                     "run (%zu of %zu pairs left out)", sa.n - nclean, sa.n);
        }
        gate_basis_text(&v, true, sa.n, sa.n, basis, sizeof(basis));
        bool color = term_color(stderr);
        const char *word = v.outcome == GATE_REGRESSION ? "B SLOWER"
                           : v.outcome == GATE_PASS     ? "PASS: B is not slower"
                                                        : "INCONCLUSIVE";
        const char *on = v.outcome == GATE_REGRESSION ? TERM_RED
                         : v.outcome == GATE_PASS     ? TERM_GREEN
                                                      : TERM_YELLOW;
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
            if (v.used_new)
                fprintf(stderr, "B/A = %.4f, %.0f%% interval [%.4f, %.4f] %s: %s%s%s (%s)\n",
                        v.r.ratio, 100 * o->confidence, v.r.lo, v.r.hi, basis,
                        color ? on : "", word, color ? TERM_RESET : "", v.why);
            else
                fprintf(stderr, "B/A: no verdict %s: %s%s%s (%s)\n", basis, color ? on : "",
                        word, color ? TERM_RESET : "", v.why);
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
            if (v.r.ratio > 0) { /* with pairs 0: all pairs' figure, not a verdict */
                junit_prop_num(t, "ratio", v.r.ratio);
                junit_prop_num(t, "ci_low", v.r.lo);
                junit_prop_num(t, "ci_high", v.r.hi);
            }
            junit_prop_num(t, "confidence", o->confidence);
            junit_prop_num(t, "pairs", (double)v.used_new);
            junit_prop_num(t, "clean_pairs", (double)nclean);
            junit_prop_num(t, "noisy_pairs", (double)(sa.n - nclean));
            junit_prop_num(t, "extra_pairs", (double)(sa.n > planned ? sa.n - planned : 0));
            junit_prop_str(t, "bounded", v.bounded ? "yes" : "no");
            junit_out(t, "%s %s: %s", gate_outcome_name(v.outcome), basis, v.why);
            if (v.outcome == GATE_REGRESSION)
                junit_fail(t, JUNIT_REGRESSION, "B is slower than A %s: %s", basis, v.why);
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
        summary = json_pack("{s:s, s:s, s:s, s:s, s:s, s:I, s:I, s:b, s:f, s:s, s:o}", "a",
                            file_a, "b", file_b, "series", series, "outcome",
                            gate_outcome_name(v.outcome), "why", v.why, "pairs",
                            (json_int_t)v.used_new, "clean_pairs", (json_int_t)nclean, "bounded",
                            v.bounded, "confidence", o->confidence, "server_b", cb->server, "runs",
                            pairs);
        if (summary && v.r.ratio > 0) {
            json_object_set_new(summary, "ratio", json_real(v.r.ratio));
            json_object_set_new(summary, "ci_low", json_real(v.r.lo));
            json_object_set_new(summary, "ci_high", json_real(v.r.hi));
        }
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
