/* shadebench: the client for CI farms and people. Submits jobs to shadebenchd,
 * follows them, downloads everything, and turns quality and timing into a
 * verdict: JUnit XML for CI systems and an exit status (0 pass, 1 regression
 * or quality failure, 2 usage or server error). */
#define _POSIX_C_SOURCE 200809L
#include <curl/curl.h>
#include <errno.h>
#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "client/stats_test.h"
#include "config.h"
#include "common/fsutil.h"

enum { EXIT_PASS = 0, EXIT_FAIL = 1, EXIT_ERROR = 2 };

struct client {
    char server[1024];
    const char *token;
    const char *out_dir;
    const char *junit;
    const char *baseline;
    const char *series; /* frame_ms, gpu_ms or cpu_ms */
    double max_slowdown;
    double min_ssim, max_flip; /* NAN: no gate */
    double timeout_s;          /* 0: wait as long as it takes */
    bool wait;
    bool quiet;
    CURL *curl;
};

struct buffer {
    char *data;
    size_t len;
};

static void die_usage(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));

static void die_usage(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("shadebench: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(EXIT_ERROR);
}

static size_t collect(char *ptr, size_t size, size_t n, void *user)
{
    struct buffer *b = user;
    char *grown = realloc(b->data, b->len + size * n + 1);
    if (!grown)
        return 0;
    b->data = grown;
    memcpy(b->data + b->len, ptr, size * n);
    b->len += size * n;
    b->data[b->len] = '\0';
    return size * n;
}

/* One request. Returns the HTTP status, or -1 when the server was not
 * reached (message printed). body may be NULL; out gets the response. */
static long request(struct client *c, const char *method, const char *path, const char *body,
                    struct buffer *out)
{
    char url[2048];
    snprintf(url, sizeof(url), "%s%s", c->server, path);
    out->data = NULL;
    out->len = 0;
    curl_easy_reset(c->curl);
    curl_easy_setopt(c->curl, CURLOPT_URL, url);
    curl_easy_setopt(c->curl, CURLOPT_CUSTOMREQUEST, method);
    curl_easy_setopt(c->curl, CURLOPT_WRITEFUNCTION, collect);
    curl_easy_setopt(c->curl, CURLOPT_WRITEDATA, out);
    curl_easy_setopt(c->curl, CURLOPT_CONNECTTIMEOUT, 10L);
    struct curl_slist *headers = NULL;
    char auth[1100];
    if (c->token && *c->token) {
        snprintf(auth, sizeof(auth), "Authorization: Bearer %s", c->token);
        headers = curl_slist_append(headers, auth);
    }
    if (body) {
        headers = curl_slist_append(headers, "Content-Type: application/json");
        curl_easy_setopt(c->curl, CURLOPT_POSTFIELDS, body);
        curl_easy_setopt(c->curl, CURLOPT_POSTFIELDSIZE, (long)strlen(body));
    }
    curl_easy_setopt(c->curl, CURLOPT_HTTPHEADER, headers);
    CURLcode rc = curl_easy_perform(c->curl);
    long status = -1;
    if (rc == CURLE_OK)
        curl_easy_getinfo(c->curl, CURLINFO_RESPONSE_CODE, &status);
    else
        fprintf(stderr, "shadebench: %s %s: %s\n", method, url, curl_easy_strerror(rc));
    curl_slist_free_all(headers);
    if (!out->data) {
        out->data = calloc(1, 1);
        out->len = 0;
    }
    return status;
}

/* A JSON request; on HTTP errors prints the daemon's error and returns NULL. */
static json_t *request_json(struct client *c, const char *method, const char *path,
                            const char *body, long *status_out)
{
    struct buffer b;
    long status = request(c, method, path, body, &b);
    if (status_out)
        *status_out = status;
    json_t *j = status > 0 ? json_loads(b.data, 0, NULL) : NULL;
    if (status >= 400 || (status > 0 && !j)) {
        json_t *e = json_object_get(j, "error");
        fprintf(stderr, "shadebench: %s %s: HTTP %ld: %s%s%s\n", method, path, status,
                json_string_value(json_object_get(e, "field")) ? json_string_value(json_object_get(e, "field")) : "",
                e ? ": " : "", e ? json_string_value(json_object_get(e, "message")) : b.data);
        json_decref(j);
        j = NULL;
    }
    free(b.data);
    return j;
}

static bool download(struct client *c, const char *path, const char *file)
{
    struct buffer b;
    long status = request(c, "GET", path, NULL, &b);
    bool ok = status == 200 && fs_write_atomic(file, b.data, b.len);
    if (!ok)
        fprintf(stderr, "shadebench: cannot download %s to %s (HTTP %ld)\n", path, file, status);
    free(b.data);
    return ok;
}

/* Per-frame samples of one series from timings.csv text. */
static json_t *parse_timings(const char *csv)
{
    json_t *series = json_object();
    const char *nl = strchr(csv, '\n');
    if (!nl)
        return series;
    char header[512];
    snprintf(header, sizeof(header), "%.*s", (int)(nl - csv), csv);
    char *names[16];
    int cols = 0;
    for (char *save = NULL, *t = strtok_r(header, ",", &save); t && cols < 16;
         t = strtok_r(NULL, ",", &save))
        names[cols++] = t;
    for (int i = 1; i < cols; i++)
        json_object_set_new(series, names[i], json_array());
    for (const char *line = nl + 1; *line;) {
        const char *end = strchr(line, '\n');
        char *p = (char *)line;
        for (int i = 0; i < cols; i++) {
            double v = strtod(p, &p);
            if (i > 0)
                json_array_append_new(json_object_get(series, names[i]), json_real(v));
            if (*p == ',')
                p++;
        }
        if (!end)
            break;
        line = end + 1;
    }
    return series;
}

/* Everything a job produced: job.json, result.json (with the per-frame
 * samples, so that it can serve as a baseline alone), timings.csv and every
 * image. */
static bool fetch_all(struct client *c, json_t *job, const char *dir)
{
    if (!fs_mkdir_p(dir)) {
        fprintf(stderr, "shadebench: cannot create %s\n", dir);
        return false;
    }
    char path[4096], url[512];
    const char *id = json_string_value(json_object_get(job, "id"));
    snprintf(path, sizeof(path), "%s/job.json", dir);
    bool ok = fs_write_json_atomic(path, job);
    json_t *result = json_object_get(job, "result");
    if (!result)
        return ok;
    snprintf(url, sizeof(url), "/v1/jobs/%s/timings.csv", id);
    struct buffer b;
    if (request(c, "GET", url, NULL, &b) == 200) {
        snprintf(path, sizeof(path), "%s/timings.csv", dir);
        ok = fs_write_atomic(path, b.data, b.len) && ok;
        json_t *copy = json_deep_copy(result);
        json_object_set_new(copy, "samples", parse_timings(b.data));
        json_object_set_new(copy, "job_id", json_string(id));
        snprintf(path, sizeof(path), "%s/result.json", dir);
        ok = fs_write_json_atomic(path, copy) && ok;
        json_decref(copy);
    } else {
        ok = false;
    }
    free(b.data);
    size_t i;
    json_t *capture;
    static const char *const kinds[][2] = {
        {"url", "frame"}, {"reference_url", "reference"}, {"ssim_map_url", "ssim"},
        {"flip_map_url", "flip"},
    };
    json_array_foreach(json_object_get(result, "captures"), i, capture) {
        int frame = (int)json_integer_value(json_object_get(capture, "frame"));
        for (size_t k = 0; k < sizeof(kinds) / sizeof(kinds[0]); k++) {
            const char *u = json_string_value(json_object_get(capture, kinds[k][0]));
            if (!u)
                continue;
            snprintf(path, sizeof(path), "%s/%s-%06d.png", dir, kinds[k][1], frame);
            ok = download(c, u, path) && ok;
        }
    }
    return ok;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

/* Follows the job until it ends: a progress bar on a terminal, plain lines
 * otherwise. Returns the final job, or NULL on a server error or time-out. */
static json_t *follow(struct client *c, const char *id)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/jobs/%s?wait=2", id);
    bool tty = isatty(STDERR_FILENO);
    double start = now_s(), first_running = 0, last_line = 0;
    int first_frames = 0;
    char last_phase[32] = "";
    for (;;) {
        json_t *job = request_json(c, "GET", path, NULL, NULL);
        if (!job)
            return NULL;
        const char *status = json_string_value(json_object_get(job, "status"));
        if (strcmp(status, "queued") != 0 && strcmp(status, "running") != 0) {
            if (tty && !c->quiet)
                fputc('\n', stderr);
            return job;
        }
        json_t *progress = json_object_get(job, "progress");
        int done = (int)json_integer_value(json_object_get(progress, "frames_done"));
        int total = (int)json_integer_value(json_object_get(progress, "frames_total"));
        const char *phase = json_string_value(json_object_get(job, "phase"));
        phase = phase ? phase : status;
        double t = now_s();
        if (strcmp(status, "running") == 0 && first_running == 0) {
            first_running = t;
            first_frames = done;
        }
        char eta[32] = "";
        double rate = first_running > 0 && t > first_running
                          ? (done - first_frames) / (t - first_running) : 0;
        if (rate > 0 && done < total)
            snprintf(eta, sizeof(eta), "ETA %.0f s", (total - done) / rate);
        if (!c->quiet && tty) {
            int width = 30, fill = total > 0 ? (int)((double)done / total * width) : 0;
            fprintf(stderr, "\r%s [%.*s%*s] %d/%d frames %3d%%  %-12s %-10s", id, fill,
                    "##############################", width - fill, "", done, total,
                    total > 0 ? 100 * done / total : 0, eta, phase);
            fflush(stderr);
        } else if (!c->quiet && (t - last_line >= 5 || strcmp(phase, last_phase) != 0)) {
            fprintf(stderr, "%s: %s, %d/%d frames%s%s\n", id, phase, done, total,
                    eta[0] ? ", " : "", eta);
            last_line = t;
        }
        snprintf(last_phase, sizeof(last_phase), "%s", phase);
        json_decref(job);
        if (c->timeout_s > 0 && t - start > c->timeout_s) {
            fprintf(stderr, "shadebench: job %s did not end within %.0f s\n", id, c->timeout_s);
            return NULL;
        }
    }
}

/* ---- verdicts and JUnit ---- */

struct testcase {
    char classname[64];
    char name[128];
    char failure[512]; /* empty: passed */
    char output[512];
};

struct verdicts {
    struct testcase *cases;
    size_t count, cap;
};

static struct testcase *add_case(struct verdicts *v, const char *classname, const char *name)
{
    if (v->count == v->cap) {
        v->cap = v->cap ? v->cap * 2 : 16;
        v->cases = realloc(v->cases, v->cap * sizeof(*v->cases));
        if (!v->cases)
            die_usage("out of memory");
    }
    struct testcase *t = &v->cases[v->count++];
    memset(t, 0, sizeof(*t));
    snprintf(t->classname, sizeof(t->classname), "%s", classname);
    snprintf(t->name, sizeof(t->name), "%s", name);
    return t;
}

static void append(char *dst, size_t cap, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void append(char *dst, size_t cap, const char *fmt, ...)
{
    size_t used = strlen(dst);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(dst + used, cap - used, fmt, ap);
    va_end(ap);
}

static void quality_cases(struct client *c, json_t *result, struct verdicts *v)
{
    size_t i;
    json_t *capture;
    json_array_foreach(json_object_get(result, "captures"), i, capture) {
        char name[64];
        snprintf(name, sizeof(name), "frame %lld quality",
                 (long long)json_integer_value(json_object_get(capture, "frame")));
        struct testcase *t = add_case(v, "shadebench.quality", name);
        json_t *m = json_object_get(capture, "metrics");
        if (!m) {
            if (!isnan(c->min_ssim) || !isnan(c->max_flip))
                append(t->failure, sizeof(t->failure),
                       "no metrics: submit the job with a \"reference\" technique");
            else
                append(t->output, sizeof(t->output), "no reference technique: nothing judged");
            continue;
        }
        json_t *pdiff = json_object_get(m, "pdiff");
        json_t *ssim = json_object_get(m, "ssim");
        json_t *flip = json_object_get(json_object_get(m, "flip"), "mean");
        if (pdiff && !json_is_true(json_object_get(pdiff, "pass")))
            append(t->failure, sizeof(t->failure), "PerceptualDiff failed: %lld pixels at %g degrees; ",
                   (long long)json_integer_value(json_object_get(pdiff, "failing_pixels")),
                   json_real_value(json_object_get(pdiff, "fov")));
        if (!isnan(c->min_ssim) && (!ssim || json_real_value(ssim) < c->min_ssim))
            append(t->failure, sizeof(t->failure), "SSIM %.6f below %.6f; ",
                   ssim ? json_real_value(ssim) : 0.0, c->min_ssim);
        if (!isnan(c->max_flip) && (!flip || json_real_value(flip) > c->max_flip))
            append(t->failure, sizeof(t->failure), "FLIP mean %.6f above %.6f; ",
                   flip ? json_real_value(flip) : 1.0, c->max_flip);
        append(t->output, sizeof(t->output), "SSIM %.6f, FLIP mean %.6f, PerceptualDiff %s",
               ssim ? json_real_value(ssim) : NAN, flip ? json_real_value(flip) : NAN,
               pdiff ? (json_is_true(json_object_get(pdiff, "pass")) ? "pass" : "fail") : "-");
    }
}

/* Samples of the chosen series: result.samples, else timings.csv beside the file. */
static double *load_samples(json_t *result, const char *series, const char *result_path,
                            size_t *n)
{
    json_t *arr = json_object_get(json_object_get(result, "samples"), series);
    json_t *own = NULL;
    if (!arr && result_path) {
        char csv_path[4096];
        snprintf(csv_path, sizeof(csv_path), "%s", result_path);
        char *slash = strrchr(csv_path, '/');
        snprintf(slash ? slash + 1 : csv_path,
                 sizeof(csv_path) - (size_t)(slash ? slash + 1 - csv_path : 0), "timings.csv");
        size_t len;
        char *csv = fs_read_file(csv_path, 64u << 20, &len);
        if (csv) {
            own = parse_timings(csv);
            arr = json_object_get(own, series);
            free(csv);
        }
    }
    *n = json_array_size(arr);
    double *v = *n ? malloc(*n * sizeof(double)) : NULL;
    for (size_t i = 0; v && i < *n; i++)
        v[i] = json_number_value(json_array_get(arr, i));
    json_decref(own);
    return v;
}

static bool timing_case(struct client *c, json_t *result, const char *result_path,
                        struct verdicts *v)
{
    json_error_t jerr;
    json_t *loaded = json_load_file(c->baseline, 0, &jerr);
    /* Either a result.json or a whole job.json with the result inside. */
    json_t *base = loaded && json_object_get(loaded, "result") ? json_object_get(loaded, "result")
                                                               : loaded;
    if (!base) {
        fprintf(stderr, "shadebench: --baseline %s: %s\n", c->baseline, jerr.text);
        return false;
    }
    size_t nb, nc;
    double *b = load_samples(base, c->series, c->baseline, &nb);
    double *s = load_samples(result, c->series, result_path, &nc);
    char name[96];
    snprintf(name, sizeof(name), "median %s vs baseline", c->series);
    struct regression_verdict r;
    bool ok = b && s && regression_test(b, nb, s, nc, c->max_slowdown, &r);
    if (!ok) {
        fprintf(stderr, "shadebench: --baseline: no per-frame %s samples (a result.json written by "
                "shadebench fetch/submit --out has them, or timings.csv beside it)\n", c->series);
    } else {
        struct testcase *t = add_case(v, "shadebench.timing", name);
        append(t->output, sizeof(t->output),
               "baseline median %.4f ms (%zu frames), now %.4f ms (%zu frames): %+.2f%%, "
               "one-sided Mann-Whitney p = %.4g, allowed %.2f%%",
               r.baseline_median, nb, r.new_median, nc, 100 * r.slowdown, r.p_value,
               100 * c->max_slowdown);
        if (r.regression)
            append(t->failure, sizeof(t->failure), "slower by %.2f%% (allowed %.2f%%), p = %.3g",
                   100 * r.slowdown, 100 * c->max_slowdown, r.p_value);
        if (!c->quiet)
            fprintf(stderr, "%s: %s%s\n", name, t->output,
                    r.regression ? "  => REGRESSION" : (r.slowdown > c->max_slowdown
                                                            ? "  => slower, but not significant"
                                                            : ""));
    }
    free(b);
    free(s);
    json_decref(loaded);
    return ok;
}

static void xml_escaped(FILE *f, const char *s)
{
    for (; *s; s++)
        switch (*s) {
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '&': fputs("&amp;", f); break;
        case '"': fputs("&quot;", f); break;
        default:
            if ((unsigned char)*s >= 0x20 || *s == '\n' || *s == '\t')
                fputc(*s, f);
        }
}

static bool write_junit(const char *path, const char *suite, double time_s, const struct verdicts *v)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return false;
    size_t failures = 0;
    for (size_t i = 0; i < v->count; i++)
        failures += v->cases[i].failure[0] != '\0';
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<testsuites name=\"shadebench\" tests=\"%zu\" failures=\"%zu\" time=\"%.3f\">\n",
            v->count, failures, time_s);
    fprintf(f, "  <testsuite name=\"");
    xml_escaped(f, suite);
    fprintf(f, "\" tests=\"%zu\" failures=\"%zu\" errors=\"0\" time=\"%.3f\">\n", v->count,
            failures, time_s);
    for (size_t i = 0; i < v->count; i++) {
        const struct testcase *t = &v->cases[i];
        fprintf(f, "    <testcase classname=\"%s\" name=\"", t->classname);
        xml_escaped(f, t->name);
        fprintf(f, "\" time=\"0\">\n");
        if (t->failure[0]) {
            fprintf(f, "      <failure type=\"%s\" message=\"", t->classname);
            xml_escaped(f, t->failure);
            fprintf(f, "\"/>\n");
        }
        if (t->output[0]) {
            fprintf(f, "      <system-out>");
            xml_escaped(f, t->output);
            fprintf(f, "</system-out>\n");
        }
        fprintf(f, "    </testcase>\n");
    }
    fprintf(f, "  </testsuite>\n</testsuites>\n");
    return fclose(f) == 0;
}

