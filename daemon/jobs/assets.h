#ifndef SHADEBENCH_ASSETS_H
#define SHADEBENCH_ASSETS_H

/* The assets (issue 21): glTF 2.0 files uploaded over HTTP (PUT
 * /v1/assets/NAME) or provided read-only by the operator (--asset-dir),
 * each converted once into a cache file the render thread reads
 * (asset_store.h has the paths). The glTF file is never parsed in the
 * daemon: the converter, shadebench-asset, runs as a child process under
 * an address-space and CPU-time limit, at lower priority, with a
 * wall-clock time-out, one conversion at a time (ASSETS_WORKERS), on a
 * thread of this module: an upload never holds an HTTP thread while it
 * converts, and never competes with the render thread for more than one
 * core. The records (name -> hash, size, the converter's description) are
 * rows of the store (table assets), so they survive restarts.
 *
 * Threads: the functions are called from libmicrohttpd's threads (uploads,
 * lists, descriptions, deletes, a job's resolution), the sweep thread
 * (queue_submit's resolver) and main (create, destroy). The worker thread
 * is this module's own. GL-free. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/store/asset_store.h"
#include "daemon/jobs/queue.h"
#include "daemon/store/store.h"
#include "daemon/scene/scene_spec.h"

/* Conversions at once, and uploads that may stream or wait to convert at
 * once: more are answered 429. */
#define ASSETS_WORKERS 1
#define ASSETS_MAX_UPLOADS 4
#define ASSETS_MAX_BYTES_DEFAULT (256ull << 20)
/* A converter's answer on stdout beyond this is not JSON we can use. */
#define ASSETS_MAX_STDOUT (1u << 20)

struct assets_config {
    const char *state_dir;
    const char *asset_dir; /* NULL or "": none */
    const char *converter; /* NULL or "": shadebench-asset beside /proc/self/exe */
    uint64_t max_asset_bytes; /* an upload's body (--max-asset-bytes) */
    struct asset_limits limits;
    struct asset_run_limits run;
};

/* Why a request is refused, by cause; the API layer answers each with its
 * HTTP status (daemon/api/asset_handlers.c). */
enum assets_cause {
    ASSETS_INTERNAL,      /* the store cannot be read or written, out of memory */
    ASSETS_INVALID,       /* a name, a body or a job's scene.asset breaks a rule */
    ASSETS_READ_ONLY,     /* an --asset-dir asset, written over HTTP */
    ASSETS_NOT_FOUND,     /* no asset of that name */
    ASSETS_CONFLICT,      /* held by a queued job, still converting, or not the pinned hash */
    ASSETS_TOO_LARGE,     /* over --max-asset-bytes */
    ASSETS_UNCONVERTIBLE, /* the converter refused or failed on the file */
    ASSETS_BUSY,          /* ASSETS_MAX_UPLOADS already stream or convert */
    ASSETS_STOPPING,      /* the daemon is stopping */
    ASSETS_NO_SPACE,      /* the state directory's disk is full */
};

/* A refusal: its cause, the field and the rule. */
struct assets_error {
    enum assets_cause cause;
    char field[64];
    char message[512];
};

struct assets;

/* Scans --asset-dir (names only: the files are hashed and converted on the
 * worker, so a large folder never delays the start), drops the rows of
 * files that left it, removes the temporaries an earlier process left
 * (uploads, conversions); assets_release_unused removes the files no name
 * points at once the jobs and sweeps hold what they need. NULL with err. */
struct assets *assets_create(const struct assets_config *cfg, struct store *store,
                             struct queue *queue, char *err, size_t errlen);
/* Kills a running conversion, ends the worker, answers waiting uploads
 * 503. Accepts NULL. */
void assets_destroy(struct assets *a);
/* fn(ctx) is called (any thread, no lock held) when an upload's answer is
 * ready: the HTTP layer resumes its waits. */
void assets_set_listener(struct assets *a, void (*fn)(void *ctx), void *ctx);

uint64_t assets_max_bytes(const struct assets *a);
/* How long an upload's answer may take once its body is in. */
double assets_answer_wait_s(const struct assets *a);
/* /v1/info's "assets": the converter's limits, the body limit, the caps. */
json_t *assets_info_json(const struct assets *a);

