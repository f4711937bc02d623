/* history: the jobs that match filters, with a figure over time: a table on
 * stdout and, with --out, the list as JSON and CSV and a trend chart. Jobs
 * are grouped by workload (client/workload.h: what makes two jobs the same
 * measurement), so that the chart has a line per workload and the table a
 * column for it; noisy runs are marked in both. cmd_history fetches the
 * list; history_render lays it out. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "client/client.h"
#include "client/suggest.h"
#include "client/verdicts.h"
#include "client/trend.h"
#include "client/workload.h"
#include "common/fsutil.h"
#include "common/noise.h"
#include "common/result_keys.h"
#include "common/timing_series.h"

/* The figure of one list entry: its value and interval. */
static bool figure_of(const json_t *entry, const char *figure, double *y, double *lo, double *hi)
{
    json_t *figs = json_object_get(entry, "figures");
    *lo = *hi = NAN;
    if (!strcmp(figure, RK_WORST_SSIM)) {
        json_t *v = json_object_get(figs, RK_WORST_SSIM);
        *y = json_is_number(v) ? json_number_value(v) : NAN;
        return json_is_number(v);
    }
    json_t *f = json_object_get(figs, figure);
    json_t *m = json_object_get(f, RK_MEDIAN);
    if (!json_is_number(m))
        return false;
    *y = json_number_value(m);
    json_t *ci = json_object_get(f, RK_CI95);
    if (json_array_size(ci) == 2) {
        *lo = json_number_value(json_array_get(ci, 0));
        *hi = json_number_value(json_array_get(ci, 1));
    }
    return true;
}

static void labels_text(const json_t *labels, char *out, size_t cap)
{
    out[0] = '\0';
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)labels, key, v) {
        size_t used = strlen(out);
        snprintf(out + used, cap - used, "%s%s=%s", used ? "," : "", key, json_string_value(v));
    }
}

/* What the list does not carry, from the job itself: the spec (for the
 * workload: jobs of one workload form one series) and the interference
 * figures (for marking noisy runs). One request a job. */
struct job_detail {
    char key[96], workload[240];
    bool has_share, noisy;
    double other_share;
};

static void job_detail(struct conn *c, const char *id, bool by_reference, struct job_detail *d)
{
    memset(d, 0, sizeof(*d));
    d->other_share = NAN;
    char path[160];
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    json_t *job = id ? conn_json(c, "GET", path, NULL, NULL) : NULL;
    json_t *spec = json_object_get(job, "spec");
    workload_key(spec, d->key, sizeof(d->key));
    workload_describe(spec, d->workload, sizeof(d->workload));
    /* A quality figure is a series per reference too: scores against
     * forward and against forward supersampled are never one trend. The
     * timing figures ignore the reference, which changes nothing timed. */
    json_t *ref = json_object_get(spec, "reference");
    if (by_reference && json_is_object(ref)) {
        size_t used = strlen(d->key);
        snprintf(d->key + used, sizeof(d->key) - used, "@%.20sx%lld",
                 json_string_value(json_object_get(ref, "technique")) ? json_string_value(json_object_get(ref, "technique")) : "?",
                 (long long)json_integer_value(json_object_get(ref, "supersample")));
    } else if (by_reference && json_is_string(ref)) {
        size_t used = strlen(d->key);
        snprintf(d->key + used, sizeof(d->key) - used, "@%.20s", json_string_value(ref));
    }
    json_t *inter = json_object_get(json_object_get(job, RK_RESULT), RK_INTERFERENCE);
    json_t *share = json_object_get(inter, "other_cpu_share");
    d->has_share = json_is_number(share);
    d->other_share = d->has_share ? json_number_value(share) : NAN;
    /* The one noise rule, alone (against an idle machine), as the daemon
     * applies it; the daemon's flag only where there are no figures. */
    d->noisy = noise_interference_noisy(inter);
    json_decref(job);
}

/* The table, the CSV, history.json and the trend chart of jobs (the list's
 * entries). list is what history.json holds. False when a file could not
 * be written. */
