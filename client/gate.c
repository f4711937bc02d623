#define _POSIX_C_SOURCE 200809L
#include "client/gate.h"
#include "common/result_keys.h"

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

double gate_cpu_left_change(double share, double reference)
{
    /* The CPU other processes left over, relative to the reference's: what
     * a CPU-bound renderer's speed follows when the machine is shared. */
    return (1.0 - share) / fmax(1.0 - reference, 0.01) - 1.0;
}

double gate_run_bound_ms(const struct gate_run *r, bool have_reference, double reference,
                         bool upper)
{
    if (!r->has_share || !have_reference)
        return r->ms;
    double scaled = r->ms * (1.0 + gate_cpu_left_change(r->other_share, reference));
    return upper ? fmax(r->ms, scaled) : fmin(r->ms, scaled);
}

double gate_pair_bound_ms(const struct gate_run *a, const struct gate_run *b, bool upper)
{
    return gate_run_bound_ms(b, a->has_share, a->other_share, upper);
}

size_t gate_mark_noisy(struct gate_run *runs, size_t n, bool have_reference, double reference,
                       double tolerance)
{
    size_t noisy = 0;
    for (size_t i = 0; i < n; i++) {
        struct gate_run *r = &runs[i];
        double change = r->has_share ? gate_cpu_left_change(r->other_share, reference) : 0.0;
        if (!r->noisy && r->has_share && have_reference && fabs(change) > tolerance) {
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
    const char *r = json_string_value(json_object_get(device, "gl_renderer"));
    if (!r)
        return RK_FRAME_MS;
    static const char *const software[] = {"llvmpipe", "softpipe", "SwiftShader", NULL};
    for (const char *const *s = software; *s; s++)
        if (strstr(r, *s))
            return RK_FRAME_MS;
    return RK_GPU_MS;
}
