#ifndef SHADEBENCH_ROUTES_H
#define SHADEBENCH_ROUTES_H

/* The URL space of the HTTP API as data: which resource a path names, its
 * id and sub-resource, and the methods it takes. Pure functions of the
 * strings (no socket, no store), so that the routing is unit-tested and
 * fuzzed on its own. GL-free; any thread. */

#include <stdbool.h>
#include <stddef.h>

#include "common/job_files.h"

enum route_kind {
    ROUTE_NONE, /* no such route or resource: 404 */
    ROUTE_HEALTHZ,
    ROUTE_METRICS,
    ROUTE_INFO,
    ROUTE_JOBS,
    ROUTE_JOB,
    ROUTE_JOB_REPORT,
    ROUTE_JOB_CHART,
    ROUTE_JOB_TIMINGS,
    ROUTE_JOB_IMAGE,
    ROUTE_JOB_PDIFF, /* /v1/jobs/{id}/pdiff/{frame}.png: PerceptualDiff's failing pixels */
    ROUTE_JOB_HISTORY, /* /v1/jobs/{id}/history: its workload's jobs over time */
    ROUTE_SWEEPS,
    ROUTE_SWEEP,
    ROUTE_SWEEP_CHART,
    ROUTE_SWEEP_REPORT,
    ROUTE_SWEEP_VERDICT, /* /v1/sweeps/{id}/verdict: sweep_verdict_json */
    ROUTE_ASSETS, /* /v1/assets */
    ROUTE_ASSET,  /* /v1/assets/{name} */
    ROUTE_UI,     /* / and /ui/...: the dashboard's files, served without the token */
    ROUTE_ASSET_FIDELITY, /* /v1/assets/{name}/fidelity: a fidelity job */
    ROUTE_JOB_FIDELITY,   /* /v1/jobs/{id}/fidelity/{file}.png: its images */
    ROUTE_COUNT
};


#define ROUTE_ASSET_NAME_MAX 128

struct route {
    enum route_kind kind;
    char id[24];       /* jobs and sweeps: digits and dashes, 1 to 23 of them */
    char chart[32];    /* charts: the name without its extension; ROUTE_JOB_FIDELITY:
                        * the file's name, [a-z0-9_-] and ".png" */
    bool chart_png;    /* charts: .png (else .svg) */
    enum job_image image; /* images: which kind (common/job_files.h) */
    int frame;         /* images and PerceptualDiff masks: 1 to 999999999 */
    /* ROUTE_ASSET: the name as given (up to ROUTE_ASSET_NAME_MAX bytes; a
     * longer one is cut and flagged). The handler checks it
     * (scene_asset_name_valid) so that a bad one is a 400 naming it. */
    char asset[ROUTE_ASSET_NAME_MAX + 1];
    bool asset_too_long;
    /* ROUTE_UI: the file's URL ("/" and "/ui/" name "/ui/index.html"). */
    char ui[64];
    /* ROUTE_NONE: what the 404 names. */
    const char *field, *message;
};

/* Parses an already URL-decoded path (no query). Always fills out; returns
 * false for ROUTE_NONE. */
bool route_parse(const char *url, struct route *out);

/* Query arguments a request may carry: the lists take at most
 * STORE_MAX_TERMS (32) filters with limit, cursor and since; anything far
 * beyond is not a question the API can answer. */
#define ROUTE_MAX_QUERY_ARGS 64

/* Checks the request target as the client sent it, before libmicrohttpd
 * splits off the query and decodes it: an encoded NUL (%00) anywhere would
 * cut the decoded path or argument short (".../1.png%00.txt" served the
 * PNG), and libmicrohttpd keeps every argument in the connection's small
 * memory pool (500 of them left the client without an answer). False, with
 * the field ("url" or "query") and the rule of a 400, when it must be
 * refused; *args gets the number of query arguments either way. */
bool route_check_target(const char *target, size_t *args, const char **field,
                        const char **message);

/* Does kind take method (GET and HEAD alike)? If not, *allow is the Allow
 * header and *rule the message of the 405. */
bool route_method_ok(enum route_kind kind, const char *method, const char **allow,
                     const char **rule);

/* A fixed label per kind, for the request counters of /metrics. */
const char *route_label(enum route_kind kind);

/* The URLs the API hands out, built here and nowhere else (the jobs and the
 * harness record ids and file names only). Each writes a path of at most
 * ROUTE_URL_MAX bytes, NUL included. */
#define ROUTE_URL_MAX 96
void route_job_url(const char *id, char out[ROUTE_URL_MAX]);
void route_sweep_url(const char *id, char out[ROUTE_URL_MAX]);
/* A finished job's per-frame figures (timings.csv). */
void route_timings_url(const char *id, char out[ROUTE_URL_MAX]);
void route_asset_url(const char *name, char out[ROUTE_URL_MAX + ROUTE_ASSET_NAME_MAX]);
void route_image_url(const char *id, enum job_image image, int frame, char out[ROUTE_URL_MAX]);
/* A capture's PerceptualDiff mask, made on request. */
void route_pdiff_url(const char *id, int frame, char out[ROUTE_URL_MAX]);
void route_verdict_url(const char *id, char out[ROUTE_URL_MAX]);
void route_history_url(const char *id, char out[ROUTE_URL_MAX]);

/* A page of a list (kind ROUTE_JOBS or ROUTE_SWEEPS) with its n query
 * arguments, each key and value percent-encoded. malloc'ed (the query can
 * be long), NULL when out of memory. */
char *route_list_url(enum route_kind kind, size_t n, const char *const keys[],
                     const char *const values[]);

#endif
