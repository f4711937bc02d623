#define _DEFAULT_SOURCE /* M_PI */
/* The gate on synthetic run samples: no change with noise passes, a 10%
 * slowdown with low noise is a regression, high noise is inconclusive; the
 * t distribution against published tables; paired ratios; spec and device
 * matching; runs and interference read from results; noisy runs marked. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/gate.h"
#include "common/timing_series.h"
#include "tests/unit/check.h"

/* A deterministic normal generator (xorshift + Box-Muller), so that the
 * rates below are the same on every machine. */
static unsigned long long rng_state = 88172645463325252ULL;
static double uniform(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return ((double)(rng_state >> 11) + 0.5) / 9007199254740992.0;
}
static double normal(void)
{
    return sqrt(-2.0 * log(uniform())) * cos(2.0 * M_PI * uniform());
}

/* n run medians around ms with multiplicative noise of relative size cv. */
static void runs(double *v, size_t n, double ms, double cv)
{
    for (size_t i = 0; i < n; i++)
        v[i] = ms * exp(cv * normal());
}

/* Outcome counts over many synthetic gates of 5 runs a side. */
static void rates(double slowdown, double cv, int trials, int counts[3])
{
    counts[0] = counts[1] = counts[2] = 0;
    for (int t = 0; t < trials; t++) {
        double b[5], c[5];
        runs(b, 5, 20.0, cv);
        runs(c, 5, 20.0 * (1 + slowdown), cv);
        struct gate_verdict v;
        gate_compare(b, 5, c, 5, 0.95, 0.05, &v);
        counts[v.outcome]++;
    }
}

/* ab's sentences speak of A and B, never of a baseline it does not have;
 * the gate's keep "the baseline". */
static void test_sides(void)
{
    struct ratio_interval r = {.na = 5, .nb = 5, .ratio = 0.953, .lo = 0.737, .hi = 1.233,
                               .cv_a = 0.2, .cv_b = 0.25, .confidence = 0.95};
    struct gate_verdict v;
    gate_decide_sides(&r, 0.05, &GATE_SIDES_AB, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && !strstr(v.why, "baseline") && strstr(v.why, "in A") &&
          strstr(v.why, "in B"));
    gate_decide(&r, 0.05, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && strstr(v.why, "in the baseline"));
    r.ratio = 1.4, r.lo = 0.98, r.hi = 2.0;
    gate_decide_sides(&r, 0.05, &GATE_SIDES_AB, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && !strstr(v.why, "baseline"));
}

/* The log and JUnit say why a verdict could not be reached: how many runs
 * were noisy and how much CPU the others took. */
static void test_noise_text(void)
{
    struct gate_run runs[4] = {
        {.ms = 10, .has_share = true, .other_share = 0.12},
        {.ms = 10, .has_share = true, .other_share = 0.41, .noisy = true},
        {.ms = 10, .has_share = true, .other_share = 0.79, .noisy = true},
        {.ms = 10, .daemon_noisy = true, .noisy = true},
    };
    char out[320];
    CHECK(gate_noise_text(runs, 4, "runs here", 0.12, out, sizeof(out)) == 3);
    CHECK(!strcmp(out, "3 of 4 runs here were noisy: other processes took 41% to 79% of the CPU "
                       "during them, against a typical 12%"));
    CHECK(gate_noise_text(runs, 2, "runs", -1, out, sizeof(out)) == 1);
    CHECK(!strcmp(out, "1 of 2 runs was noisy: other processes took 41% of the CPU during it"));
    CHECK(gate_noise_text(runs + 3, 1, "pairs", -1, out, sizeof(out)) == 1 &&
          strstr(out, "flagged it (no CPU figures)"));
    CHECK(gate_noise_text(runs, 1, "runs", 0.1, out, sizeof(out)) == 0 && out[0] == '\0');
    /* Truncation never overruns. */
    char tiny[12];
    gate_noise_text(runs, 4, "runs here", 0.12, tiny, sizeof(tiny));
    CHECK(strlen(tiny) < sizeof(tiny));
}

