/* submit (with the timing gate), fetch, status, list, cancel and info. */
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
#include "client/workload.h"
#include "common/fsutil.h"
#include "common/result_keys.h"

/* ---- the baseline ---- */

struct baseline {
    json_t *root;   /* the file */
    json_t *beside; /* job.json beside a result.json without a spec */
    const json_t *result, *spec, *device;
};

static void baseline_finish(struct baseline *b)
{
    json_decref(b->root);
    json_decref(b->beside);
    memset(b, 0, sizeof(*b));
}

/* A result.json written by this client (with its spec, and gate_runs for
 * several runs), or a job.json with the result inside. Read before any job
 * runs, so that a wrong path fails at once. */
static bool baseline_load(const char *path, struct baseline *b)
{
    memset(b, 0, sizeof(*b));
    char err[600];
    b->root = load_json_file("baseline", path, err, sizeof(err));
    if (!b->root) {
        fprintf(stderr, "shadebench: --baseline: %s\n", err);
        return false;
    }
    json_t *inner = json_object_get(b->root, RK_RESULT);
    b->result = inner ? inner : b->root;
    b->spec = json_object_get(inner ? b->root : b->result, "spec");
    if (!b->spec) {
        /* An older result.json: the spec is in job.json beside it. */
        char beside[4096];
        snprintf(beside, sizeof(beside), "%s", path);
        char *slash = strrchr(beside, '/');
        snprintf(slash ? slash + 1 : beside,
                 sizeof(beside) - (size_t)(slash ? slash + 1 - beside : 0), "job.json");
        b->beside = json_load_file(beside, 0, NULL);
        b->spec = json_object_get(b->beside, "spec");
    }
    b->device = json_object_get(b->result, "device");
    if (!json_is_object(b->result) || !json_object_get(b->result, RK_FRAME_MS)) {
        fprintf(stderr, "shadebench: --baseline %s: not a finished job's result (no frame_ms)\n",
                path);
        baseline_finish(b);
        return false;
    }
    return true;
}

/* ---- the gate ---- */

struct spec_check {
    const struct baseline *base;
    const struct options *o;
    bool mismatch;
};

static bool check_spec(const json_t *spec, void *ctx)
{
    struct spec_check *sc = ctx;
    char what[512];
    if (!sc->base->spec) {
        if (sc->o->allow_mismatch)
            return true;
        fprintf(stderr, "shadebench: the baseline has no job spec to check the job against "
                "(neither in it nor in job.json beside it); --allow-mismatch compares anyway\n");
        sc->mismatch = true;
        return false;
    }
    if (!gate_spec_differs(sc->base->spec, spec, what, sizeof(what)))
        return true;
    if (sc->o->allow_mismatch) {
        fprintf(stderr, "shadebench: warning: not the baseline's job (%s); compared anyway "
                "(--allow-mismatch)\n", what);
        return true;
    }
    fprintf(stderr, "shadebench: not the baseline's job: %s. Labels, repeat, captures, the "
            "reference and metrics may differ; nothing else (--allow-mismatch to compare "
            "anyway)\n", what);
    sc->mismatch = true;
    return false;
}

/* Job-file repeat as the number of runs, else 5. */
static int default_runs(const char *file)
{
    json_t *job = json_load_file(file, 0, NULL);
    json_t *rep = json_object_get(job, "repeat");
    int n = json_is_integer(rep) ? (int)json_integer_value(rep)
            : json_is_object(rep) ? (int)json_integer_value(json_object_get(rep, "max")) : 0;
    json_decref(job);
    return n > 1 ? (n > 100 ? 100 : n) : 5;
}

/* Consecutive noisy runs at the end: when a whole batch was disturbed, the
 * machine's conditions differ from the baseline's and more runs will not
 * help. */
static size_t trailing_noisy(const struct run_set *s)
{
    size_t k = 0;
    while (k < s->n && s->runs[s->n - 1 - k].noisy)
        k++;
    return k;
}