/* Judges a finished job: quality per capture, the timing gate, JUnit. */
static int judge(struct client *c, json_t *job, const char *result_path)
{
    struct verdicts v = {0};
    const char *id = json_string_value(json_object_get(job, "id"));
    const char *status = json_string_value(json_object_get(job, "status"));
    json_t *result = json_object_get(job, "result");
    char name[96];
    snprintf(name, sizeof(name), "job %s", id ? id : "?");
    struct testcase *t = add_case(&v, "shadebench.job", name);
    if (strcmp(status, "done") != 0)
        append(t->failure, sizeof(t->failure), "job %s: %s", status,
               json_string_value(json_object_get(job, "error")) ? json_string_value(json_object_get(job, "error")) : "");
    bool usable = true;
    if (result) {
        quality_cases(c, result, &v);
        if (c->baseline)
            usable = timing_case(c, result, result_path, &v);
    }
    size_t failures = 0;
    for (size_t i = 0; i < v.count; i++) {
        failures += v.cases[i].failure[0] != '\0';
        if (v.cases[i].failure[0] && !c->quiet)
            fprintf(stderr, "FAIL %s: %s\n", v.cases[i].name, v.cases[i].failure);
    }
    if (c->junit) {
        char suite[128];
        snprintf(suite, sizeof(suite), "shadebench.%s",
                 json_string_value(json_object_get(job, "technique")) ? json_string_value(json_object_get(job, "technique")) : "job");
        double wall = result ? json_real_value(json_object_get(result, "wall_s")) : 0;
        if (!write_junit(c->junit, suite, wall, &v)) {
            fprintf(stderr, "shadebench: cannot write %s\n", c->junit);
            usable = false;
        }
    }
    if (!c->quiet)
        fprintf(stderr, "%zu checks, %zu failed\n", v.count, failures);
    free(v.cases);
    if (!usable)
        return EXIT_ERROR;
    return failures ? EXIT_FAIL : EXIT_PASS;
}