static bool history_render(struct conn *c, const struct options *o, json_t *jobs, json_t *list)
{
    size_t n = json_array_size(jobs);
    /* The figure: as asked, else the one meaningful on the first job's
     * device (frame_ms on llvmpipe, where gpu_ms covers rasterization only). */
    const char *figure = o->figure ? o->figure : o->series;
    if (!figure) {
        figure = RK_FRAME_MS;
        size_t i;
        json_t *e;
        json_array_foreach(jobs, i, e) {
            const char *r = json_string_value(json_object_get(json_object_get(e, "figures"), "gl_renderer"));
            if (r) {
                figure = timing_series_for_renderer(r);
                break;
            }
        }
    }
    struct trend_point *pts = calloc(n ? n : 1, sizeof(*pts));
    size_t npts = 0;
    FILE *csv = NULL;
    char file[4096];
    bool ok = pts != NULL;
    if (o->out_dir) {
        ok = ok && fs_mkdir_p(o->out_dir);
        snprintf(file, sizeof(file), "%s/history.csv", o->out_dir);
        if (ok && !(csv = fopen(file, "w")))
            ok = false;
        if (csv)
            fprintf(csv, "id,created,status,technique,%s,%s_ci95_low,%s_ci95_high,worst_ssim,"
                    "other_cpu_share,noisy,workload,workload_key,gl_renderer,labels\n", figure,
                    figure, figure);
    }
    printf("%-22s %-24s %-9s %-10s %12s %-23s %-10s %-11s %-40s %s\n", "id", "created", "status",
           "technique", figure, "95% interval", "worst SSIM", "others' CPU", "workload", "labels");
    size_t i, noisy = 0;
    json_t *e;
    json_t *workloads = json_object(); /* key -> describe, for the summary */
    json_array_foreach(jobs, i, e) {
        double y, lo, hi;
        bool has = figure_of(e, figure, &y, &lo, &hi);
        json_t *figs = json_object_get(e, "figures");
        json_t *ssim = json_object_get(figs, RK_WORST_SSIM);
        char labels[512], interval[64] = "", ssim_text[32] = "-", noise[32] = "-";
        labels_text(json_object_get(e, "labels"), labels, sizeof(labels));
        if (!isnan(lo))
            snprintf(interval, sizeof(interval), "[%.4g, %.4g]", lo, hi);
        if (json_is_number(ssim))
            snprintf(ssim_text, sizeof(ssim_text), "%.6f", json_number_value(ssim));
        const char *id = json_string_value(json_object_get(e, "id"));
        const char *created = json_string_value(json_object_get(e, "created"));
        const char *tech = json_string_value(json_object_get(e, "technique"));
        const char *status = json_string_value(json_object_get(e, "status"));
        const char *renderer = json_string_value(json_object_get(figs, "gl_renderer"));
        struct job_detail d;
        job_detail(c, id, !strcmp(figure, RK_WORST_SSIM), &d);
        json_object_set_new(workloads, d.key, json_string(d.workload));
        noisy += d.noisy;
        if (d.has_share)
            snprintf(noise, sizeof(noise), "%s%.0f%%", d.noisy ? "NOISY " : "", 100 * d.other_share);
        else if (d.noisy)
            snprintf(noise, sizeof(noise), "NOISY");
        /* The workload column without the technique (a column of its own). */
        const char *wl = d.workload;
        if (tech && !strncmp(wl, tech, strlen(tech)) && wl[strlen(tech)] == ' ')
            wl += strlen(tech) + 1;
        char value[32] = "-";
        if (has)
            snprintf(value, sizeof(value), "%.4f", y);
        printf("%-22s %-24s %-9s %-10s %12s %-23s %-10s %-11s %-40s %s\n", id ? id : "",
               created ? created : "", status ? status : "", tech ? tech : "", value, interval,
               ssim_text, noise, wl, labels);
        if (csv) {
            char c_lo[32] = "", c_hi[32] = "", c_ssim[32] = "", c_share[32] = "";
            if (!isnan(lo)) {
                snprintf(c_lo, sizeof(c_lo), "%.6g", lo);
                snprintf(c_hi, sizeof(c_hi), "%.6g", hi);
            }
            if (json_is_number(ssim))
                snprintf(c_ssim, sizeof(c_ssim), "%.6f", json_number_value(ssim));
            if (d.has_share)
                snprintf(c_share, sizeof(c_share), "%.4f", d.other_share);
            fprintf(csv, "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,\"%s\",%s,\"%s\",\"%s\"\n", id ? id : "",
                    created ? created : "", status ? status : "", tech ? tech : "",
                    has ? value : "", c_lo, c_hi, c_ssim, c_share, d.noisy ? "true" : "false",
                    d.workload, d.key, renderer ? renderer : "", labels);
        }
        json_object_set_new(e, "workload", json_pack("{s:s, s:s}", "key", d.key, "name", d.workload));
        if (has && pts) {
            struct trend_point *p = &pts[npts++];
            p->t = iso_unix_s(created);
            p->y = y;
            p->lo = lo;
            p->hi = hi;
            snprintf(p->series, sizeof(p->series), "%.47s", d.key);
            snprintf(p->name, sizeof(p->name), "%s", d.workload);
            snprintf(p->label, sizeof(p->label), "%s", id ? id : "");
            p->noisy = d.noisy;
            p->other_share = d.other_share;
            if (isnan(p->t))
                npts--;
        }
    }
    if (!o->quiet) {
        fprintf(stderr, "%zu jobs, %zu workload%s (a series each)", n, json_object_size(workloads),
                json_object_size(workloads) == 1 ? "" : "s");
        if (noisy)
            fprintf(stderr, "; %zu noisy run%s (others' CPU marked NOISY): compare them with care",
                    noisy, noisy == 1 ? "" : "s");
        fputc('\n', stderr);
    }
    json_decref(workloads);
    if (csv && fclose(csv) != 0)
        ok = false;
    if (o->out_dir && ok) {
        snprintf(file, sizeof(file), "%s/history.json", o->out_dir);
        json_object_set_new(list, "id", json_string("history"));
        json_object_set_new(list, "figure", json_string(figure));
        ok = fs_write_json_atomic(file, list);
        char title[160], ylabel[96];
        snprintf(title, sizeof(title), "%s over time (%zu jobs)", figure, npts);
        snprintf(ylabel, sizeof(ylabel), "%s%s", strcmp(figure, RK_WORST_SSIM) ? "median " : "",
                 figure);
        char *svg = trend_svg(pts, npts, title, ylabel);
        snprintf(file, sizeof(file), "%s/trend.svg", o->out_dir);
        ok = ok && svg && fs_write_atomic(file, svg, strlen(svg));
        free(svg);
        if (ok && !o->quiet)
            fprintf(stderr, "files in %s\n", o->out_dir);
    }
    free(pts);
    return ok;
}