/* PUT /v1/assets/NAME. begin: the headers are in (content_length 0:
 * unknown, chunked); NULL with e when refused. write: each piece of the
 * body, hashed and written to a temporary file under STATE_DIR/assets; past
 * the limit, or on a full disk, the rest is read and dropped and finish
 * refuses it (ASSETS_TOO_LARGE, ASSETS_NO_SPACE). finish consumes u: queues
 * the conversion and returns its ticket (> 0), whose answer
 * assets_ticket_take gives once assets_ticket_done; 0 with e when refused.
 * abort: the client went away. */
struct asset_upload;
struct asset_upload *assets_upload_begin(struct assets *a, const char *name,
                                         uint64_t content_length, struct assets_error *e);
void assets_upload_write(struct asset_upload *u, const void *data, size_t len);
uint64_t assets_upload_finish(struct asset_upload *u, struct assets_error *e);
void assets_upload_abort(struct asset_upload *u);
bool assets_ticket_done(struct assets *a, uint64_t ticket);
/* A conversion's answer: the stored record (name, sha256, size, format,
 * description), a new reference, and whether it replaced one of that name;
 * or, with record NULL, the refusal. */
struct assets_answer {
    json_t *record;
    bool replaced;
    struct assets_error refusal;
};
/* The answer; the ticket is released. False when there is no such ticket
 * or it is not done. */
bool assets_ticket_take(struct assets *a, uint64_t ticket, struct assets_answer *out);
/* The client went away: the conversion goes on, its answer is dropped. */
void assets_ticket_drop(struct assets *a, uint64_t ticket);

/* GET /v1/assets/NAME: the record with the converter's description; DELETE
 * /v1/assets/NAME: what was deleted. A new reference, or NULL with e. */
json_t *assets_describe(struct assets *a, const char *name, struct assets_error *e);
json_t *assets_delete(struct assets *a, const char *name, struct assets_error *e);
/* GET /v1/assets?limit=&cursor=: a page of records (their descriptions as
 * counts), the cursor of the next page ("" on the last), and the
 * --asset-dir files still converting or that failed. */
struct assets_page {
    json_t *items; /* a new reference */
    char next[STORE_ASSET_NAME_CAP];
    size_t converting, failed;
};
bool assets_list(struct assets *a, const char *cursor, int limit, struct assets_page *page,
                 struct assets_error *e);

/* A job's scene.asset: fills scene->asset_sha256 from the store, or
 * refuses (ASSETS_INVALID: an unknown name; ASSETS_CONFLICT: the pinned hash
 * differs, or it is still converting). Pins nothing: a probe. */
bool assets_resolve(struct assets *a, struct scene_spec *scene, struct assets_error *e);

/* Pins (asset_pins.c): every asset a job names (scene.asset, and
 * look.ibl.environment's and reference_look's {"asset": NAME}, which must be
 * an environment map) resolved to its hash and the hash pinned in one step,
 * under the assets' lock, so that no DELETE or replacing PUT
 * comes between: while pinned, the name cannot be deleted (ASSETS_CONFLICT)
 * and the hash's files stay whatever replaces the name. Fills
 * scene->asset_sha256 (unless given) and asset_bytes (what a job on it
 * holds in memory, for its cost). A given asset_sha256 other than the
 * name's hash is accepted while a pin of that name and hash is held (a
 * sweep's, whose points all run on the hash it was accepted with), or, with
 * restore (a sweep resumed at start-up), while the hash's files are there;
 * else ASSETS_CONFLICT. Each pin is let go with assets_unpin. */
bool assets_pin(struct assets *a, struct job_spec *spec, bool restore, struct assets_error *e);
void assets_unpin(struct assets *a, const struct job_spec *spec);
/* A job on the asset has finished: its hash's files go if nothing else
 * holds them (the name was deleted or replaced meanwhile). */
void assets_job_ended(struct assets *a, const struct job_spec *spec);
/* The queue's hooks (queue.h) for these, ctx a. */
void assets_queue_hooks(struct assets *a, struct queue_asset_hooks *out);
/* Start-up, once the queue's jobs and the sweeps are loaded (and have
 * pinned what they hold): the files of hashes that nothing holds and no
 * name points at (a crash between a delete's row and its files). */
void assets_release_unused(struct assets *a);

#endif