/* n pairs: A at a_ms, B at b_ms, each with multiplicative noise cv, and
 * the CPU others took during each side's runs. */
static void pairs(struct gate_run *a, struct gate_run *b, size_t n, double a_ms, double b_ms,
                  double cv, double share_a, double share_b)
{
    for (size_t i = 0; i < n; i++) {
        a[i] = (struct gate_run){.ms = a_ms * exp(cv * normal()), .has_share = true,
                                 .other_share = share_a};
        b[i] = (struct gate_run){.ms = b_ms * exp(cv * normal()), .has_share = true,
                                 .other_share = share_b};
    }
}

/* ab's findings: unlike jobs see different shares of the same neighbours
 * (a long job more of a periodic one), which compared across the pair
 * called every pair noisy; a verdict states what it rests on and refuses
 * too few pairs; A against A decides. */
static void test_ab(void)
{
    struct gate_run a[12], b[12];
    struct gate_verdict v;
    char basis[200];
    /* Unlike workloads: B takes half A's time, and its runs always see 50%
     * of the CPU taken where A's see 10% (each side steady). */
    pairs(a, b, 7, 20.0, 10.0, 0.01, 0.10, 0.50);
    gate_evaluate_ab(a, b, 7, 0.95, 0.05, NOISE_TOLERANCE, &v);
    gate_basis_text(&v, true, 7, 7, basis, sizeof(basis));
    CHECK(v.outcome == GATE_PASS && v.used_new == 7 && v.clean_new == 7 && !v.bounded);
    CHECK(!strcmp(basis, "over 7 pairs (none left out)"));
    CHECK(v.r.ratio > 0.45 && v.r.ratio < 0.55);
    /* One of A's runs disturbed against A's own typical run: that pair
     * alone is left out, and the headline says so. */
    a[3].other_share = 0.60;
    gate_evaluate_ab(a, b, 7, 0.95, 0.05, NOISE_TOLERANCE, &v);
    gate_basis_text(&v, true, 7, 7, basis, sizeof(basis));
    CHECK(a[3].noisy && b[3].noisy && !a[2].noisy && strstr(a[3].why, "during A's"));
    CHECK(v.outcome == GATE_PASS && v.used_new == 6 && !strcmp(basis, "over 6 pairs (1 noisy pair left out)"));

    /* A drift of the whole machine: in the last four pairs the neighbours
     * leave both sides half the CPU they left before (A 45% instead of 90%,
     * B 25% instead of 50%), and both run twice as long. Both runs of each
     * pair met it alike: no pair is left out. */
    pairs(a, b, 9, 20.0, 10.0, 0.01, 0.10, 0.50);
    for (size_t i = 5; i < 9; i++) {
        a[i].other_share = 0.55, b[i].other_share = 0.75;
        a[i].ms *= 2.0, b[i].ms *= 2.0;
    }
    gate_evaluate_ab(a, b, 9, 0.95, 0.05, NOISE_TOLERANCE, &v);
    CHECK(v.outcome == GATE_PASS && v.used_new == 9 && !v.bounded);

    /* Too few pairs: no verdict on two, whatever they say. */
    pairs(a, b, 2, 20.0, 20.0, 0.0001, 0.05, 0.05);
    gate_evaluate_ab(a, b, 2, 0.95, 0.05, NOISE_TOLERANCE, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && v.used_new == 0 && strstr(v.why, "at least 3") &&
          strstr(v.why, "not a verdict"));
    gate_basis_text(&v, true, 2, 2, basis, sizeof(basis));
    CHECK(!strcmp(basis, "on too few pairs for an interval"));

    /* One clean pair of seven: a bounded verdict over all seven says so,
     * never "over 1 pairs". In the noisy six, B's run (then A's, in turn)
     * had 40% of the CPU taken against its side's typical 5%. */
    pairs(a, b, 7, 20.0, 60.0, 0.01, 0.05, 0.05);
    for (size_t i = 0; i < 6; i++)
        (i % 2 ? a : b)[i].other_share = 0.40;
    gate_evaluate_ab(a, b, 7, 0.95, 0.05, NOISE_TOLERANCE, &v);
    gate_basis_text(&v, true, 7, 7, basis, sizeof(basis));
    CHECK(v.outcome == GATE_REGRESSION && v.bounded && v.clean_new == 1 && v.used_new == 7);
    CHECK(strstr(basis, "over 7 pairs (1 clean, 6 noisy ones bounded"));

    /* A against A: the same job on both sides, pairs clean, a pass over all
     * of them (it used to say "over 0 pairs"). */
    pairs(a, b, 5, 20.0, 20.0, 0.02, 0.03, 0.03);
    for (size_t i = 0; i < 5; i++)
        b[i].other_share = 0.03 + 0.01 * (double)(i % 3);
    gate_evaluate_ab(a, b, 5, 0.95, 0.05, NOISE_TOLERANCE, &v);
    CHECK(v.outcome == GATE_PASS && v.used_new == 5 && v.r.ratio > 0.95 && v.r.ratio < 1.05);

    /* Confirmation: runs 5 and on were run to confirm a regression; all
     * noisy, none of them enters the verdict. */
    pairs(a, b, 8, 20.0, 30.0, 0.01, 0.05, 0.05);
    for (size_t i = 5; i < 8; i++)
        b[i].other_share = 0.70;
    gate_evaluate_ab(a, b, 8, 0.95, 0.05, NOISE_TOLERANCE, &v);
    CHECK(v.outcome == GATE_REGRESSION && !v.bounded &&
          gate_runs_in_verdict(a, 8, 5, v.bounded) == 0 && gate_runs_in_verdict(a, 8, 0, false) == 5);
}