static int gate_or_runs(struct conn *c, const struct options *o, const char *file,
                        const struct baseline *base, int planned)
{
    double t0 = clock_mono_s();
    int rc = EXIT_ERROR;
    char err[512];
    struct run_set s;
    run_set_init(&s, c, "run");
    struct gate_run *brun = NULL;
    size_t nb = 0;
    struct junit j;
    junit_init(&j);
    char *text = job_text_for_submit(file, o, 1, err, sizeof(err));
    json_t *info = NULL, *gate_json = NULL;
    if (!text) {
        fprintf(stderr, "shadebench: %s\n", err);
        goto out;
    }
    /* The device first: a baseline from another device is refused before
     * anything runs. */
    if (!(info = conn_json(c, "GET", "/v1/info", NULL, NULL)))
        goto out;
    json_t *device = json_object_get(info, "device");
    if (base && gate_device_differs(base->device, device, err, sizeof(err))) {
        if (!o->allow_mismatch) {
            fprintf(stderr, "shadebench: the baseline was measured on another device: %s "
                    "(--allow-mismatch to compare anyway)\n", err);
            goto out;
        }
        fprintf(stderr, "shadebench: warning: another device than the baseline's: %s\n", err);
    }
    const char *series = o->series ? o->series : gate_default_series(base ? base->device : device);
    if (base && !(nb = gate_runs_from_result(base->result, series, &brun))) {
        fprintf(stderr, "shadebench: the baseline has no %s figures\n", series);
        goto out;
    }
    struct spec_check sc = {base, o, false};
    struct gate_verdict v;
    memset(&v, 0, sizeof(v));
    struct gate_reruns plan = {.planned = (size_t)planned, .budget = o->max_reruns,
                               .decide = base != NULL, .unit = "run"};
    size_t target = (size_t)planned;
    char stop_reason[200] = "";
    s.planned = (size_t)planned;
    s.budget = o->max_reruns;
    if (!o->quiet)
        fprintf(stderr, "%d clean runs of %s wanted, each a job of its own, judged on %s; at "
                "most %d extra for noisy runs, an unclear verdict or confirming a regression "
                "(--max-reruns)\n", planned, file, series, o->max_reruns);
    for (;;) {
        while (s.n < target && !s.failed) {
            if (!run_set_add(&s, o, text, series, base && s.n == 0 ? check_spec : NULL, &sc))
                goto out;
        }
        if (s.failed)
            break;
        if (base) {
            gate_evaluate_baseline(brun, nb, s.runs, s.n, o->confidence, o->max_slowdown,
                                   o->noise_tolerance, &v);
        } else {
            /* Runs for a later baseline: marked against their own typical run. */
            double ref;
            for (size_t i = 0; i < s.n; i++)
                s.runs[i].noisy = false, s.runs[i].why[0] = '\0';
            bool have = gate_typical_share(s.runs, s.n, &ref);
            gate_mark_noisy(s.runs, s.n, have, ref, o->noise_tolerance);
        }
        size_t trailing = trailing_noisy(&s);
        bool batch_noisy = trailing >= (size_t)(planned > 3 ? planned : 3);
        struct gate_step step;
        gate_next(&plan, s.runs, s.n, &v, batch_noisy, &step);
        if (step.more) {
            if (!o->quiet && base)
                fprintf(stderr, "%s\n", step.say);
            target += step.more;
            continue;
        }
        if (step.budget_spent)
            snprintf(stop_reason, sizeof(stop_reason), "all %d extra runs (--max-reruns) used",
                     o->max_reruns);
        else if (batch_noisy && step.wanted_more)
            snprintf(stop_reason, sizeof(stop_reason), "the last %zu runs were all noisy: the "
                     "machine is busier than when the runs compared were measured", trailing);
        if (step.unconfirmed && v.outcome == GATE_REGRESSION) {
            /* Not a verdict: what was seen, and why it stands unconfirmed. */
            v.outcome = GATE_INCONCLUSIVE;
            snprintf(v.why, sizeof(v.why), "%s", step.unconfirmed_why);
        }
        break;
    }
    size_t nb_clean = v.clean_old, nc_clean = 0;
    for (size_t i = 0; i < s.n; i++)
        nc_clean += !s.runs[i].noisy;

    /* The verdicts. Names come from the job file as the user wrote it, so
     * that a default the daemon adds later renames nothing. */
    json_t *first = s.n ? json_array_get(s.jobs, 0) : s.failed;
    json_t *user_spec = json_loads(text, 0, NULL);
    char name[400], classname[96];
    junit_job_name(user_spec, name, sizeof(name));
    job_classname(user_spec, classname, sizeof(classname));
    json_decref(user_spec);
    /* The job case times its job; the gate case the whole gate. */
    double job_s = s.n ? s.runs[0].elapsed_s : s.elapsed_s;
    struct junit_case *jc = job_case(&j, classname, name, s.failed ? s.failed : first, job_s);
    if (jc && s.n > 1) {
        junit_prop_num(jc, "runs", (double)s.n);
        junit_out(jc, "the first of %zu runs, each a job of its own", s.n);
    }
    if (s.n)
        quality_cases(o, json_object_get(first, RK_RESULT), classname, name, &j);
    char noise_new[320] = "", noise_base[320] = "";
    double typical = -1;
    if (!gate_typical_share(brun, nb, &typical) && !gate_typical_share(s.runs, s.n, &typical))
        typical = -1;
    gate_noise_text(s.runs, s.n, base ? "runs here" : "runs", typical, noise_new,
                    sizeof(noise_new));
    gate_noise_text(brun, nb, "baseline runs", typical, noise_base, sizeof(noise_base));
    if (!o->quiet && s.n) {
        fprintf(stderr, "%zu runs in all: %zu asked, %zu extra of at most %d (--max-reruns)%s%s\n",
                s.n, (size_t)planned, s.n > (size_t)planned ? s.n - (size_t)planned : 0,
                o->max_reruns, stop_reason[0] ? "; stopped: " : "", stop_reason);
        for (size_t i = 0; i < s.n; i++)
            if (s.runs[i].noisy)
                fprintf(stderr, "  run %zu (job %s) left out: %s\n", i + 1, s.runs[i].job,
                        s.runs[i].why);
        if (noise_new[0])
            fprintf(stderr, "noise: %s\n", noise_new);
    }
    if (!base && !s.failed && !o->quiet) {
        fprintf(stderr, "kept %zu clean runs of the %d asked for the baseline\n", nc_clean, planned);
        if (nc_clean < (size_t)planned)
            fprintf(stderr, "shadebench: warning: only %zu clean runs within --max-reruns %d: the "
                    "baseline keeps every run, its noisy ones marked, and a gate against it "
                    "leaves those out\n", nc_clean, o->max_reruns);
    }
    if (base && !s.failed) {
        if (!o->quiet) {
            struct run_set bs = {.what = "baseline run", .runs = brun, .n = nb};
            fprintf(stderr, "baseline runs:\n");
            run_set_print(&bs, series, stderr);
            if (noise_base[0])
                fprintf(stderr, "noise: %s\n", noise_base);
        }
        char cname[460], basis[200];
        snprintf(cname, sizeof(cname), "%s: median %s against the baseline", name, series);
        gate_basis_text(&v, false, nb, s.n, basis, sizeof(basis));
        struct junit_case *t = junit_add(&j, classname, cname);
        if (t) {
            t->time_s = clock_mono_s() - t0;
            junit_prop_str(t, "outcome", gate_outcome_name(v.outcome));
            junit_prop_str(t, "series", series);
            if (v.r.ratio > 0) { /* with no runs used: all runs' figure, not a verdict */
                junit_prop_num(t, "ratio", v.r.ratio);
                junit_prop_num(t, "ci_low", v.r.lo);
                junit_prop_num(t, "ci_high", v.r.hi);
            }
            junit_prop_num(t, "confidence", o->confidence);
            junit_prop_num(t, "allowed_slowdown", o->max_slowdown);
            junit_prop_num(t, "baseline_runs", (double)nb_clean);
            junit_prop_num(t, "runs", (double)nc_clean);
            junit_prop_num(t, "noisy_runs", (double)(s.n - nc_clean + nb - nb_clean));
            junit_prop_num(t, "extra_runs", (double)(s.n > (size_t)planned ? s.n - (size_t)planned : 0));
            junit_prop_str(t, "bounded", v.bounded ? "yes" : "no");
            junit_out(t, "%s %s: %s", gate_outcome_name(v.outcome), basis, v.why);
            junit_out(t, "%zu baseline runs and %zu runs here compared (%zu and %zu left out as "
                      "noisy)", nb_clean, nc_clean, nb - nb_clean, s.n - nc_clean);
            for (size_t i = 0; i < s.n; i++)
                if (s.runs[i].noisy)
                    junit_out(t, "run %s left out: %s", s.runs[i].job, s.runs[i].why);
            if (v.outcome == GATE_REGRESSION)
                junit_fail(t, JUNIT_REGRESSION, "%s: %s", basis, v.why);
            else if (v.outcome == GATE_INCONCLUSIVE)
                junit_inconclusive(t, o->fail_inconclusive, "inconclusive%s: %s%s%s%s%s%s%s",
                                   o->fail_inconclusive ? " (--fail-inconclusive)" : "", v.why,
                                   noise_new[0] ? "; " : "", noise_new, noise_base[0] ? "; " : "",
                                   noise_base, stop_reason[0] ? "; stopped: " : "", stop_reason);
        }
        if (!o->quiet) {
            bool color = term_color(stderr);
            fprintf(stderr, "gate %s: %s%s%s: %s\n", basis,
                    !color ? "" : v.outcome == GATE_REGRESSION ? TERM_RED
                                : v.outcome == GATE_PASS       ? TERM_GREEN
                                                               : TERM_YELLOW,
                    v.outcome == GATE_REGRESSION ? "REGRESSION"
                    : v.outcome == GATE_PASS     ? "PASS"
                                                 : "INCONCLUSIVE",
                    color ? TERM_RESET : "", v.why);
            if (v.outcome == GATE_INCONCLUSIVE)
                fprintf(stderr, "shadebench: warning: the timing gate could not decide within "
                        "%d extra runs%s%s%s%s\n", o->max_reruns, noise_new[0] ? "; " : "",
                        noise_new, noise_base[0] ? "; " : "", noise_base);
        }
        gate_json = json_pack("{s:s, s:s, s:f, s:f, s:f, s:f, s:f, s:I, s:I, s:s}", "outcome",
                              gate_outcome_name(v.outcome), "series", series, "ratio", v.r.ratio,
                              "ci_low", v.r.lo, "ci_high", v.r.hi, "confidence", o->confidence,
                              "allowed_slowdown", o->max_slowdown, "baseline_runs",
                              (json_int_t)nb_clean, "runs", (json_int_t)nc_clean, "why", v.why);
        if (gate_json) {
            json_object_set_new(gate_json, "basis", json_string(basis));
            json_object_set_new(gate_json, "bounded", json_boolean(v.bounded));
        }
        if (gate_json && noise_new[0])
            json_object_set_new(gate_json, "noise", json_string(noise_new));
    }
    rc = junit_conclude(o, &j, name, clock_mono_s() - t0);
    if (o->out_dir && s.n) {
        json_t *extra = json_pack("{s:o}", "gate_runs", run_set_json(&s));
        if (gate_json)
            json_object_set(extra, "gate", gate_json);
        json_t *written = fetch_job_files(c, first, o->out_dir, true, extra);
        bool ok = written && run_set_write(&s, o->out_dir);
        if (ok && gate_json) {
            char path[4096];
            snprintf(path, sizeof(path), "%s/gate.json", o->out_dir);
            ok = fs_write_json_atomic(path, gate_json);
        }
        json_decref(written);
        json_decref(extra);
        if (!ok)
            rc = EXIT_ERROR;
        else if (!o->quiet)
            fprintf(stderr, "files in %s\n", o->out_dir);
    }
out:
    json_decref(gate_json);
    json_decref(info);
    free(text);
    free(brun);
    run_set_finish(&s);
    junit_finish(&j);
    return rc;
}

