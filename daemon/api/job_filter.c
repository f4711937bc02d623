#define _DEFAULT_SOURCE /* timegm */
#include "daemon/api/job_filter.h"
#include "common/result_keys.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void job_filter_init(struct job_filter *f) { memset(f, 0, sizeof(*f)); }

bool job_filter_parse_time(const char *text, char out[32])
{
    char *end;
    double secs = strtod(text, &end);
    if (end != text && *end == '\0' && strchr(text, '-') == NULL) {
        if (!(secs >= 0 && secs < 1e11))
            return false;
        time_t t = (time_t)secs;
        struct tm tm;
        gmtime_r(&t, &tm);
        char buf[80];
        snprintf(buf, sizeof(buf), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                 tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                 (int)((secs - (double)t) * 1000) % 1000);
        snprintf(out, 32, "%.31s", buf);
        return true;
    }
    int y, mo, d, h = 0, mi = 0, s = 0, ms = 0, n = 0;
    if (sscanf(text, "%4d-%2d-%2d%n", &y, &mo, &d, &n) != 3)
        return false;
    const char *p = text + n;
    if (*p == 'T' || *p == ' ') {
        int m = 0;
        if (sscanf(p + 1, "%2d:%2d%n", &h, &mi, &m) != 2)
            return false;
        p += 1 + m;
        if (*p == ':') {
            if (sscanf(p + 1, "%2d%n", &s, &m) != 1)
                return false;
            p += 1 + m;
            if (*p == '.') {
                int digits = 0;
                p++;
                while (isdigit((unsigned char)*p)) {
                    if (digits < 3)
                        ms = ms * 10 + (*p - '0');
                    digits++;
                    p++;
                }
                if (!digits)
                    return false;
                for (; digits < 3; digits++)
                    ms *= 10;
            }
        }
        if (*p == 'Z')
            p++;
    }
    if (*p || mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 || s > 60)
        return false;
    if (y < 1970 || y > 9999)
        return false;
    char buf[80];
    snprintf(buf, sizeof(buf), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", y, mo, d, h, mi, s, ms);
    snprintf(out, 32, "%.31s", buf);
    return true;
}

static bool add_term(struct job_filter *f, enum job_filter_kind kind, const char *label,
                     const char *value, const char *key, struct job_error *err)
{
    if (f->nterms == JOB_FILTER_MAX_TERMS)
        return job_error_set(err, key, "at most %d filters", JOB_FILTER_MAX_TERMS);
    if (strlen(value) >= sizeof(f->terms[0].value))
        return job_error_set(err, key, "must be at most %zu bytes", sizeof(f->terms[0].value) - 1);
    struct job_filter_term *t = &f->terms[f->nterms++];
    t->kind = kind;
    snprintf(t->label, sizeof(t->label), "%s", label ? label : "");
    snprintf(t->value, sizeof(t->value), "%s", value);
    return true;
}

bool job_filter_add(struct job_filter *f, const char *key, const char *value,
                    struct job_error *err)
{
    value = value ? value : "";
    if (!strcmp(key, "technique"))
        return add_term(f, FILTER_TECHNIQUE, NULL, value, key, err);
    if (!strcmp(key, "status")) {
        static const char *const names[] = {"queued", "running", "done", "failed",
                                            "cancelled", "interrupted", NULL};
        for (const char *const *n = names; *n; n++)
            if (!strcmp(*n, value))
                return add_term(f, FILTER_STATUS, NULL, value, key, err);
        char list[160];
        jf_list_choices(names, list, sizeof(list));
        return job_error_set(err, key, "must be one of: %s", list);
    }
    if (!strcmp(key, "since")) {
        if (!job_filter_parse_time(value, f->since))
            return job_error_set(err, key, "must be a UTC time like 2026-11-21, "
                                 "2026-11-21T10:00:00Z, or seconds since 1970");
        return true;
    }
    if (!strncmp(key, "label.", 6)) {
        const char *name = key + 6;
        size_t len = strlen(name);
        bool ok = len >= 1 && len <= 32;
        for (size_t i = 0; ok && i < len; i++)
            ok = isalnum((unsigned char)name[i]) || name[i] == '_' || name[i] == '-' ||
                 name[i] == '.';
        if (!ok)
            return job_error_set(err, key, "label names are 1 to 32 characters of A-Z, a-z, "
                                 "0-9, '_', '-' and '.'");
        return add_term(f, FILTER_LABEL, name, value, key, err);
    }
    char field[64];
    snprintf(field, sizeof(field), "%s", key);
    return job_error_set(err, field, "unknown filter: the job list takes technique=, status=, "
                         "label.NAME= and since=");
}

bool job_filter_match(const struct job_filter *f, const json_t *entry)
{
    if (f->since[0]) {
        const char *created = json_string_value(json_object_get(entry, "created"));
        if (!created || strcmp(created, f->since) < 0)
            return false;
    }
    /* Terms of one kind (and one label name) are alternatives: a group
     * holds when any of its terms does, and every group must hold. */
    for (size_t i = 0; i < f->nterms; i++) {
        const struct job_filter_term *t = &f->terms[i];
        bool first_of_group = true;
        for (size_t k = 0; k < i && first_of_group; k++)
            first_of_group = !(f->terms[k].kind == t->kind && !strcmp(f->terms[k].label, t->label));
        if (!first_of_group)
            continue;
        bool any = false;
        for (size_t k = i; k < f->nterms && !any; k++) {
            const struct job_filter_term *u = &f->terms[k];
            if (u->kind != t->kind || strcmp(u->label, t->label) != 0)
                continue;
            const char *have =
                u->kind == FILTER_TECHNIQUE ? json_string_value(json_object_get(entry, "technique"))
                : u->kind == FILTER_STATUS  ? json_string_value(json_object_get(entry, "status"))
                : json_string_value(json_object_get(json_object_get(entry, "labels"), u->label));
            any = have && !strcmp(have, u->value);
        }
        if (!any)
            return false;
    }
    return true;
}

/* A series' headline: over the runs of a repeated job (the median of run
 * medians, with the across-run interval), else over the frames. */
static json_t *series_figure(const json_t *result, const char *series)
{
    json_t *across = json_object_get(json_object_get(result, RK_REPEAT), series);
    json_t *st = json_object_get(result, series);
    if (!st && !across)
        return NULL;
    if (across)
        return json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(across, RK_MEDIAN), RK_CI95,
                         json_object_get(across, RK_CI95), "over", "runs");
    return json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(st, RK_MEDIAN), RK_CI95,
                     json_object_get(st, RK_MEDIAN_CI95), "over", "frames");
}