/* The baseline gate: new runs marked against the baseline's typical share
 * (both measured under like conditions, or left out), the verdict's basis
 * stated, and fresh confirming runs counted only when they enter it. */
static void test_baseline(void)
{
    struct gate_run base[5], cur[8];
    struct gate_verdict v;
    char basis[200];
    for (size_t i = 0; i < 5; i++)
        base[i] = (struct gate_run){.ms = 20.0 * exp(0.01 * normal()), .has_share = true,
                                    .other_share = 0.74};
    for (size_t i = 0; i < 8; i++)
        cur[i] = (struct gate_run){.ms = 20.0 * exp(0.01 * normal()), .has_share = true,
                                   .other_share = 0.76};
    /* Noisy alone (76% taken), like the baseline's runs: kept, a pass. */
    gate_evaluate_baseline(base, 5, cur, 8, 0.95, 0.05, NOISE_TOLERANCE, &v);
    gate_basis_text(&v, false, 5, 8, basis, sizeof(basis));
    CHECK(v.outcome == GATE_PASS && v.used_old == 5 && v.used_new == 8 &&
          !strcmp(basis, "over 5 baseline runs and 8 runs here (none left out)"));
    /* The last three at 95%: left out against the baseline's 74%. */
    for (size_t i = 5; i < 8; i++)
        cur[i].other_share = 0.95, cur[i].ms *= 1.5;
    gate_evaluate_baseline(base, 5, cur, 8, 0.95, 0.05, NOISE_TOLERANCE, &v);
    gate_basis_text(&v, false, 5, 8, basis, sizeof(basis));
    CHECK(cur[7].noisy && !cur[4].noisy && v.used_new == 5 &&
          !strcmp(basis, "over 5 baseline runs and 5 runs here (3 noisy runs left out)"));
    CHECK(gate_runs_in_verdict(cur, 8, 5, v.bounded) == 0);
}

/* The rerun policy: a regression is confirmed on a fresh set that enters
 * its verdict; noisy confirming runs are replaced within the budget; with
 * the budget spent and none entered, it stands unconfirmed. */
