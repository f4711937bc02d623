/* Talking to a daemon: requests, JSON errors, downloads, and following a
 * job or a sweep with progress. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client/client.h"
#include "client/term.h"
#include "common/fsutil.h"

bool conn_init(struct conn *c, const char *server, const char *token)
{
    memset(c, 0, sizeof(*c));
    snprintf(c->server, sizeof(c->server), "%s", server);
    size_t len = strlen(c->server);
    while (len && c->server[len - 1] == '/')
        c->server[--len] = '\0';
    c->token = token;
    c->curl = curl_easy_init();
    return c->curl != NULL;
}

void conn_finish(struct conn *c)
{
    if (c && c->curl)
        curl_easy_cleanup(c->curl);
    if (c)
        c->curl = NULL;
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

long conn_request(struct conn *c, const char *method, const char *path, const char *body,
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

json_t *conn_json(struct conn *c, const char *method, const char *path, const char *body,
                  long *status_out)
{
    struct buffer b;
    long status = conn_request(c, method, path, body, &b);
    if (status_out)
        *status_out = status;
    json_t *j = status > 0 ? json_loads(b.data ? b.data : "", 0, NULL) : NULL;
    if (status == 401) {
        /* The daemon answers a missing and a wrong token alike; the client
         * knows which it sent. */
        if (c->token && *c->token)
            fprintf(stderr, "shadebench: %s %s%s: HTTP 401: the daemon refused the token from "
                    "%s: it is not the token the daemon was started with (shadebenchd "
                    "--token FILE)\n", method, c->server, path,
                    c->token_source && *c->token_source ? c->token_source : "the command line");
        else
            fprintf(stderr, "shadebench: %s %s%s: HTTP 401: the daemon needs a token and none "
                    "was given: --token-file FILE, $SHADEBENCH_TOKEN or "
                    "$SHADEBENCH_TOKEN_FILE\n", method, c->server, path);
        json_decref(j);
        j = NULL;
    } else if (status >= 400 || (status > 0 && !j)) {
        json_t *e = json_object_get(j, "error");
        const char *field = json_string_value(json_object_get(e, "field"));
        const char *message = json_string_value(json_object_get(e, "message"));
        fprintf(stderr, "shadebench: %s %s%s: HTTP %ld: %s%s%s\n", method, c->server, path, status,
                field ? field : "", field ? ": " : "", message ? message : (b.data ? b.data : ""));
        json_decref(j);
        j = NULL;
    }
    free(b.data);
    return j;
}

json_t *conn_list(struct conn *c, const char *path, const char *key)
{
    json_t *all = json_array();
    char *at = strdup(path);
    /* Each page names the next (a path on this server) until the last. */
    while (at && all) {
        json_t *page = conn_json(c, "GET", at, NULL, NULL);
        if (!page) {
            json_decref(all);
            all = NULL;
            break;
        }
        json_array_extend(all, json_object_get(page, key));
        const char *next = json_string_value(json_object_get(page, "next"));
        char *follow = next && next[0] == '/' && strcmp(next, at) != 0 ? strdup(next) : NULL;
        free(at);
        at = follow;
        json_decref(page);
    }
    free(at);
    return all ? json_pack("{s:o}", key, all) : NULL;
}

bool conn_download(struct conn *c, const char *path, const char *file)
{
    struct buffer b;
    long status = conn_request(c, "GET", path, NULL, &b);
    bool ok = status == 200 && fs_write_atomic(file, b.data, b.len);
    if (!ok)
        fprintf(stderr, "shadebench: cannot download %s to %s (HTTP %ld)\n", path, file, status);
    free(b.data);
    return ok;
}