json_t *job_filter_figures(const json_t *result)
{
    if (!json_is_object(result))
        return NULL;
    json_t *o = json_object();
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    for (int k = 0; k < 3; k++) {
        json_t *fig = series_figure(result, series[k]);
        if (fig)
            json_object_set_new(o, series[k], fig);
    }
    json_t *rep = json_object_get(result, RK_REPEAT);
    json_object_set_new(o, RK_RUNS, json_integer(rep ? json_integer_value(json_object_get(rep, RK_RUNS)) : 1));
    json_t *ssim = json_object_get(json_object_get(json_object_get(result, RK_QUALITY), RK_WORST_SSIM),
                                   "value");
    if (json_is_number(ssim))
        json_object_set(o, RK_WORST_SSIM, ssim);
    json_t *dev = json_object_get(result, "device");
    static const char *const keep[] = {"gl_renderer", "gl_version"};
    for (int k = 0; k < 2; k++)
        if (json_is_string(json_object_get(dev, keep[k])))
            json_object_set(o, keep[k], json_object_get(dev, keep[k]));
    return o;
}

json_t *job_filter_visit(json_t *entry, const json_t *result, void *ctx)
{
    const struct job_filter *f = ctx;
    if (!job_filter_match(f, entry)) {
        json_decref(entry);
        return NULL;
    }
    json_t *fig = job_filter_figures(result);
    if (fig)
        json_object_set_new(entry, "figures", fig);
    return entry;
}