/* ---- commands ---- */

static int finish_job(struct client *c, json_t *job)
{
    char result_path[4096] = "";
    int rc = EXIT_PASS;
    json_t *result = json_object_get(job, "result");
    if (result && c->baseline && !c->out_dir) {
        /* The timing gate needs this run's per-frame samples too. */
        char path[256];
        struct buffer b;
        snprintf(path, sizeof(path), "/v1/jobs/%s/timings.csv",
                 json_string_value(json_object_get(job, "id")));
        if (request(c, "GET", path, NULL, &b) == 200)
            json_object_set_new(result, "samples", parse_timings(b.data));
        free(b.data);
    }
    if (c->out_dir) {
        if (!fetch_all(c, job, c->out_dir))
            rc = EXIT_ERROR;
        snprintf(result_path, sizeof(result_path), "%s/result.json", c->out_dir);
        if (!c->quiet)
            fprintf(stderr, "files in %s\n", c->out_dir);
    }
    int verdict = judge(c, job, result_path[0] ? result_path : NULL);
    return rc == EXIT_ERROR ? rc : verdict;
}

static int cmd_submit(struct client *c, const char *file)
{
    size_t len;
    char *text = fs_read_file(file, 1 << 20, &len);
    if (!text)
        die_usage("cannot read %s", file);
    json_t *reply = request_json(c, "POST", "/v1/jobs", text, NULL);
    free(text);
    if (!reply)
        return EXIT_ERROR;
    char id[64];
    snprintf(id, sizeof(id), "%s", json_string_value(json_object_get(reply, "id")));
    json_decref(reply);
    printf("%s\n", id);
    fflush(stdout);
    if (!c->wait)
        return EXIT_PASS;
    json_t *job = follow(c, id);
    if (!job)
        return EXIT_ERROR;
    int rc = finish_job(c, job);
    json_decref(job);
    return rc;
}

