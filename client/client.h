#ifndef SHADEBENCH_CLIENT_H
#define SHADEBENCH_CLIENT_H

/* The pieces of the shadebench CI client that its commands share: the
 * options, a connection to a daemon (libcurl, bearer token), following a
 * job or a sweep with progress, and the --out folder with a job's files.
 * Single-threaded: one process, one command. Exit statuses: 0 pass (an
 * undecided timing check passes with a warning), 1 a regression, a quality
 * failure or a failed job, 2 a usage error, a server that cannot be reached
 * or refuses, or a baseline that does not match, 3 a timing check that could
 * not decide, when asked to fail on that (--fail-inconclusive,
 * $SHADEBENCH_FAIL_INCONCLUSIVE=1) and nothing failed outright. */

#include <curl/curl.h>
#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "client/fleet.h"
#include "common/clock.h" /* clock_mono_s: every interval the client measures */

enum { EXIT_PASS = 0, EXIT_FAIL = 1, EXIT_ERROR = 2, EXIT_INCONCLUSIVE = 3 };

struct options {
    const char *out_dir;
    const char *junit;
    const char *baseline;
    const char *series;       /* NULL: the device's meaningful one */
    double max_slowdown;      /* the minimum effect that counts as a regression */
    double min_ssim, max_flip; /* NAN: no gate */
    double timeout_s;         /* 0: wait as long as it takes */
    double confidence;        /* of the intervals, 0.95 */
    double noise_tolerance;   /* relative change of the CPU left, 0.10; INFINITY: off */
    int runs;                 /* 0: the command's default */
    int max_reruns;
    bool wait, quiet, allow_mismatch, fail_inconclusive;
    json_t *labels;           /* --label KEY=VALUE, added to submitted jobs */
    json_t *filters;          /* history: --filter KEY=VALUE, as query arguments */
    json_t *channels;         /* fidelity: --channel NAME (repeatable) */
    const char *since;
    const char *figure;       /* history: frame_ms, gpu_ms, cpu_ms or worst_ssim */
    struct fleet_options fleet; /* sweep --slurm */
};

struct conn {
    char server[1024];
    const char *token;
    const char *token_source; /* where the token came from, for a refusal's message */
    CURL *curl;
};

struct buffer {
    char *data;
    size_t len;
};

/* The daemon at server (trailing slashes dropped). False when libcurl
 * cannot start. */
bool conn_init(struct conn *c, const char *server, const char *token);
void conn_finish(struct conn *c);

/* One request. Returns the HTTP status, or -1 when the server was not
 * reached (message printed). out gets the body (always NUL-terminated; the
 * caller frees out->data). */
long conn_request(struct conn *c, const char *method, const char *path, const char *body,
                  struct buffer *out);

/* A JSON request; on an HTTP error prints the daemon's error (field and
 * rule) and returns NULL. */
json_t *conn_json(struct conn *c, const char *method, const char *path, const char *body,
                  long *status);

/* A list that comes in pages (GET /v1/jobs, /v1/sweeps): path's first page,
 * then each "next" link until the last; {key: [every item]}. NULL (the
 * error printed) when a page cannot be had. */
json_t *conn_list(struct conn *c, const char *path, const char *key);

bool conn_download(struct conn *c, const char *path, const char *file);

/* Follows a job until it ends (a bar on a terminal, plain lines otherwise,
 * prefixed with what). Returns the final job, or NULL on a server error or
 * after timeout_s (> 0). */
json_t *conn_follow_job(struct conn *c, const char *id, const char *what, bool quiet,
                        double timeout_s);

/* The same for a sweep, by points. */
json_t *conn_follow_sweep(struct conn *c, const char *id, bool quiet, double timeout_s);

/* Per-frame samples of each series from timings.csv text:
 * {"frame_ms": [...], "gpu_ms": [...], ...}. New reference. */
json_t *parse_timings(const char *csv);

/* --out DIR must not mix files of two jobs (or sweeps): it may be absent,
 * empty, or hold job.json (sweep.json) of this very id. False with a
 * message in err otherwise. id NULL: a job not submitted yet. */
bool out_dir_claim(const char *dir, const char *marker_file, const char *id, char *err,
                   size_t cap);

/* Downloads a finished job: job.json, timings.csv, result.json (the result
 * with its per-frame samples, its job id and spec, usable alone as a
 * baseline) and, with images, every capture, reference and difference map.
 * The returned result (new reference, NULL on failure) is what was written
 * to result.json; extra (may be NULL) is merged into it first. */
json_t *fetch_job_files(struct conn *c, const json_t *job, const char *dir, bool images,
                        const json_t *extra);


/* A JSON file the user named (what: "job file", "sweep file"). NULL with
 * err saying which file and why: it cannot be read (the system's reason), or
 * where its JSON is broken. */
json_t *load_json_file(const char *what, const char *path, char *err, size_t cap);

/* A job file with --label added and repeat overridden (repeat > 0).
 * Returns malloc'ed JSON text, or NULL with a message in err. */
char *job_text_for_submit(const char *file, const struct options *o, int repeat, char *err,
                          size_t cap);

/* --label KEY=VALUE on a sweep: into its base job's labels, so that every
 * point job carries them (a daemon's sweep and a fleet's alike). */
void sweep_add_labels(json_t *body, const json_t *labels);

/* Commands: each returns an exit status. */
int cmd_submit(struct conn *c, const struct options *o, const char *file);
int cmd_fetch(struct conn *c, const struct options *o, const char *id);
int cmd_status(struct conn *c, const char *id);
int cmd_list(struct conn *c);
int cmd_print(struct conn *c, const char *method, const char *path);
int cmd_info(struct conn *c);
int cmd_ab(struct conn *a, struct conn *b, const struct options *o, const char *file_a,
           const char *file_b);
int cmd_sweep(struct conn *c, const struct options *o, const char *file);
int cmd_history(struct conn *c, const struct options *o);
int cmd_fidelity(struct conn *c, const struct options *o, const char *asset,
                 const char *request_file);

#endif