/* A technique filter that matched no job: a typo ("fowrard") must not read
 * as an empty history. True when the daemon knows the technique (it has
 * merely no finished job yet); else the error, with the nearest name. A
 * technique the daemon no longer has still matches its old jobs, so this
 * is asked only when nothing matched. */
static bool known_technique(struct conn *c, const char *tech)
{
    json_t *info = conn_json(c, "GET", "/v1/info", NULL, NULL);
    if (!info)
        return false;
    json_t *list = json_object_get(info, "techniques");
    const char *names[64];
    size_t n = 0, i;
    json_t *t;
    bool known = false;
    json_array_foreach(list, i, t) {
        const char *name = json_string_value(json_object_get(t, "name"));
        if (name && n < 64)
            names[n++] = name;
        known = known || (name && !strcmp(name, tech));
    }
    if (!known) {
        const char *near = suggest_nearest(tech, names, n);
        char all[1024] = "";
        for (size_t k = 0; k < n; k++) {
            size_t used = strlen(all);
            snprintf(all + used, sizeof(all) - used, "%s%s", k ? ", " : "", names[k]);
        }
        fprintf(stderr, "shadebench: --filter technique=%s matches no job and no technique the "
                "daemon knows%s%s%s (it knows %s)\n", tech, near ? "; did you mean " : "",
                near ? near : "", near ? "?" : "", all);
    }
    json_decref(info);
    return known;
}

int cmd_history(struct conn *c, const struct options *o)
{
    /* The whole history, page after page (the daemon's pages unless
     * --filter limit=N; no limit of our own, which a daemon from before
     * pages would refuse). */
    char err[600], query[4096] = "";
    if (o->out_dir && !out_dir_claim(o->out_dir, "history.json", NULL, err, sizeof(err))) {
        fprintf(stderr, "shadebench: %s\n", err);
        return EXIT_ERROR;
    }
    /* Finished jobs unless a status filter says otherwise. */
    bool has_status = json_object_get(o->filters, "status") != NULL;
    const char *key;
    json_t *v;
    json_object_foreach(o->filters, key, v) {
        char *k = curl_easy_escape(c->curl, key, 0), *val = curl_easy_escape(c->curl, json_string_value(v), 0);
        size_t used = strlen(query);
        snprintf(query + used, sizeof(query) - used, "%c%s=%s", used ? '&' : '?', k ? k : "",
                 val ? val : "");
        curl_free(k);
        curl_free(val);
    }
    if (!has_status) {
        size_t used = strlen(query);
        snprintf(query + used, sizeof(query) - used, "%cstatus=done", used ? '&' : '?');
    }
    if (o->since) {
        char *val = curl_easy_escape(c->curl, o->since, 0);
        size_t used = strlen(query);
        snprintf(query + used, sizeof(query) - used, "&since=%s", val ? val : "");
        curl_free(val);
    }
    char path[4200];
    snprintf(path, sizeof(path), "/v1/jobs%s", query);
    json_t *list = conn_list(c, path, "jobs");
    if (!list)
        return EXIT_ERROR;
    json_t *jobs = json_object_get(list, "jobs");
    const char *tech = json_string_value(json_object_get(o->filters, "technique"));
    if (!json_array_size(jobs) && tech && !known_technique(c, tech)) {
        json_decref(list);
        return EXIT_ERROR;
    }
    bool ok = history_render(c, o, jobs, list);
    json_decref(list);
    if (!ok) {
        fprintf(stderr, "shadebench: cannot write the history files in %s\n", o->out_dir);
        return EXIT_ERROR;
    }
    return EXIT_PASS;
}
