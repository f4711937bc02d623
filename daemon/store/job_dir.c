#define _POSIX_C_SOURCE 200809L
#include "daemon/store/job_dir.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/job_files.h"
#include "common/clock.h"
#include "common/fsutil.h"
#include "common/log.h"
#include "common/result_keys.h"
#include "daemon/spec/job_figures.h"

json_t *job_dir_labels(const struct job_spec *spec)
{
    json_t *o = json_object();
    for (int k = 0; k < spec->nlabels; k++)
        json_object_set_new(o, spec->labels[k].key, json_string(spec->labels[k].value));
    return o;
}

/* spec.json: the job as accepted, written once. With result.json it is
 * enough to rebuild the job's row (store_import). */
bool job_dir_write_spec(const char *dir, const char *id, double created,
                          const struct job_spec *spec, char *err, size_t errlen)
{
    char path[PATH_MAX + 16];
    job_file_path(dir, JOB_FILE_SPEC, path, sizeof(path));
    json_t *o = json_pack("{s:s, s:f, s:o}", "id", id, "created_unix", created, "spec",
                          job_spec_to_json(spec));
    bool ok = o && fs_write_json_atomic(path, o);
    if (!ok)
        snprintf(err, errlen, "cannot write %s: %s", path, o ? strerror(errno) : "out of memory");
    json_decref(o);
    return ok;
}

json_t *job_dir_read_spec(const struct store_row *row)
{
    char path[PATH_MAX + 16], why[600] = "";
    job_file_path(row->dir, JOB_FILE_SPEC, path, sizeof(path));
    json_t *rec = record_read(path, why, sizeof(why));
    json_t *spec = json_incref(json_object_get(rec, "spec"));
    if (!spec)
        LOG(LOG_WARN, "job %s: %s: %s", row->id, path, rec ? "no spec in it" : why);
    json_decref(rec);
    return spec;
}

/* A result.json is complete once nothing more would have been added to it:
 * the metrics stage adds "quality" for jobs with a reference, the repeats
 * add "repeat". An earlier version means the job never finished. */
static bool result_complete(const struct job_spec *spec, const json_t *result)
{
    if (spec->reference[0] && !json_object_get(result, RK_QUALITY))
        return false;
    if (job_spec_runs(spec) > 1 && !json_object_get(result, "repeat"))
        return false;
    return true;
}

static double file_mtime(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_mtim.tv_sec + st.st_mtim.tv_nsec / 1e9 : 0;
}

void job_dir_fail_result(struct store *store, struct store_row *row, const char *path,
                           const char *why)
{
    char quarantined[PATH_MAX] = "", reason[800];
    snprintf(reason, sizeof(reason), "result.json of a finished job: %s", why);
    if (access(path, F_OK) == 0)
        record_quarantine(store_record_kind(store, STORE_JOBS), row->id, path, reason,
                          quarantined, sizeof(quarantined));
    else
        LOG(LOG_WARN, "job %s: %s", row->id, reason);
    row->status = JOB_FAILED;
    snprintf(row->error, sizeof(row->error), "result.json is missing or damaged: %.600s%s%s", why,
             quarantined[0] ? "; moved to " : "", quarantined);
    json_decref(row->figures);
    row->figures = NULL;
    char err[PATH_MAX + 300];
    if (!store_put(store, row, 0, NULL, err, sizeof(err)))
        LOG(LOG_ERROR, "job %s: %s", row->id, err);
}

void job_dir_interrupted(struct store_row *row, const char *result_why)
{
    row->status = JOB_INTERRUPTED;
    row->finished = clock_unix_s();
    snprintf(row->error, sizeof(row->error),
             "interrupted: the daemon stopped (killed or crashed) while this job ran; its files "
             "may be incomplete (result.json %.700s), submit it again to measure it", result_why);
}

/* The row of a job known from its parsed spec. */
static void row_from_spec(struct store_row *row, const struct job_spec *spec, double created)
{
    snprintf(row->technique, sizeof(row->technique), "%s", spec->technique);
    row->created = created;
    row->total = spec->frames * job_spec_runs(spec);
    json_decref(row->labels);
    json_decref(row->spec);
    row->labels = job_dir_labels(spec);
    row->spec = job_spec_to_json(spec);
}