static int cmd_fetch(struct client *c, const char *id)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    json_t *job = request_json(c, "GET", path, NULL, NULL);
    if (!job)
        return EXIT_ERROR;
    const char *status = json_string_value(json_object_get(job, "status"));
    if (strcmp(status, "queued") == 0 || strcmp(status, "running") == 0) {
        json_decref(job);
        if (!c->wait) {
            fprintf(stderr, "shadebench: job %s is %s; use --wait to wait for it\n", id, status);
            return EXIT_ERROR;
        }
        if (!(job = follow(c, id)))
            return EXIT_ERROR;
    }
    int rc = finish_job(c, job);
    json_decref(job);
    return rc;
}

static int print_json(struct client *c, const char *method, const char *path)
{
    json_t *j = request_json(c, method, path, NULL, NULL);
    if (!j)
        return EXIT_ERROR;
    json_dumpf(j, stdout, JSON_INDENT(2));
    putchar('\n');
    json_decref(j);
    return EXIT_PASS;
}

static int cmd_status(struct client *c, const char *id)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/jobs/%s", id);
    json_t *job = request_json(c, "GET", path, NULL, NULL);
    if (!job)
        return EXIT_ERROR;
    json_t *p = json_object_get(job, "progress");
    printf("%s %s %s %lld/%lld frames%s%s\n", id, json_string_value(json_object_get(job, "status")),
           json_string_value(json_object_get(job, "technique")),
           (long long)json_integer_value(json_object_get(p, "frames_done")),
           (long long)json_integer_value(json_object_get(p, "frames_total")),
           json_object_get(job, "error") ? "  " : "",
           json_object_get(job, "error") ? json_string_value(json_object_get(job, "error")) : "");
    json_decref(job);
    return EXIT_PASS;
}