static void test_reruns(void)
{
    struct gate_run runs[12];
    for (size_t i = 0; i < 12; i++)
        runs[i] = (struct gate_run){.ms = 30, .has_share = true, .other_share = 0.05};
    struct gate_reruns r = {.planned = 3, .budget = 6, .decide = true, .unit = "run"};
    struct gate_verdict reg = {.outcome = GATE_REGRESSION};
    snprintf(reg.why, sizeof(reg.why), "slower by 50.0%%");
    struct gate_step step;
    gate_next(&r, runs, 3, &reg, false, &step);
    CHECK(step.more == 3 && r.confirming && r.confirm_from == 3 && r.budget == 3 &&
          strstr(step.say, "confirming on 3 more runs"));
    /* The three confirming runs were all left out as noisy: replaced. */
    runs[3].noisy = runs[4].noisy = runs[5].noisy = true;
    gate_next(&r, runs, 6, &reg, false, &step);
    CHECK(step.more == 3 && r.budget == 0 && strstr(step.say, "3 of the runs confirming") &&
          !step.unconfirmed);
    /* Those too: the budget is spent and nothing fresh entered the verdict. */
    runs[6].noisy = runs[7].noisy = runs[8].noisy = true;
    gate_next(&r, runs, 9, &reg, false, &step);
    CHECK(step.more == 0 && step.unconfirmed && step.budget_spent &&
          strstr(step.unconfirmed_why, "could not be confirmed: only 0 of the 6 runs"));
    /* Bounded verdicts count every fresh run with figures. */
    reg.bounded = true;
    gate_next(&r, runs, 9, &reg, false, &step);
    CHECK(step.more == 0 && !step.unconfirmed);
    /* Clean confirming runs confirm it: stop, a regression. */
    struct gate_reruns r2 = {.planned = 3, .budget = 6, .decide = true, .unit = "pair"};
    reg.bounded = false;
    for (size_t i = 0; i < 12; i++)
        runs[i].noisy = false;
    gate_next(&r2, runs, 3, &reg, false, &step);
    gate_next(&r2, runs, 6, &reg, false, &step);
    CHECK(step.more == 0 && !step.unconfirmed && !step.wanted_more);
    /* A whole noisy set stops the runs for a later baseline too. */
    struct gate_reruns r3 = {.planned = 3, .budget = 6, .decide = false, .unit = "run"};
    runs[1].noisy = true;
    gate_next(&r3, runs, 3, &reg, false, &step);
    CHECK(step.more == 1 && strstr(step.say, "1 noisy run(s) left out"));
    gate_next(&r3, runs, 4, &reg, true, &step);
    CHECK(step.more == 0 && step.wanted_more == false);
}

/* The rule "software renderer -> frame_ms", written once and read by the
 * gate, ab, history and the charts. */
static void test_series_rule(void)
{
    CHECK(!strcmp(timing_series_for_renderer("llvmpipe (LLVM 15.0.6, 256 bits)"), "frame_ms"));
    CHECK(!strcmp(timing_series_for_renderer("softpipe"), "frame_ms"));
    CHECK(!strcmp(timing_series_for_renderer("Google SwiftShader"), "frame_ms"));
    CHECK(!strcmp(timing_series_for_renderer("NVIDIA H100 80GB HBM3/PCIe/SSE2"), "gpu_ms"));
    CHECK(!strcmp(timing_series_for_renderer(NULL), "frame_ms"));
    json_t *dev = json_pack("{s:s}", "gl_renderer", "AMD Radeon RX 7900 XTX (radeonsi)");
    CHECK(!strcmp(gate_default_series(dev), "gpu_ms"));
    json_decref(dev);
}

