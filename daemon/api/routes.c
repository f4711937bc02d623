#define _POSIX_C_SOURCE 200809L
#include "daemon/api/routes.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const struct {
    const char *label, *allow, *rule;
} KINDS[ROUTE_COUNT] = {
    [ROUTE_NONE] = {"other", "GET", "use GET"},
    [ROUTE_HEALTHZ] = {"/healthz", "GET, HEAD", "use GET"},
    [ROUTE_METRICS] = {"/metrics", "GET, HEAD", "use GET"},
    [ROUTE_INFO] = {"/v1/info", "GET, HEAD", "use GET"},
    [ROUTE_JOBS] = {"/v1/jobs", "GET, HEAD, POST", "use GET to list jobs or POST to submit one"},
    [ROUTE_JOB] = {"/v1/jobs/{id}", "GET, HEAD, DELETE", "use GET or DELETE on a job"},
    [ROUTE_JOB_REPORT] = {"/v1/jobs/{id}/report.html", "GET, HEAD", "use GET"},
    [ROUTE_JOB_CHART] = {"/v1/jobs/{id}/charts/{name}", "GET, HEAD", "use GET"},
    [ROUTE_JOB_TIMINGS] = {"/v1/jobs/{id}/timings.csv", "GET, HEAD", "use GET"},
    [ROUTE_JOB_IMAGE] = {"/v1/jobs/{id}/{images}/{frame}.png", "GET, HEAD", "use GET"},
    [ROUTE_JOB_PDIFF] = {"/v1/jobs/{id}/pdiff/{frame}.png", "GET, HEAD", "use GET"},
    [ROUTE_JOB_HISTORY] = {"/v1/jobs/{id}/history", "GET, HEAD", "use GET"},
    [ROUTE_SWEEPS] = {"/v1/sweeps", "GET, HEAD, POST", "use GET to list sweeps or POST to start one"},
    [ROUTE_SWEEP] = {"/v1/sweeps/{id}", "GET, HEAD, DELETE", "use GET or DELETE on a sweep"},
    [ROUTE_SWEEP_CHART] = {"/v1/sweeps/{id}/charts/{name}", "GET, HEAD", "use GET"},
    [ROUTE_SWEEP_REPORT] = {"/v1/sweeps/{id}/report.html", "GET, HEAD", "use GET"},
    [ROUTE_SWEEP_VERDICT] = {"/v1/sweeps/{id}/verdict", "GET, HEAD", "use GET"},
    [ROUTE_ASSETS] = {"/v1/assets", "GET, HEAD", "use GET to list assets; PUT /v1/assets/NAME uploads one"},
    [ROUTE_ASSET] = {"/v1/assets/{name}", "GET, HEAD, PUT, DELETE",
                     "use PUT to upload the asset's file as the body, GET or DELETE"},
    [ROUTE_UI] = {"/ui", "GET, HEAD", "use GET"},
    [ROUTE_JOB_FIDELITY] = {"/v1/jobs/{id}/fidelity/{file}", "GET, HEAD", "use GET"},
    [ROUTE_ASSET_FIDELITY] = {"/v1/assets/{name}/fidelity", "POST",
                              "use POST to compare the asset with the Khronos viewer"},
};


static bool none(struct route *r, const char *field, const char *message)
{
    r->kind = ROUTE_NONE;
    r->field = field;
    r->message = message;
    return false;
}

/* Job and sweep ids are time stamps with a serial: digits and dashes. */
static bool take_id(const char *s, size_t len, struct route *r)
{
    if (len == 0 || len >= sizeof(r->id))
        return false;
    for (size_t i = 0; i < len; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || s[i] == '-'))
            return false;
    memcpy(r->id, s, len);
    r->id[len] = '\0';
    return true;
}

