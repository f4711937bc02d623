#ifndef SHADEBENCH_JOB_FILES_H
#define SHADEBENCH_JOB_FILES_H

/* The files a finished job leaves in its directory and the names the API
 * serves its images under: one table, read by the harness and the metrics
 * stage (which write them), the API (which serves and links them: URLs are
 * built in daemon/api/routes.c from this table) and the client (which
 * downloads them). GL-free; any thread. */

#include <stdbool.h>
#include <stddef.h>

#define JOB_FILE_SPEC "spec.json"     /* the job as accepted (the store's) */
#define JOB_FILE_RESULT "result.json" /* the harness's */
#define JOB_FILE_TIMINGS "timings.csv"

/* The per-capture images of a job, one PNG per captured frame each. */
enum job_image {
    JOB_IMAGE_FRAME,     /* the technique's frame */
    JOB_IMAGE_REFERENCE, /* the reference technique's frame */
    JOB_IMAGE_SSIM,      /* SSIM map (white = 1) */
    JOB_IMAGE_FLIP,      /* FLIP error map */
    JOB_IMAGE_HEATMAP,   /* light evaluations per pixel */
    JOB_IMAGE_COUNT
};

struct job_image_kind {
    const char *prefix;   /* of the file name: "frame" in frame-000100.png */
    const char *folder;   /* of the URL: "frames" in /v1/jobs/ID/frames/100.png */
    /* The keys of a capture entry (result.captures[i], or
     * result.heatmap.captures[i] for heat maps) holding its file name and,
     * as served, its URL. */
    const char *file_key, *url_key;
};

const struct job_image_kind *job_image_kind(enum job_image image);

/* "frame-000100.png": what fits in JOB_IMAGE_NAME_MAX, NUL included. */
#define JOB_IMAGE_NAME_MAX 40
void job_image_name(enum job_image image, int frame, char out[JOB_IMAGE_NAME_MAX]);
/* dir/name; false when it does not fit in cap. */
bool job_image_path(const char *dir, enum job_image image, int frame, char *out, size_t cap);
/* dir/file (JOB_FILE_RESULT, ...); false when it does not fit in cap. */
bool job_file_path(const char *dir, const char *file, char *out, size_t cap);

#endif