int main(void)
{
    test_sides();
    test_series_rule();
    test_reruns();
    test_noise_text();
    test_ab();
    test_baseline();
    /* Student's t against the tables. */
    CHECK_NEAR(student_t_quantile(0.975, 1), 12.706, 1e-3);
    CHECK_NEAR(student_t_quantile(0.975, 4), 2.776, 1e-3);
    CHECK_NEAR(student_t_quantile(0.975, 8), 2.306, 1e-3);
    CHECK_NEAR(student_t_quantile(0.95, 10), 1.812, 1e-3);
    CHECK_NEAR(student_t_quantile(0.975, 1000), 1.962, 1e-3);
    CHECK_NEAR(student_t_quantile(0.025, 8), -2.306, 1e-3);
    CHECK_NEAR(student_t_cdf(0.0, 3.7), 0.5, 1e-12);
    CHECK_NEAR(student_t_cdf(2.306, 8), 0.975, 1e-4);
    /* Fractional degrees of freedom (Welch) sit between their neighbours. */
    double q75 = student_t_quantile(0.975, 7.5);
    CHECK(q75 < student_t_quantile(0.975, 7) && q75 > student_t_quantile(0.975, 8));

    /* Welch on logs, by hand: a = {10, 10.2, 9.8}, b = 1.1 * a exactly,
     * so the ratio is 1.1 with the spread of a on both sides. */
    double a[3] = {10, 10.2, 9.8}, b[3] = {11, 11.22, 10.78};
    struct ratio_interval r;
    CHECK(welch_log_ratio(a, 3, b, 3, 0.95, &r));
    CHECK_NEAR(r.ratio, 1.1, 1e-9);
    CHECK(r.lo > 1.0 && r.hi > 1.1 && r.lo < 1.1);
    CHECK_NEAR(r.df, 4.0, 1e-9); /* equal variances and sizes: df = 2n - 2 */
    CHECK(r.p_greater < 0.01);
    /* One baseline run: its spread is taken from the other side. */
    CHECK(welch_log_ratio(a, 1, b, 3, 0.95, &r) && r.df == 2.0 && r.lo < r.ratio);
    CHECK(!welch_log_ratio(a, 1, b, 1, 0.95, &r));
    double bad[2] = {10, 0};
    CHECK(!welch_log_ratio(bad, 2, b, 3, 0.95, &r));

    struct gate_verdict v;
    /* The three outcomes on fixed samples. */
    double base[5] = {20.0, 20.3, 19.8, 20.1, 19.9};
    double same[5] = {20.1, 19.9, 20.2, 19.8, 20.0};
    double slow[5] = {22.0, 22.3, 21.8, 22.1, 21.9};
    double wild[5] = {16.0, 25.0, 19.0, 28.0, 21.0};
    gate_compare(base, 5, same, 5, 0.95, 0.05, &v);
    CHECK(v.outcome == GATE_PASS && strstr(v.why, "ruled out"));
    gate_compare(base, 5, slow, 5, 0.95, 0.05, &v);
    CHECK(v.outcome == GATE_REGRESSION && v.r.ratio > 1.09 && strstr(v.why, "slower by"));
    gate_compare(base, 5, wild, 5, 0.95, 0.05, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && strstr(v.why, "spread"));
    gate_compare(base, 5, slow, 1, 0.95, 0.05, &v);
    CHECK(v.outcome == GATE_INCONCLUSIVE && strstr(v.why, "too few"));
    /* A slowdown below the minimum effect is never a regression, however
     * certain. */
    double slight[5] = {20.6, 20.9, 20.4, 20.7, 20.5};
    gate_compare(base, 5, slight, 5, 0.95, 0.05, &v);
    CHECK(v.outcome != GATE_REGRESSION && v.r.lo > 1.0);

    /* Rates over 2000 synthetic gates of 5 runs a side. */
    int c[3];
    rates(0.0, 0.02, 2000, c); /* no change, 2% run-to-run noise */
    printf("no change, 2%% noise: pass %d, regression %d, inconclusive %d\n", c[0], c[1], c[2]);
    CHECK(c[GATE_REGRESSION] <= 20 && c[GATE_PASS] >= 1200);
    rates(0.10, 0.01, 2000, c); /* a 10% slowdown, 1% noise */
    printf("10%% slower, 1%% noise: pass %d, regression %d, inconclusive %d\n", c[0], c[1], c[2]);
    CHECK(c[GATE_REGRESSION] >= 1980 && c[GATE_PASS] == 0);
    /* No change under 20% noise: too noisy to tell, nearly always. A false
     * regression needs the interval wholly above no change, which happens
     * at most at the one-sided level of a 95% interval (2.5%); the caller
     * confirms a regression on fresh runs before it fails a build. */
    rates(0.0, 0.20, 2000, c);
    printf("no change, 20%% noise: pass %d, regression %d, inconclusive %d\n", c[0], c[1], c[2]);
    CHECK(c[GATE_INCONCLUSIVE] >= 1800 && c[GATE_REGRESSION] <= 60);

    /* Paired ratios: B is half of A on every pair, whatever A's drift. */
    double pa[6] = {10, 14, 9, 20, 12, 11}, pb[6];
    for (int i = 0; i < 6; i++)
        pb[i] = pa[i] * 0.5 * (i % 2 ? 1.01 : 0.99);
    CHECK(paired_log_ratio(pa, pb, 6, 0.95, &r));
    CHECK(r.lo < 0.5 && r.hi > 0.5 && r.hi - r.lo < 0.03);
    /* The same drift with independent samples gives a far wider interval. */
    struct ratio_interval w;
    CHECK(welch_log_ratio(pa, 6, pb, 6, 0.95, &w) && w.hi - w.lo > 5 * (r.hi - r.lo));
    CHECK(!paired_log_ratio(pa, pb, 1, 0.95, &r));

    /* Specs: labels, repeat, captures and the reference do not matter;
     * scene.lights does, and the difference is named. */
    json_t *s1 = json_loads("{\"technique\":\"forward\",\"frames\":20,\"scene\":{\"lights\":10,"
                            "\"width\":160},\"repeat\":1,\"labels\":{\"commit\":\"a\"},"
                            "\"reference\":null,\"async_distance\":0}", 0, NULL);
    json_t *s2 = json_loads("{\"technique\":\"forward\",\"frames\":20,\"scene\":{\"lights\":10,"
                            "\"width\":160},\"repeat\":5,\"labels\":{\"commit\":\"b\"},"
                            "\"reference\":\"forward\",\"capture_interval\":5,"
                            "\"async_distance\":0.0}", 0, NULL);
    json_t *s3 = json_loads("{\"technique\":\"forward\",\"frames\":20,\"scene\":{\"lights\":80,"
                            "\"width\":160},\"async_distance\":0}", 0, NULL);
    json_t *s4 = json_loads("{\"technique\":\"forward\",\"frames\":20,\"scene\":{\"lights\":10,"
                            "\"width\":160,\"depth\":1},\"async_distance\":0}", 0, NULL);
    char what[256];
    CHECK(!gate_spec_differs(s1, s2, what, sizeof(what)));
    CHECK(gate_spec_differs(s1, s3, what, sizeof(what)) &&
          strcmp(what, "scene.lights: 10 in the baseline, 80 here") == 0);
    CHECK(gate_spec_differs(s1, s4, what, sizeof(what)) && strstr(what, "scene.depth: absent"));
    json_decref(s1);
    json_decref(s2);
    json_decref(s3);
    json_decref(s4);

    json_t *d1 = json_pack("{s:s, s:s}", "gl_renderer", "llvmpipe (LLVM 15.0.6, 256 bits)",
                           "gl_version", "4.5 (Core Profile) Mesa 22.3.6");
    json_t *d2 = json_pack("{s:s, s:s}", "gl_renderer", "NVIDIA GeForce RTX 3070/PCIe/SSE2",
                           "gl_version", "4.6.0 NVIDIA 535.54.03");
    CHECK(!gate_device_differs(d1, d1, what, sizeof(what)));
    CHECK(gate_device_differs(d1, d2, what, sizeof(what)) && strstr(what, "gl_renderer"));
    CHECK(strcmp(gate_default_series(d1), "frame_ms") == 0);
    CHECK(strcmp(gate_default_series(d2), "gpu_ms") == 0);
    json_decref(d1);
    json_decref(d2);

    /* Runs from results: a single run with interference, a repeated job,
     * and a client-written result with gate_runs. */
    json_t *single = json_loads("{\"job_id\":\"j1\",\"frame_ms\":{\"median\":12.5},"
                                "\"interference\":{\"loadavg_start\":[0.5,0.4,0.3],"
                                "\"loadavg_end\":[0.7,0.4,0.3],\"other_cpu_share\":0.03,"
                                "\"noisy\":false}}", 0, NULL);
    struct gate_run *gr = NULL;
    CHECK(gate_runs_from_result(single, "frame_ms", &gr) == 1 && gr[0].ms == 12.5 &&
          gr[0].has_share && gr[0].other_share == 0.03 && gr[0].load_end == 0.7 &&
          strcmp(gr[0].job, "j1") == 0);
    free(gr);
    CHECK(gate_runs_from_result(single, "gpu_ms", &gr) == 0 && gr == NULL);
    json_decref(single);
    json_t *repeated = json_loads("{\"frame_ms\":{\"median\":12.5},\"runs\":[{\"run\":1,"
                                  "\"frame_ms\":{\"median\":12.5}},{\"run\":2,\"frame_ms\":"
                                  "{\"median\":13.0}}]}", 0, NULL);
    CHECK(gate_runs_from_result(repeated, "frame_ms", &gr) == 2 && gr[1].ms == 13.0 &&
          !gr[1].has_share);
    free(gr);
    json_decref(repeated);
    json_t *client = json_loads("{\"gate_runs\":[{\"job\":\"a\",\"frame_ms\":10.0,"
                                "\"interference\":{\"other_cpu_share\":0.02}},{\"job\":\"b\","
                                "\"frame_ms\":11.0,\"noisy\":true,\"why\":\"busy\"},{\"job\":\"c\","
                                "\"frame_ms\":10.2,\"interference\":{\"other_cpu_share\":0.04}}]}",
                                0, NULL);
    size_t n = gate_runs_from_result(client, "frame_ms", &gr);
    CHECK(n == 3 && gr[1].noisy && strcmp(gr[1].why, "busy") == 0 && strcmp(gr[2].job, "c") == 0);
    double share;
    CHECK(gate_typical_share(gr, n, &share) && fabs(share - 0.03) < 1e-12);
    double values[3];
    CHECK(gate_clean_values(gr, n, values) == 2 && values[1] == 10.2);
    free(gr);
    json_decref(client);

    /* Noise: runs measured under other load than the baseline's are marked. */
    struct gate_run nr[4] = {
        {.ms = 10, .has_share = true, .other_share = 0.05},
        {.ms = 10, .has_share = true, .other_share = 0.45},
        {.ms = 10, .has_share = false, .daemon_noisy = true},
        {.ms = 10, .has_share = true, .other_share = 0.12},
    };
    CHECK(gate_mark_noisy(nr, 4, true, 0.04, 0.10) == 1 && nr[1].noisy &&
          strstr(nr[1].why, "45%") && strstr(nr[1].why, "43% less CPU left") && !nr[3].noisy &&
          !nr[2].noisy);
    /* On a saturated machine five points matter: 15% left instead of 20%
     * (the one noise rule, common/noise.h). */
    CHECK_NEAR(noise_cpu_left_change(0.85, 0.80), -0.25, 1e-12);
    CHECK_NEAR(noise_cpu_left_change(0.05, 0.02), -0.0306122, 1e-6);

    /* A run bounded by its CPU change against a typical share: left 40% of
     * the CPU where the typical run was left 80%, it could be up to twice
     * as slow for that alone. */
    {
        struct gate_run b = {.ms = 30, .has_share = true, .other_share = 0.6};
        CHECK_NEAR(gate_run_bound_ms(&b, true, 0.2, false), 15.0, 1e-9);
        CHECK_NEAR(gate_run_bound_ms(&b, true, 0.2, true), 30.0, 1e-9);
        CHECK_NEAR(gate_run_bound_ms(&b, false, 0.2, false), 30.0, 1e-9);
        b.has_share = false;
        CHECK_NEAR(gate_run_bound_ms(&b, true, 0.2, false), 30.0, 1e-9);
    }
    struct gate_run busy[2] = {{.ms = 10, .has_share = true, .other_share = 0.85},
                               {.ms = 10, .has_share = true, .other_share = 0.81}};
    CHECK(gate_mark_noisy(busy, 2, true, 0.80, 0.10) == 1 && busy[0].noisy && !busy[1].noisy);
    struct gate_run nr2[2] = {{.ms = 10, .daemon_noisy = true}, {.ms = 10}};
    CHECK(gate_mark_noisy(nr2, 2, false, 0, 0.10) == 1 && nr2[0].noisy);
    return check_finish("test_gate");
}