bool job_dir_done_from_result(struct store *store, struct store_row *row,
                              const struct job_spec *spec, const char *dir, char *why,
                              size_t whylen)
{
    char path[PATH_MAX + 16];
    job_file_path(dir, JOB_FILE_RESULT, path, sizeof(path));
    bool present = access(path, F_OK) == 0;
    char read_why[600] = "";
    json_t *result = present ? record_read(path, read_why, sizeof(read_why)) : NULL;
    if (!present) {
        snprintf(why, whylen, "missing");
    } else if (!result) {
        char reason[800], moved[PATH_MAX] = "";
        snprintf(reason, sizeof(reason), "result.json of job %s: %s", row->id, read_why);
        record_quarantine(store_record_kind(store, STORE_JOBS), row->id, path, reason, moved,
                          sizeof(moved));
        snprintf(why, whylen, "damaged (%.300s)%s%.400s", read_why,
                 moved[0] ? " and moved to " : "", moved);
    }
    bool complete = result && result_complete(spec, result);
    if (result && !complete)
        snprintf(why, whylen, "incomplete");
    if (complete) {
        row->status = JOB_DONE;
        double started = json_number_value(json_object_get(result, RK_STARTED_UNIX));
        if (row->started <= 0 && started > 0)
            row->started = started;
        row->finished = file_mtime(path);
        row->done = row->total;
        row->error[0] = '\0';
        json_decref(row->figures);
        row->figures = job_figures(result);
    }
    json_decref(result);
    return complete;
}

/* Rebuilds a job's row from spec.json (written once at submission) and
 * result.json. false, with why, when they do not allow it. lost says what
 * became of its state, for the message of an interrupted one. */
static bool rebuild_row(struct store *store, const struct technique_catalog *techniques,
                        const char *id, const char *dir, const char *lost, struct store_row *row,
                        char *why, size_t whylen)
{
    char path[PATH_MAX + 16], swhy[700] = "";
    job_file_path(dir, JOB_FILE_SPEC, path, sizeof(path));
    json_t *rec = record_read(path, swhy, sizeof(swhy));
    struct job_spec spec;
    struct job_error jerr;
    const char *rid = json_string_value(json_object_get(rec, "id"));
    if (rec && (!rid || strcmp(rid, id) != 0))
        snprintf(swhy, sizeof(swhy), "its id does not match its directory");
    else if (rec && !job_spec_parse(json_object_get(rec, "spec"), techniques, &spec, &jerr))
        snprintf(swhy, sizeof(swhy), "not a job this daemon can run (%s: %s)", jerr.field,
                 jerr.message);
    if (swhy[0]) {
        snprintf(why, whylen, "spec.json: %s", swhy);
        json_decref(rec);
        return false;
    }
    row_from_spec(row, &spec, json_number_value(json_object_get(rec, "created_unix")));
    json_decref(rec);
    char rwhy[800] = "";
    snprintf(row->id, sizeof(row->id), "%s", id);
    if (job_dir_done_from_result(store, row, &spec, dir, rwhy, sizeof(rwhy))) {
        snprintf(why, whylen, "rebuilt as done from spec.json and result.json");
        return true;
    }
    /* Its state is unknown: it may have been queued, running or failed.
     * Interrupted says so, and nothing is run twice behind anyone's back. */
    row->status = JOB_INTERRUPTED;
    row->finished = clock_unix_s();
    snprintf(row->error, sizeof(row->error),
             "interrupted: %s and its result.json is %.700s; submit it again to measure it",
             lost, rwhy);
    snprintf(why, whylen, "rebuilt as interrupted from spec.json (result.json %s)", rwhy);
    return true;
}

