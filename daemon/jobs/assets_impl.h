#ifndef SHADEBENCH_ASSETS_IMPL_H
#define SHADEBENCH_ASSETS_IMPL_H

/* The assets' insides (assets.h), shared by their files and by nothing
 * outside them: assets.c (lifetime, the worker, start-up), asset_child.c
 * (the converter as a child process), asset_records.c (files, records,
 * reads, deletes, a job's resolution), asset_upload.c (uploads and their
 * tickets), asset_dir.c (--asset-dir). Threads: as assets.h says; a
 * function named *_locked is called under a->lock. */

#include <limits.h>
#include <nettle/sha2.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "daemon/jobs/assets.h"

/* Free space an upload must leave beside itself, as the store's reserve
 * asks for jobs (store_reserve.h): an asset never takes the room a job's
 * result needs. */
#define ASSETS_HEADROOM (64ull << 20)

enum task_kind { TASK_UPLOAD, TASK_DIR };

/* One conversion to do, on the worker. */
struct task {
    enum task_kind kind;
    char name[STORE_ASSET_NAME_CAP];
    char path[PATH_MAX]; /* TASK_UPLOAD: the temporary file; TASK_DIR: the file in the dir */
    char sha256[65];     /* TASK_UPLOAD: known; TASK_DIR: hashed on the worker */
    char ext[8];
    uint64_t size;
    uint64_t ticket; /* 0: nobody waits (TASK_DIR) */
    struct task *next;
};

struct ticket {
    uint64_t serial;
    bool done, dropped;
    struct assets_answer answer;
    struct ticket *next;
};

enum dir_state { DIR_PENDING, DIR_READY, DIR_FAILED };
struct dir_entry {
    char name[STORE_ASSET_NAME_CAP];
    enum dir_state state;
    char error[512];
};

struct asset_upload {
    struct assets *a;
    char name[STORE_ASSET_NAME_CAP];
    char tmp[PATH_MAX];
    int fd;
    struct sha256_ctx sha;
    uint64_t bytes;
    unsigned char magic[4];
    bool too_large, disk_full;
    int io_errno;
};

/* A hash pinned under a name (asset_pins.c): count holders. */
struct asset_pin {
    char name[STORE_ASSET_NAME_CAP];
    char sha256[65];
    unsigned count;
};

struct assets {
    struct assets_config cfg;
    char state_dir[PATH_MAX], asset_dir[PATH_MAX], asset_dir_real[PATH_MAX];
    char converter[PATH_MAX], dir[PATH_MAX]; /* dir: STATE_DIR/assets */
    struct store *store;
    struct queue *queue;
    /* Guards everything below. Record changes (an upload's row, a delete)
     * hold it across their store write so that a delete and a replace of
     * one name, or the files of one hash, never interleave; never held
     * while converting. */
    pthread_mutex_t lock;
    pthread_cond_t work;
    struct task *tasks, **tasks_tail;
    struct ticket *tickets;
    uint64_t serial;
    unsigned uploads; /* streaming or waiting to convert: at most ASSETS_MAX_UPLOADS */
    char busy_sha[65]; /* the hash the worker is converting: its files stay */
    pid_t child;       /* the converter running, or 0 */
    bool stopping;
    struct dir_entry *dir_entries;
    size_t ndir;
    struct asset_pin *pins; /* submissions' and sweeps' pins */
    size_t npins, pins_cap;
    void (*listener)(void *ctx);
    void *listener_ctx;
    pthread_t workers[ASSETS_WORKERS];
    int nworkers;
};

/* assets.c */
void asset_refuse(struct assets_error *e, enum assets_cause cause, const char *field,
                  const char *fmt, ...) __attribute__((format(printf, 4, 5)));
void sha256_hex(const uint8_t digest[SHA256_DIGEST_SIZE], char out[65]);
void assets_notify(struct assets *a);

/* asset_child.c */
/* The cache and description of sha, converting in when they are not there
 * yet (an identical file converted before costs nothing). On success
 * *description is a new reference; else e says why. */
bool asset_ensure_cache(struct assets *a, const char *sha, const char *in, json_t **description,
                        struct assets_error *e);

/* asset_records.c */
void asset_path(const struct assets *a, const char *sha, const char *ext, char *out,
                size_t cap);
bool file_exists(const char *path);
/* Under a->lock: the files of a hash no name points at, no conversion is
 * working on, and no pin or queued or running job holds. */
void asset_release_files_locked(struct assets *a, const char *sha);
/* Under a->lock: a name of --asset-dir that is not ready answers here. */
bool asset_dir_not_ready_locked(struct assets *a, const char *name, const char *field,
                                struct assets_error *e);

/* asset_pins.c */
/* Under a->lock: the pin of that name and hash (either may be NULL: any). */
struct asset_pin *asset_pin_find_locked(struct assets *a, const char *name, const char *sha);
/* Under a->lock: the record of name now points at sha. The files of the
 * hash it pointed at before go when nothing else needs them. *replaced:
 * the name had a record. */
bool asset_put_record_locked(struct assets *a, const struct task *t, const json_t *description,
                             bool *replaced, struct assets_error *e);

/* asset_upload.c */
/* Under a->lock: may name be written over HTTP? */
bool asset_writable_locked(struct assets *a, const char *name, struct assets_error *e);
void asset_upload_run(struct assets *a, struct task *t);

/* asset_dir.c */
struct dir_entry *asset_dir_find(struct assets *a, const char *name);
void asset_dir_run(struct assets *a, struct task *t);
/* The folder's .glb and .gltf files: each a task for the worker. A link
 * is followed only when it stays inside the folder. */
bool scan_asset_dir(struct assets *a, char *err, size_t errlen);
/* Rows of --asset-dir files that are no longer there (or no folder now). */
void drop_gone_dir_rows(struct assets *a);

#endif