/* One job, as submitted: the files, the quality verdicts, JUnit. Names
 * from user_spec (the job file) when there is one, else from the spec the
 * daemon filled in (fetch). */
static int finish_single(struct conn *c, const struct options *o, json_t *job,
                         const json_t *user_spec, double time_s)
{
    int rc = EXIT_PASS;
    if (o->out_dir) {
        json_t *written = fetch_job_files(c, job, o->out_dir, true, NULL);
        if (!written)
            rc = EXIT_ERROR;
        else if (!o->quiet)
            fprintf(stderr, "files in %s\n", o->out_dir);
        json_decref(written);
    }
    struct junit j;
    junit_init(&j);
    const json_t *spec = user_spec ? user_spec : json_object_get(job, "spec");
    char name[400], classname[96];
    junit_job_name(spec, name, sizeof(name));
    job_classname(spec, classname, sizeof(classname));
    struct junit_case *jc = job_case(&j, classname, name, job, time_s);
    json_t *result = json_object_get(job, RK_RESULT);
    struct gate_run run;
    if (jc && !jc->failure[0] && result) {
        /* Its timing figures judged alone by the noise rule: a run disturbed
         * by other processes is not a clean measurement, so it is no PASS. */
        gate_run_from_result(result, NULL, RK_FRAME_MS, &run);
        if (run.noisy_alone && run.has_share)
            junit_skip(jc, "NOISY", "its timing figures are not a clean measurement: other "
                       "processes took %.0f%% of the CPU during its timed frames (noisy: more than "
                       "%.0f%% less CPU left than an idle machine's)", 100 * run.other_share,
                       100 * NOISE_TOLERANCE);
        else if (run.noisy_alone)
            junit_skip(jc, "NOISY", "its timing figures are not a clean measurement: the "
                       "daemon marked the run noisy");
    }
    if (result)
        quality_cases(o, result, classname, name, &j);
    int verdict = junit_conclude(o, &j, name, time_s);
    junit_finish(&j);
    return rc == EXIT_ERROR ? rc : verdict;
}