/* "NAME.svg" or "NAME.png", NAME of letters, digits and underscores. */
static bool take_chart(const char *s, struct route *r)
{
    const char *dot = strrchr(s, '.');
    if (!dot || dot == s || (size_t)(dot - s) >= sizeof(r->chart))
        return false;
    if (strcmp(dot, ".svg") != 0 && strcmp(dot, ".png") != 0)
        return false;
    for (const char *p = s; p < dot; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
              *p == '_'))
            return false;
    memcpy(r->chart, s, (size_t)(dot - s));
    r->chart[dot - s] = '\0';
    r->chart_png = strcmp(dot, ".png") == 0;
    return true;
}

/* "K.png" with K a positive decimal of at most 9 digits, no sign or spaces. */
static bool take_frame(const char *s, struct route *r)
{
    int frame = 0, digits = 0;
    /* Nine digits at most: their value always fits an int. */
    while (digits < 9 && s[digits] >= '0' && s[digits] <= '9')
        frame = frame * 10 + (s[digits] - '0'), digits++;
    if (digits == 0 || strcmp(s + digits, ".png") != 0 || frame <= 0)
        return false;
    r->frame = frame;
    return true;
}

static bool job_routes(const char *rest, struct route *r)
{
    const char *slash = strchr(rest, '/');
    if (!take_id(rest, slash ? (size_t)(slash - rest) : strlen(rest), r))
        return none(r, "id", "no such job");
    if (!slash) {
        r->kind = ROUTE_JOB;
        return true;
    }
    const char *sub = slash + 1;
    if (strcmp(sub, "report.html") == 0) {
        r->kind = ROUTE_JOB_REPORT;
        return true;
    }
    if (strcmp(sub, JOB_FILE_TIMINGS) == 0) {
        r->kind = ROUTE_JOB_TIMINGS;
        return true;
    }
    if (strcmp(sub, "history") == 0) {
        r->kind = ROUTE_JOB_HISTORY;
        return true;
    }
    if (strncmp(sub, "charts/", 7) == 0) {
        if (!take_chart(sub + 7, r))
            return none(r, "chart", "charts are NAME.svg or NAME.png");
        r->kind = ROUTE_JOB_CHART;
        return true;
    }
    if (strncmp(sub, "pdiff/", 6) == 0) {
        if (!take_frame(sub + 6, r))
            return none(r, "frame", "masks are K.png with K a captured frame (see result.captures)");
        r->kind = ROUTE_JOB_PDIFF;
        return true;
    }
    if (strncmp(sub, "fidelity/", 9) == 0) {
        const char *f = sub + 9;
        size_t n = strlen(f);
        bool ok = n > 4 && n < sizeof(r->chart) && strcmp(f + n - 4, ".png") == 0;
        for (size_t i = 0; ok && i < n - 4; i++)
            ok = (f[i] >= 'a' && f[i] <= 'z') || (f[i] >= '0' && f[i] <= '9') || f[i] == '_' ||
                 f[i] == '-';
        if (!ok)
            return none(r, "file", "fidelity images are NAME.png (see result.fidelity)");
        memcpy(r->chart, f, n + 1);
        r->kind = ROUTE_JOB_FIDELITY;
        return true;
    }
    for (int k = 0; k < JOB_IMAGE_COUNT; k++) {
        const char *folder = job_image_kind((enum job_image)k)->folder;
        size_t len = strlen(folder);
        if (strncmp(sub, folder, len) == 0 && sub[len] == '/') {
            if (!take_frame(sub + len + 1, r))
                return none(r, "frame", "images are K.png with K a captured frame (see result.captures)");
            r->kind = ROUTE_JOB_IMAGE;
            r->image = (enum job_image)k;
            return true;
        }
    }
    return none(r, "url", "no such resource");
}