/* A job.json of an earlier version, read whole and valid: its row. */
static void row_from_legacy(struct store *store, const char *id, const char *dir, const json_t *o,
                            enum job_status status, const struct job_spec *spec,
                            struct store_row *row)
{
    json_t *times = json_object_get(o, "times_unix");
    row_from_spec(row, spec, json_number_value(json_array_get(times, 0)));
    row->status = status;
    row->started = json_number_value(json_array_get(times, 1));
    row->finished = json_number_value(json_array_get(times, 2));
    row->done = (int)json_integer_value(json_object_get(json_object_get(o, "progress"),
                                                        "frames_done"));
    const char *error = json_string_value(json_object_get(o, "error"));
    snprintf(row->error, sizeof(row->error), "%s", error ? error : "");
    char why[800] = "", path[PATH_MAX + 16];
    job_file_path(dir, JOB_FILE_SPEC, path, sizeof(path));
    /* Earlier versions may not have written it: the directory must be
     * enough to rebuild the row from now on. */
    if (access(path, F_OK) != 0 && !job_dir_write_spec(dir, id, row->created, spec, why, sizeof(why)))
        LOG(LOG_WARN, "job %s: %s", id, why);
    if (status == JOB_RUNNING) {
        /* A complete result.json is the last thing a job writes before it
         * is done: the daemon died (or the disk was full) between that and
         * writing job.json. Anything less was cut short. */
        snprintf(row->id, sizeof(row->id), "%s", id);
        if (job_dir_done_from_result(store, row, spec, dir, why, sizeof(why))) {
            LOG(LOG_WARN, "job %s: job.json says running, but its result.json is complete: done",
                id);
        } else {
            job_dir_interrupted(row, why);
        }
    } else if (status == JOB_DONE) {
        job_file_path(dir, JOB_FILE_RESULT, path, sizeof(path));
        json_t *result = record_read(path, why, sizeof(why));
        if (result) {
            row->figures = job_figures(result);
            json_decref(result);
        } else {
            snprintf(row->id, sizeof(row->id), "%s", id);
            job_dir_fail_result(store, row, path, why);
        }
    } else if (status == JOB_QUEUED) {
        row->done = 0;
    }
}

bool job_dir_import(struct store *store, const struct technique_catalog *techniques,
                      const char *id, const char *dir, struct store_row *row)
{
    char path[PATH_MAX + 16], why[600] = "";
    snprintf(path, sizeof(path), "%s/job.json", dir);
    bool legacy = access(path, F_OK) == 0;
    json_t *o = legacy ? record_read(path, why, sizeof(why)) : NULL;
    struct job_spec spec;
    struct job_error jerr;
    enum job_status status = JOB_INTERRUPTED;
    if (o) {
        const char *jid = json_string_value(json_object_get(o, "id"));
        if (!jid || strcmp(jid, id) != 0)
            snprintf(why, sizeof(why), "its id %.40s does not match its directory",
                     jid ? jid : "(none)");
        else if (!job_status_parse(json_string_value(json_object_get(o, "status")), &status))
            snprintf(why, sizeof(why), "no valid status");
        else if (!job_spec_parse(json_object_get(o, "spec"), techniques, &spec, &jerr))
            snprintf(why, sizeof(why), "not a job this daemon can read (%s: %s)", jerr.field,
                     jerr.message);
        if (!why[0]) {
            row_from_legacy(store, id, dir, o, status, &spec, row);
            json_decref(o);
            if (job_status_finished(row->status)) {
                json_decref(row->spec); /* its spec.json has it */
                row->spec = NULL;
            }
            return true;
        }
        json_decref(o);
    }
    char rebuilt[800], reason[1600];
    const char *lost = legacy ? "its job.json was damaged" : "its state was not in the store";
    if (!rebuild_row(store, techniques, id, dir, lost, row, rebuilt, sizeof(rebuilt))) {
        snprintf(reason, sizeof(reason), "%s%s; cannot be rebuilt: %s", legacy ? "job.json: " : "",
                 legacy ? why : "no row in the store and no job.json", rebuilt);
        record_quarantine(store_record_kind(store, STORE_JOBS), id, dir, reason, NULL, 0);
        return false;
    }
    if (job_status_finished(row->status)) {
        json_decref(row->spec);
        row->spec = NULL;
    }
    if (legacy) {
        snprintf(reason, sizeof(reason), "job.json: %s; job %s", why, rebuilt);
        record_quarantine(store_record_kind(store, STORE_JOBS), id, path, reason, NULL, 0);
    } else {
        snprintf(reason, sizeof(reason), "no row in the store (a submission cut short, or the "
                 "store was rebuilt); job %s", rebuilt);
    }
    LOG(LOG_WARN, "job %s: %s", id, reason);
    return true;
}