int cmd_submit(struct conn *c, const struct options *o, const char *file)
{
    char err[600];
    if (o->baseline && !o->wait) {
        fprintf(stderr, "shadebench: --baseline needs --wait: the gate judges finished runs\n");
        return EXIT_ERROR;
    }
    if (o->runs > 1 && !o->wait) {
        fprintf(stderr, "shadebench: --runs needs --wait\n");
        return EXIT_ERROR;
    }
    if (o->out_dir && !o->wait) {
        fprintf(stderr, "shadebench: --out needs --wait: files exist once the job is done\n");
        return EXIT_ERROR;
    }
    if (o->out_dir && !out_dir_claim(o->out_dir, "job.json", NULL, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    if (!isnan(o->min_ssim) || !isnan(o->max_flip)) {
        /* A quality check that cannot judge anything is a usage error, found
         * before a job runs, not a failure found after it. */
        json_t *job = load_json_file("job file", file, err, sizeof(err));
        char why[300];
        bool judged = !job || workload_quality_judged(job, why, sizeof(why));
        json_decref(job);
        if (!judged) {
            fprintf(stderr, "shadebench: %s cannot be judged by %s: %s\n", file,
                    !isnan(o->min_ssim) ? "--min-ssim" : "--max-flip", why);
            return EXIT_ERROR;
        }
    }
    struct baseline base;
    if (o->baseline && !baseline_load(o->baseline, &base))
        return EXIT_ERROR;
    int runs = o->runs ? o->runs : o->baseline ? default_runs(file) : 1;
    if (o->baseline || runs > 1) {
        int rc = gate_or_runs(c, o, file, o->baseline ? &base : NULL, runs);
        if (o->baseline)
            baseline_finish(&base);
        return rc;
    }
    char *text = job_text_for_submit(file, o, 0, err, sizeof(err));
    if (!text) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    double t0 = clock_mono_s();
    json_t *reply = conn_json(c, "POST", "/v1/jobs", text, NULL);
    json_t *user_spec = json_loads(text, 0, NULL);
    free(text);
    if (!reply) {
        json_decref(user_spec);
        return EXIT_ERROR;
    }
    char id[64];
    snprintf(id, sizeof(id), "%s", json_string_value(json_object_get(reply, "id")));
    json_decref(reply);
    printf("%s\n", id);
    fflush(stdout);
    json_t *job = o->wait ? conn_follow_job(c, id, NULL, o->quiet, o->timeout_s) : NULL;
    int rc = !o->wait ? EXIT_PASS
             : job    ? finish_single(c, o, job, user_spec, clock_mono_s() - t0)
                      : EXIT_ERROR;
    json_decref(job);
    json_decref(user_spec);
    return rc;
}

int cmd_fetch(struct conn *c, const struct options *o, const char *id)
{
    char path[256], err[600];
    if (o->baseline) {
        fprintf(stderr, "shadebench: fetch judges one finished job; compare with a baseline "
                "through submit --wait --baseline\n");
        return EXIT_ERROR;
    }
    if (!out_dir_claim(o->out_dir, "job.json", id, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    json_t *job = conn_json(c, "GET", path, NULL, NULL);
    if (!job)
        return EXIT_ERROR;
    const char *status = json_string_value(json_object_get(job, "status"));
    if (status && (strcmp(status, "queued") == 0 || strcmp(status, "running") == 0)) {
        json_decref(job);
        if (!o->wait) {
            fprintf(stderr, "shadebench: job %s is %s; use --wait to wait for it\n", id, status);
            return EXIT_ERROR;
        }
        if (!(job = conn_follow_job(c, id, NULL, o->quiet, o->timeout_s)))
            return EXIT_ERROR;
    }
    int rc = finish_single(c, o, job, NULL, 0);
    json_decref(job);
    return rc;
}

int cmd_print(struct conn *c, const char *method, const char *path)
{
    json_t *j = conn_json(c, method, path, NULL, NULL);
    if (!j)
        return EXIT_ERROR;
    json_dumpf(j, stdout, JSON_INDENT(2));
    putchar('\n');
    json_decref(j);
    return EXIT_PASS;
}

/* One line of the info summary: a name and its summary, cut to fit a
 * terminal line. */
static void info_line(const char *name, const char *summary, size_t options)
{
    char opts[32] = "";
    if (options)
        snprintf(opts, sizeof(opts), " [%zu option%s]", options, options == 1 ? "" : "s");
    int room = 100 - 22 - (int)strlen(opts);
    int len = summary ? (int)strlen(summary) : 0;
    printf("  %-20s%.*s%s%s\n", name, len > room ? room - 3 : len, summary ? summary : "",
           len > room ? "..." : "", opts);
}

int cmd_info(struct conn *c)
{
    json_t *info = conn_json(c, "GET", "/v1/info", NULL, NULL);
    if (!info)
        return EXIT_ERROR;
    json_t *dev = json_object_get(info, "device");
    printf("%s %s (API %s) at %s\n", json_string_value(json_object_get(info, "name")),
           json_string_value(json_object_get(info, "version")),
           json_string_value(json_object_get(info, "api")), c->server);
    printf("device: %s, OpenGL %s, GLSL %s (EGL %s, %s platform)\n",
           json_string_value(json_object_get(dev, "gl_renderer")),
           json_string_value(json_object_get(dev, "gl_version")),
           json_string_value(json_object_get(dev, "glsl_version")),
           json_string_value(json_object_get(dev, "egl_device")),
           json_string_value(json_object_get(dev, "egl_platform")));
    printf("  timing series judged by default: %s\n", gate_default_series(dev));
    static const char *const lists[] = {"techniques", "effects"};
    for (int l = 0; l < 2; l++) {
        json_t *arr = json_object_get(info, lists[l]);
        printf("%s (%zu):\n", lists[l], json_array_size(arr));
        size_t i;
        json_t *t;
        json_array_foreach(arr, i, t)
            info_line(json_string_value(json_object_get(t, "name")),
                      json_string_value(json_object_get(t, "summary")),
                      json_object_size(json_object_get(t, "options")));
    }
    json_t *limits = json_object_get(info, "limits");
    printf("limits:");
    const char *key;
    json_t *v;
    const char *sep = " ";
    json_object_foreach(limits, key, v) {
        if (json_is_integer(v))
            printf("%s%s %lld", sep, key, (long long)json_integer_value(v));
        else if (json_is_number(v))
            printf("%s%s %g", sep, key, json_number_value(v));
        sep = ", ";
    }
    json_t *budget = json_object_get(json_object_get(info, "memory"), "budget_bytes");
    if (json_is_number(budget))
        printf("%smemory budget %.1f MiB", sep, json_number_value(budget) / (1024.0 * 1024.0));
    printf("\n%zu sweepable fields. shadebench info --json prints the daemon's whole answer "
           "(every option with its rule).\n", json_object_size(json_object_get(info, "sweepable")));
    json_decref(info);
    return EXIT_PASS;
}

int cmd_status(struct conn *c, const char *id)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    json_t *job = conn_json(c, "GET", path, NULL, NULL);
    if (!job)
        return EXIT_ERROR;
    json_t *p = json_object_get(job, "progress");
    const char *error = json_string_value(json_object_get(job, "error"));
    printf("%s %s %s %lld/%lld frames%s%s\n", id, json_string_value(json_object_get(job, "status")),
           json_string_value(json_object_get(job, "technique")),
           (long long)json_integer_value(json_object_get(p, "frames_done")),
           (long long)json_integer_value(json_object_get(p, "frames_total")), error ? "  " : "",
           error ? error : "");
    json_decref(job);
    return EXIT_PASS;
}

int cmd_list(struct conn *c)
{
    json_t *list = conn_list(c, "/v1/jobs", "jobs");
    if (!list)
        return EXIT_ERROR;
    size_t i;
    json_t *job;
    json_array_foreach(json_object_get(list, "jobs"), i, job) {
        json_t *p = json_object_get(job, "progress");
        printf("%-22s %-11s %-8s %lld/%lld\n", json_string_value(json_object_get(job, "id")),
               json_string_value(json_object_get(job, "status")),
               json_string_value(json_object_get(job, "technique")),
               (long long)json_integer_value(json_object_get(p, "frames_done")),
               (long long)json_integer_value(json_object_get(p, "frames_total")));
    }
    json_decref(list);
    return EXIT_PASS;
}