static bool sweep_routes(const char *rest, struct route *r)
{
    if (!*rest) {
        r->kind = ROUTE_SWEEPS;
        return true;
    }
    size_t id_len = strcspn(rest, "/");
    if (!take_id(rest, id_len, r))
        return none(r, "id", "no such sweep");
    if (!rest[id_len]) {
        r->kind = ROUTE_SWEEP;
        return true;
    }
    const char *sub = rest + id_len + 1;
    if (strcmp(sub, "report.html") == 0) {
        r->kind = ROUTE_SWEEP_REPORT;
        return true;
    }
    if (strcmp(sub, "verdict") == 0) {
        r->kind = ROUTE_SWEEP_VERDICT;
        return true;
    }
    if (strncmp(sub, "charts/", 7) == 0) {
        if (!take_chart(sub + 7, r))
            return none(r, "chart", "charts are NAME.svg or NAME.png");
        r->kind = ROUTE_SWEEP_CHART;
        return true;
    }
    return none(r, "url", "no such resource");
}

bool route_parse(const char *url, struct route *r)
{
    memset(r, 0, sizeof(*r));
    if (strcmp(url, "/healthz") == 0)
        r->kind = ROUTE_HEALTHZ;
    else if (strcmp(url, "/metrics") == 0)
        r->kind = ROUTE_METRICS;
    else if (strcmp(url, "/v1/info") == 0)
        r->kind = ROUTE_INFO;
    else if (strcmp(url, "/v1/jobs") == 0 || strcmp(url, "/v1/jobs/") == 0)
        r->kind = ROUTE_JOBS;
    else if (strncmp(url, "/v1/jobs/", 9) == 0)
        return job_routes(url + 9, r);
    else if (strcmp(url, "/v1/sweeps") == 0)
        r->kind = ROUTE_SWEEPS;
    else if (strncmp(url, "/v1/sweeps/", 11) == 0)
        return sweep_routes(url + 11, r);
    else if (strcmp(url, "/") == 0 || strcmp(url, "/ui") == 0 || strcmp(url, "/ui/") == 0) {
        r->kind = ROUTE_UI;
        snprintf(r->ui, sizeof(r->ui), "/ui/index.html");
    } else if (strncmp(url, "/ui/", 4) == 0) {
        /* The handler looks the file up: an unknown one is a 404 there. */
        if (strlen(url) >= sizeof(r->ui))
            return none(r, "url", "no such file of the dashboard");
        r->kind = ROUTE_UI;
        snprintf(r->ui, sizeof(r->ui), "%s", url);
    } else if (strcmp(url, "/v1/assets") == 0 || strcmp(url, "/v1/assets/") == 0)
        r->kind = ROUTE_ASSETS;
    else if (strncmp(url, "/v1/assets/", 11) == 0) {
        /* One path segment; its rules are the handler's (a 400 naming it). */
        const char *name = url + 11;
        const char *slash = strchr(name, '/');
        if (slash && (strcmp(slash, "/fidelity") != 0 || slash == name))
            return none(r, "url", "no such resource: an asset is /v1/assets/NAME (and "
                        "/v1/assets/NAME/fidelity)");
        size_t len = slash ? (size_t)(slash - name) : strlen(name);
        r->asset_too_long = len > ROUTE_ASSET_NAME_MAX;
        if (r->asset_too_long)
            len = ROUTE_ASSET_NAME_MAX;
        memcpy(r->asset, name, len);
        r->asset[len] = '\0';
        r->kind = slash ? ROUTE_ASSET_FIDELITY : ROUTE_ASSET;
    }
    else
        return none(r, "url", "no such route");
    return true;
}

bool route_check_target(const char *target, size_t *args, const char **field,
                        const char **message)
{
    const char *query = strchr(target, '?');
    *args = 0;
    if (query && query[1]) {
        *args = 1;
        for (const char *p = query + 1; *p; p++)
            *args += *p == '&';
    }
    for (const char *p = strchr(target, '%'); p; p = strchr(p + 1, '%')) {
        if (!isxdigit((unsigned char)p[1]) || !isxdigit((unsigned char)p[2])) {
            /* RFC 3986: libmicrohttpd would pass "%zz" through as it is. */
            *field = "url";
            *message = "a percent-encoding must be '%' and two hexadecimal digits (RFC 3986)";
            return false;
        }
        if (p[1] == '0' && p[2] == '0') {
            *field = "url";
            *message = "must not contain an encoded NUL byte (%00), which would cut it short";
            return false;
        }
    }
    if (*args > ROUTE_MAX_QUERY_ARGS) {
        *field = "query";
        *message = "at most 64 query arguments (filters, limit, cursor, wait, ...)";
        return false;
    }
    return true;
}

