/* The --out folder and a job's files in it; job files prepared for
 * submission. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "client/client.h"
#include "common/fsutil.h"
#include "common/job_files.h"
#include "common/result_keys.h"

bool out_dir_claim(const char *dir, const char *marker_file, const char *id, char *err,
                   size_t cap)
{
    struct stat st;
    if (stat(dir, &st) != 0) {
        if (errno == ENOENT)
            return true;
        snprintf(err, cap, "--out %s: %s", dir, strerror(errno));
        return false;
    }
    if (!S_ISDIR(st.st_mode)) {
        snprintf(err, cap, "--out %s is not a folder", dir);
        return false;
    }
    DIR *d = opendir(dir);
    if (!d) {
        snprintf(err, cap, "--out %s: %s", dir, strerror(errno));
        return false;
    }
    bool empty = true;
    struct dirent *e;
    while (empty && (e = readdir(d)))
        empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
    closedir(d);
    if (empty)
        return true;
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s", dir, marker_file);
    json_t *marker = json_load_file(path, 0, NULL);
    const char *held = json_string_value(json_object_get(marker, "id"));
    bool same = held && id && strcmp(held, id) == 0;
    if (!same) {
        if (held)
            snprintf(err, cap, "--out %s already holds the files of %s; give an empty or new "
                     "folder, so that files of two runs never mix", dir, held);
        else
            snprintf(err, cap, "--out %s is not empty; give an empty or new folder, so that "
                     "files of two runs never mix", dir);
    }
    json_decref(marker);
    return same;
}

json_t *fetch_job_files(struct conn *c, const json_t *job, const char *dir, bool images,
                        const json_t *extra)
{
    if (!fs_mkdir_p(dir)) {
        fprintf(stderr, "shadebench: cannot create %s\n", dir);
        return NULL;
    }
    char path[4096];
    const char *id = json_string_value(json_object_get(job, "id"));
    const char *timings_url = json_string_value(json_object_get(job, "timings_url"));
    snprintf(path, sizeof(path), "%s/job.json", dir);
    bool ok = fs_write_json_atomic(path, job);
    json_t *result = json_object_get(job, RK_RESULT);
    if (!result)
        return ok ? json_object() : NULL;
    job_file_path(dir, JOB_FILE_TIMINGS, path, sizeof(path));
    ok = timings_url && conn_download(c, timings_url, path) && ok;
    json_t *copy = json_deep_copy(result);
    size_t len;
    char *csv = fs_read_file(path, 256u << 20, &len);
    if (csv)
        json_object_set_new(copy, "samples", parse_timings(csv));
    free(csv);
    json_object_set_new(copy, "job_id", json_string(id ? id : ""));
    if (json_object_get(job, "spec"))
        json_object_set(copy, "spec", json_object_get(job, "spec"));
    if (extra)
        json_object_update(copy, (json_t *)extra);
    job_file_path(dir, JOB_FILE_RESULT, path, sizeof(path));
    ok = fs_write_json_atomic(path, copy) && ok;
    size_t i;
    json_t *capture;
    static const enum job_image kinds[] = {JOB_IMAGE_FRAME, JOB_IMAGE_REFERENCE, JOB_IMAGE_SSIM,
                                           JOB_IMAGE_FLIP};
    json_array_foreach(images ? json_object_get(result, RK_CAPTURES) : NULL, i, capture) {
        int frame = (int)json_integer_value(json_object_get(capture, "frame"));
        for (size_t k = 0; k < sizeof(kinds) / sizeof(kinds[0]); k++) {
            const char *u = json_string_value(
                json_object_get(capture, job_image_kind(kinds[k])->url_key));
            if (!u)
                continue;
            job_image_path(dir, kinds[k], frame, path, sizeof(path));
            ok = conn_download(c, u, path) && ok;
        }
    }
    if (!ok) {
        json_decref(copy);
        return NULL;
    }
    return copy;
}

json_t *load_json_file(const char *what, const char *path, char *err, size_t cap)
{
    /* Opened here, so that a missing file says so with the system's reason
     * rather than as a parse error at line -1. */
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, cap, "cannot read the %s %s: %s", what, path, strerror(errno));
        return NULL;
    }
    json_error_t jerr;
    json_t *j = json_loadf(f, JSON_REJECT_DUPLICATES, &jerr);
    fclose(f);
    if (!j)
        snprintf(err, cap, "the %s %s is not valid JSON: line %d, column %d: %s", what, path,
                 jerr.line, jerr.column, jerr.text);
    return j;
}

char *job_text_for_submit(const char *file, const struct options *o, int repeat, char *err,
                          size_t cap)
{
    json_t *job = load_json_file("job file", file, err, cap);
    if (!job)
        return NULL;
    if (!json_is_object(job)) {
        snprintf(err, cap, "%s: a job is a JSON object", file);
        json_decref(job);
        return NULL;
    }
    if (o->labels && json_object_size(o->labels)) {
        json_t *labels = json_object_get(job, "labels");
        if (labels && !json_is_object(labels)) {
            snprintf(err, cap, "%s: labels must be an object to add --label to", file);
            json_decref(job);
            return NULL;
        }
        if (!labels) {
            labels = json_object();
            json_object_set_new(job, "labels", labels);
        }
        json_object_update(labels, o->labels);
    }
    if (repeat > 0)
        json_object_set_new(job, "repeat", json_integer(repeat));
    char *text = json_dumps(job, JSON_COMPACT);
    json_decref(job);
    if (!text)
        snprintf(err, cap, "out of memory");
    return text;
}
