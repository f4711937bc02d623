#ifndef SHADEBENCH_FIDELITY_H
#define SHADEBENCH_FIDELITY_H

/* The fidelity worker: the thread that finishes a fidelity job (a job
 * with "fidelity", fidelity_spec.h) once the render thread has drawn
 * shadebench's channels (fidelity_render.h). It runs the Khronos reference,
 * shadebench-reference, as a child process in a process group of its own,
 * at nice 10, under a wall-clock time-out and a memory limit (the resident
 * memory of the whole group, Chromium's processes included, polled; past
 * either the group is killed), a cancelled job kills it too; it caches the
 * reference's images by what they depend on (STATE/reference-cache/KEY:
 * the viewer's version and IBL sampler, the asset's and the environment's
 * hashes, the size, camera, lights, exposure, tone curve and environment),
 * so that a sweep renders each once, keeping the FIDELITY_CACHE_MAX_KEYS
 * most recently used; then it compares each channel with
 * quality/ (SSIM, FLIP, PerceptualDiff, PSNR; the SSIM and FLIP maps as
 * difference images), writes result.fidelity and finishes the job. The
 * render thread waits for it to be idle before it times the next job, so
 * Chromium never shares the CPU with a timed run.
 *
 * Threads: create, destroy and info on main and the HTTP threads; submit
 * and wait_idle on the render thread; the worker is its own. GL-free. */

#include <jansson.h>
#include <stdbool.h>
#include <stdint.h>

#include "daemon/jobs/queue.h"

#define FIDELITY_DIR "fidelity" /* in a job's directory */
#define FIDELITY_CACHE_DIR "reference-cache" /* in the state directory */
/* Keys the cache keeps: past it the least recently used go (each key is a
 * folder of one PNG a channel and the run's cost). */
#define FIDELITY_CACHE_MAX_KEYS 512

struct fidelity_config {
    const char *state_dir;
    /* The operator's paths (--chromium, --reference-viewer, ...); NULL or
     * "": the usual places (reference_files.h). */
    const char *chromium, *viewer_dir, *page_dir, *program, *pkgdatadir;
    double timeout_s;      /* the reference child's wall clock (0: FIDELITY_TIMEOUT_S) */
    uint64_t memory_bytes; /* its process group's resident memory (0: FIDELITY_MEMORY) */
};
#define FIDELITY_TIMEOUT_S 300.0
#define FIDELITY_MEMORY (4ull << 30)

struct fidelity;

struct fidelity *fidelity_create(const struct fidelity_config *cfg, struct queue *q);
/* Kills a running reference, fails what is left. Accepts NULL. */
void fidelity_destroy(struct fidelity *f);

/* Is the reference there (Chromium, the viewer, the page, the program)?
 * why: what is missing and where it looked. Any thread. */
bool fidelity_available(const struct fidelity *f, char *why, size_t whylen);
/* /v1/info's "reference". New reference. */
json_t *fidelity_info_json(const struct fidelity *f);

/* Render thread: takes ownership of result and view (fidelity_render). */
void fidelity_submit(struct fidelity *f, struct job *job, json_t *result, json_t *view);
/* Render thread: blocks until every job handed over has finished. */
void fidelity_wait_idle(struct fidelity *f);

/* The child's request (GL-free, unit-tested): the page's request from the
 * job's spec and the render thread's view, paths filled by the caller.
 * NULL with err when the look cannot be stated to the viewer. */
json_t *fidelity_page_request(const struct job_spec *spec, const json_t *view,
                              const char *const *channels, int nchannels, char *err,
                              size_t errlen);
/* The cache key of a page request: SHA-256 (hex) of the viewer's version,
 * the sampler, the asset's and environment's hashes and the request. */
void fidelity_cache_key(const json_t *page_request, const struct job_spec *spec,
                        char out[65]);
/* The viewer writes gamma 2.2 (pow(c, 1 / 2.2)) where shadebench writes
 * sRGB: this maps an 8-bit viewer value to the sRGB value of the same
 * linear colour (tonemap srgb, aces, pbr_neutral), or to the linear value
 * (tonemap none, which writes no encoding). */
uint8_t fidelity_reencode(uint8_t v, bool to_linear);

#endif