bool route_method_ok(enum route_kind kind, const char *method, const char **allow,
                     const char **rule)
{
    if ((unsigned)kind >= ROUTE_COUNT)
        kind = ROUTE_NONE;
    *allow = KINDS[kind].allow;
    *rule = KINDS[kind].rule;
    if (strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0)
        return kind != ROUTE_ASSET_FIDELITY;
    if (strcmp(method, "POST") == 0)
        return kind == ROUTE_JOBS || kind == ROUTE_SWEEPS || kind == ROUTE_ASSET_FIDELITY;
    if (strcmp(method, "DELETE") == 0)
        return kind == ROUTE_JOB || kind == ROUTE_SWEEP || kind == ROUTE_ASSET;
    if (strcmp(method, "PUT") == 0)
        return kind == ROUTE_ASSET;
    return false;
}

const char *route_label(enum route_kind kind)
{
    return (unsigned)kind < ROUTE_COUNT ? KINDS[kind].label : KINDS[ROUTE_NONE].label;
}

void route_job_url(const char *id, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/jobs/%s", id);
}

void route_timings_url(const char *id, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/jobs/%s/%s", id, JOB_FILE_TIMINGS);
}

void route_sweep_url(const char *id, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/sweeps/%s", id);
}

void route_asset_url(const char *name, char out[ROUTE_URL_MAX + ROUTE_ASSET_NAME_MAX])
{
    snprintf(out, ROUTE_URL_MAX + ROUTE_ASSET_NAME_MAX, "/v1/assets/%s", name);
}

void route_image_url(const char *id, enum job_image image, int frame, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/jobs/%s/%s/%d.png", id, job_image_kind(image)->folder, frame);
}

void route_pdiff_url(const char *id, int frame, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/jobs/%s/pdiff/%d.png", id, frame);
}

void route_history_url(const char *id, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/jobs/%s/history", id);
}

void route_verdict_url(const char *id, char out[ROUTE_URL_MAX])
{
    snprintf(out, ROUTE_URL_MAX, "/v1/sweeps/%s/verdict", id);
}

/* Query arguments keep the unreserved characters of RFC 3986 and escape
 * every other byte. */
static size_t encode(const char *s, char *out)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t n = 0;
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if ((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') ||
            *p == '-' || *p == '_' || *p == '.' || *p == '~') {
            if (out)
                out[n] = (char)*p;
            n++;
        } else {
            if (out) {
                out[n] = '%';
                out[n + 1] = hex[*p >> 4];
                out[n + 2] = hex[*p & 15];
            }
            n += 3;
        }
    }
    return n;
}

char *route_list_url(enum route_kind kind, size_t n, const char *const keys[],
                     const char *const values[])
{
    const char *path = kind == ROUTE_SWEEPS ? "/v1/sweeps" : "/v1/jobs";
    size_t len = strlen(path) + 1;
    for (size_t i = 0; i < n; i++)
        len += encode(keys[i], NULL) + encode(values[i], NULL) + 2;
    char *url = malloc(len);
    if (!url)
        return NULL;
    size_t at = (size_t)sprintf(url, "%s", path);
    for (size_t i = 0; i < n; i++) {
        url[at++] = i ? '&' : '?';
        at += encode(keys[i], url + at);
        url[at++] = '=';
        at += encode(values[i], url + at);
    }
    url[at] = '\0';
    return url;
}