json_t *conn_follow_job(struct conn *c, const char *id, const char *what, bool quiet,
                        double timeout_s)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/jobs/%s?wait=2", id);
    bool tty = term_is_tty(stderr), drawn = false;
    double start = clock_mono_s(), first_running = 0, last_line = 0;
    int first_frames = 0;
    char last_phase[32] = "";
    what = what ? what : id;
    for (;;) {
        json_t *job = conn_json(c, "GET", path, NULL, NULL);
        if (!job)
            return NULL;
        const char *status = json_string_value(json_object_get(job, "status"));
        status = status ? status : "?";
        if (strcmp(status, "queued") != 0 && strcmp(status, "running") != 0) {
            /* The bar goes: the line that reports the run takes its place,
             * rather than a bar frozen at its last poll above it. */
            if (tty && !quiet && drawn) {
                fputs(TERM_CLEAR_LINE, stderr);
                fflush(stderr);
            }
            return job;
        }
        json_t *progress = json_object_get(job, "progress");
        int done = (int)json_integer_value(json_object_get(progress, "frames_done"));
        int total = (int)json_integer_value(json_object_get(progress, "frames_total"));
        const char *phase = json_string_value(json_object_get(job, "phase"));
        phase = phase ? phase : status;
        double t = clock_mono_s();
        if (strcmp(status, "running") == 0 && first_running == 0) {
            first_running = t;
            first_frames = done;
        }
        char eta[32] = "";
        double rate = first_running > 0 && t > first_running
                          ? (done - first_frames) / (t - first_running) : 0;
        if (rate > 0 && done < total)
            snprintf(eta, sizeof(eta), "ETA %.0f s", (total - done) / rate);
        if (!quiet && tty) {
            int width = 30, fill = total > 0 ? (int)((double)done / total * width) : 0;
            fprintf(stderr, TERM_CLEAR_LINE "%s [%.*s%*s] %d/%d frames %3d%%  %-12s %-10s", what,
                    fill, "##############################", width - fill, "", done, total,
                    total > 0 ? 100 * done / total : 0, eta, phase);
            fflush(stderr);
            drawn = true;
        } else if (!quiet && (t - last_line >= 5 || strcmp(phase, last_phase) != 0)) {
            fprintf(stderr, "%s: %s, %d/%d frames%s%s\n", what, phase, done, total,
                    eta[0] ? ", " : "", eta);
            last_line = t;
        }
        snprintf(last_phase, sizeof(last_phase), "%s", phase);
        json_decref(job);
        if (timeout_s > 0 && t - start > timeout_s) {
            if (drawn)
                fputs(TERM_CLEAR_LINE, stderr);
            fprintf(stderr, "shadebench: job %s did not end within %.0f s\n", id, timeout_s);
            return NULL;
        }
    }
}

json_t *conn_follow_sweep(struct conn *c, const char *id, bool quiet, double timeout_s)
{
    char path[256];
    snprintf(path, sizeof(path), "/v1/sweeps/%s?wait=5", id);
    double start = clock_mono_s();
    long last_done = -1;
    for (;;) {
        json_t *sw = conn_json(c, "GET", path, NULL, NULL);
        if (!sw)
            return NULL;
        const char *status = json_string_value(json_object_get(sw, "status"));
        status = status ? status : "?";
        json_t *p = json_object_get(sw, "progress");
        long done = (long)json_integer_value(json_object_get(p, "points_done"));
        long total = (long)json_integer_value(json_object_get(p, "points_total"));
        bool running = !strcmp(status, "queued") || !strcmp(status, "running");
        if (!quiet && (done != last_done || !running)) {
            const char *job = json_string_value(json_object_get(sw, "current_job"));
            fprintf(stderr, "sweep %s: %s, %ld/%ld points%s%s\n", id, status, done, total,
                    job ? ", running job " : "", job ? job : "");
            last_done = done;
        }
        if (!running)
            return sw;
        json_decref(sw);
        if (timeout_s > 0 && clock_mono_s() - start > timeout_s) {
            fprintf(stderr, "shadebench: sweep %s did not end within %.0f s\n", id, timeout_s);
            return NULL;
        }
    }
}

json_t *parse_timings(const char *csv)
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
