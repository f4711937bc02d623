/* history: the jobs that match filters, with a figure over time: a table on
 * stdout and, with --out, the list as JSON and CSV and a trend chart. */
#define _DEFAULT_SOURCE /* timegm */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "client/client.h"
#include "client/trend.h"
#include "common/fsutil.h"
#include "common/result_keys.h"

static double iso_to_unix(const char *s)
{
    struct tm tm;
    memset(&tm, 0, sizeof(tm));
    int ms = 0;
    if (!s || sscanf(s, "%d-%d-%dT%d:%d:%d.%dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                     &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &ms) < 6)
        return NAN;
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    return (double)timegm(&tm) + ms / 1000.0;
}

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
                figure = strstr(r, "llvmpipe") || strstr(r, "softpipe") || strstr(r, "SwiftShader")
                             ? RK_FRAME_MS : RK_GPU_MS;
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
                    "gl_renderer,labels\n", figure, figure, figure);
    }
    printf("%-22s %-24s %-9s %-10s %12s %-23s %-10s %s\n", "id", "created", "status", "technique",
           figure, "95% interval", "worst SSIM", "labels");
    size_t i;
    json_t *e;
    json_array_foreach(jobs, i, e) {
        double y, lo, hi;
        bool has = figure_of(e, figure, &y, &lo, &hi);
        json_t *figs = json_object_get(e, "figures");
        json_t *ssim = json_object_get(figs, RK_WORST_SSIM);
        char labels[512], interval[64] = "", ssim_text[32] = "-";
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
        char value[32] = "-";
        if (has)
            snprintf(value, sizeof(value), "%.4f", y);
        printf("%-22s %-24s %-9s %-10s %12s %-23s %-10s %s\n", id ? id : "", created ? created : "",
               status ? status : "", tech ? tech : "", value, interval, ssim_text, labels);
        if (csv) {
            char c_lo[32] = "", c_hi[32] = "", c_ssim[32] = "";
            if (!isnan(lo)) {
                snprintf(c_lo, sizeof(c_lo), "%.6g", lo);
                snprintf(c_hi, sizeof(c_hi), "%.6g", hi);
            }
            if (json_is_number(ssim))
                snprintf(c_ssim, sizeof(c_ssim), "%.6f", json_number_value(ssim));
            fprintf(csv, "%s,%s,%s,%s,%s,%s,%s,%s,\"%s\",\"%s\"\n", id ? id : "",
                    created ? created : "", status ? status : "", tech ? tech : "",
                    has ? value : "", c_lo, c_hi, c_ssim, renderer ? renderer : "", labels);
        }
        if (has && pts) {
            struct trend_point *p = &pts[npts++];
            p->t = iso_to_unix(created);
            p->y = y;
            p->lo = lo;
            p->hi = hi;
            snprintf(p->series, sizeof(p->series), "%s", tech ? tech : "?");
            snprintf(p->label, sizeof(p->label), "%s", id ? id : "");
            if (isnan(p->t))
                npts--;
        }
    }
    if (!o->quiet)
        fprintf(stderr, "%zu jobs\n", n);
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
    json_decref(list);
    if (!ok) {
        fprintf(stderr, "shadebench: cannot write the history files in %s\n", o->out_dir);
        return EXIT_ERROR;
    }
    return EXIT_PASS;
}