static int cmd_list(struct client *c)
{
    json_t *list = request_json(c, "GET", "/v1/jobs", NULL, NULL);
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

static void usage(FILE *f)
{
    fprintf(f,
            "Usage: shadebench [OPTION]... COMMAND [ARG]\n"
            "Drives shadebenchd from CI farms and terminals.\n\n"
            "Commands:\n"
            "  submit JOB.json     submit a job (prints its id); with --wait follow it to the end\n"
            "  status ID           one line: status, technique, progress, error\n"
            "  list                every job, one a line\n"
            "  cancel ID           cancel a queued or running job\n"
            "  fetch ID            download a finished job (--out DIR) and judge it\n"
            "  info                the daemon's version, device and techniques\n\n"
            "Options:\n"
            "  --server URL        default $SHADEBENCH_SERVER, else http://127.0.0.1:8460\n"
            "  --token TOKEN       bearer token (default $SHADEBENCH_TOKEN)\n"
            "  --wait              follow the job with progress until it ends\n"
            "  --out DIR           download job.json, result.json, timings.csv and images\n"
            "  --junit FILE        write JUnit XML: the job, one case per capture, timing gates\n"
            "  --min-ssim X        a capture fails below this SSIM (needs a reference)\n"
            "  --max-flip X        a capture fails above this mean FLIP (needs a reference)\n"
            "  --baseline FILE     result.json (or job.json) of an earlier run to compare with\n"
            "  --max-slowdown P    allowed slowdown of the median, e.g. 5%% or 0.05 (default 5%%)\n"
            "  --series NAME       frame_ms (default), gpu_ms or cpu_ms for the timing gate\n"
            "  --timeout S         give up waiting after S seconds\n"
            "  --quiet             no progress or verdict lines on stderr\n\n"
            "Exit status: 0 pass, 1 regression or quality failure (or a failed job),\n"
            "2 usage or server error.\n");
}

int main(int argc, char **argv)
{
    struct client c = {.series = "frame_ms", .max_slowdown = 0.05, .min_ssim = NAN,
                       .max_flip = NAN};
    const char *server = getenv("SHADEBENCH_SERVER");
    snprintf(c.server, sizeof(c.server), "%s", server && *server ? server : "http://127.0.0.1:8460");
    c.token = getenv("SHADEBENCH_TOKEN");
    enum { O_SERVER = 256, O_TOKEN, O_WAIT, O_OUT, O_JUNIT, O_MIN_SSIM, O_MAX_FLIP, O_BASELINE,
           O_SLOWDOWN, O_SERIES, O_TIMEOUT, O_QUIET, O_HELP, O_VERSION };
    static const struct option longopts[] = {
        {"server", required_argument, NULL, O_SERVER},
        {"token", required_argument, NULL, O_TOKEN},
        {"wait", no_argument, NULL, O_WAIT},
        {"out", required_argument, NULL, O_OUT},
        {"junit", required_argument, NULL, O_JUNIT},
        {"min-ssim", required_argument, NULL, O_MIN_SSIM},
        {"max-flip", required_argument, NULL, O_MAX_FLIP},
        {"baseline", required_argument, NULL, O_BASELINE},
        {"max-slowdown", required_argument, NULL, O_SLOWDOWN},
        {"series", required_argument, NULL, O_SERIES},
        {"timeout", required_argument, NULL, O_TIMEOUT},
        {"quiet", no_argument, NULL, O_QUIET},
        {"help", no_argument, NULL, O_HELP},
        {"version", no_argument, NULL, O_VERSION},
        {NULL, 0, NULL, 0},
    };
    int opt;
    char *end;
    while ((opt = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (opt) {
        case O_SERVER: snprintf(c.server, sizeof(c.server), "%s", optarg); break;
        case O_TOKEN: c.token = optarg; break;
        case O_WAIT: c.wait = true; break;
        case O_OUT: c.out_dir = optarg; break;
        case O_JUNIT: c.junit = optarg; break;
        case O_MIN_SSIM:
            c.min_ssim = strtod(optarg, &end);
            if (*end || !(c.min_ssim >= -1 && c.min_ssim <= 1))
                die_usage("--min-ssim must be a number from -1 to 1");
            break;
        case O_MAX_FLIP:
            c.max_flip = strtod(optarg, &end);
            if (*end || !(c.max_flip >= 0 && c.max_flip <= 1))
                die_usage("--max-flip must be a number from 0 to 1");
            break;
        case O_BASELINE: c.baseline = optarg; break;
        case O_SLOWDOWN:
            c.max_slowdown = strtod(optarg, &end);
            if (*end == '%')
                c.max_slowdown /= 100.0, end++;
            if (*end || !(c.max_slowdown >= 0 && c.max_slowdown <= 100))
                die_usage("--max-slowdown must be like 5%% or 0.05");
            break;
        case O_SERIES:
            if (strcmp(optarg, "frame_ms") && strcmp(optarg, "gpu_ms") && strcmp(optarg, "cpu_ms"))
                die_usage("--series must be frame_ms, gpu_ms or cpu_ms");
            c.series = optarg;
            break;
        case O_TIMEOUT:
            c.timeout_s = strtod(optarg, &end);
            if (*end || !(c.timeout_s > 0))
                die_usage("--timeout must be a number of seconds above 0");
            break;
        case O_QUIET: c.quiet = true; break;
        case O_HELP: usage(stdout); return EXIT_PASS;
        case O_VERSION: printf("shadebench %s\n", PACKAGE_VERSION); return EXIT_PASS;
        default: usage(stderr); return EXIT_ERROR;
        }
    }
    size_t len = strlen(c.server);
    while (len && c.server[len - 1] == '/')
        c.server[--len] = '\0';
    if (optind >= argc) {
        usage(stderr);
        return EXIT_ERROR;
    }
    const char *cmd = argv[optind];
    const char *arg = optind + 1 < argc ? argv[optind + 1] : NULL;
    bool needs_arg = strcmp(cmd, "submit") == 0 || strcmp(cmd, "status") == 0 ||
                     strcmp(cmd, "cancel") == 0 || strcmp(cmd, "fetch") == 0;
    if (argc != optind + 1 + (needs_arg ? 1 : 0))
        die_usage("%s %s", cmd, needs_arg ? "takes one argument" : "takes no argument");
    if (strcmp(cmd, "fetch") == 0 && !c.out_dir)
        die_usage("fetch needs --out DIR");
    curl_global_init(CURL_GLOBAL_DEFAULT);
    c.curl = curl_easy_init();
    if (!c.curl)
        die_usage("cannot initialise libcurl");
    int rc;
    char path[256];
    if (strcmp(cmd, "submit") == 0)
        rc = cmd_submit(&c, arg);
    else if (strcmp(cmd, "status") == 0)
        rc = cmd_status(&c, arg);
    else if (strcmp(cmd, "list") == 0)
        rc = cmd_list(&c);
    else if (strcmp(cmd, "cancel") == 0) {
        snprintf(path, sizeof(path), "/v1/jobs/%s", arg);
        rc = print_json(&c, "DELETE", path);
    } else if (strcmp(cmd, "fetch") == 0)
        rc = cmd_fetch(&c, arg);
    else if (strcmp(cmd, "info") == 0)
        rc = print_json(&c, "GET", "/v1/info");
    else
        die_usage("unknown command %s (see --help)", cmd);
    curl_easy_cleanup(c.curl);
    curl_global_cleanup();
    return rc;
}
