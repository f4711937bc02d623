/* A fleet sweep's plan: the sweep expanded into its point jobs by the
 * daemon's own code (sweep_spec_parse and sweep_point_job from libsb-jobs,
 * with the daemon's catalogue of techniques), so that a point run by a
 * Slurm task is the job the daemon would have run for it. Single-threaded. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "client/fleet.h"
#include "common/fsutil.h"
#include "daemon/spec/sweep_spec.h"
#include "daemon/techniques/catalog.h"

bool fleet_plan_write(const json_t *body, const char *dir, char *err, size_t cap)
{
    static struct technique_catalog catalog;
    static bool have_catalog;
    char why[256];
    if (!have_catalog && !technique_catalog_init(&catalog, why, sizeof(why))) {
        snprintf(err, cap, "the catalogue of techniques: %s", why);
        return false;
    }
    have_catalog = true;
    struct sweep_spec spec;
    struct job_error jerr;
    if (!sweep_spec_parse(body, &catalog, &spec, &jerr)) {
        snprintf(err, cap, "%s: %s", jerr.field, jerr.message);
        return false;
    }
    bool ok = false;
    json_t *points = json_array(), *plan = NULL;
    char path[PATH_MAX];
    if (spec.kind == SWEEP_FIND) {
        snprintf(err, cap, "find: a bisection's probes run one after another, each chosen by the "
                           "last, so it cannot run as a job array; run it on one daemon "
                           "(shadebench sweep without --slurm), or sweep a grid with vary");
        goto out;
    }
    snprintf(path, sizeof(path), "%s/plan", dir);
    if (!fs_mkdir_p(path)) {
        snprintf(err, cap, "cannot create %s: %s", path, strerror(errno));
        goto out;
    }
    for (size_t i = 0; i < spec.npoints; i++) {
        json_t *values = NULL, *job = sweep_point_job(&spec, i, &values);
        snprintf(path, sizeof(path), "%s/plan/%zu.json", dir, i);
        bool written = job && fs_write_json_atomic(path, job);
        json_array_append_new(points, json_pack("{s:I, s:O, s:o, s:b}", "index", (json_int_t)i,
                                                "technique", json_object_get(job, "technique"),
                                                "values", values ? values : json_object(),
                                                "timed_reference", i >= spec.ngrid));
        json_decref(job);
        if (!written) {
            snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
            goto out;
        }
    }
    plan = json_pack("{s:s, s:I, s:I, s:O, s:[]}", "kind", "vary", "points_total",
                     (json_int_t)spec.npoints, "grid_points", (json_int_t)spec.ngrid, "points",
                     points, "params");
    for (int p = 0; plan && p < spec.nparams; p++)
        json_array_append_new(json_object_get(plan, "params"), json_string(spec.params[p]));
    snprintf(path, sizeof(path), "%s/plan/sweep.json", dir);
    if (!plan || !fs_write_json_atomic(path, body)) {
        snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
        goto out;
    }
    /* Last: a plan folder without points.json is one that was not finished. */
    snprintf(path, sizeof(path), "%s/plan/points.json", dir);
    if (!fs_write_json_atomic(path, plan)) {
        snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
        goto out;
    }
    ok = true;
out:
    json_decref(plan);
    json_decref(points);
    sweep_spec_finish(&spec);
    return ok;
}

json_t *fleet_plan_read(const char *dir, char *err, size_t cap)
{
    char path[PATH_MAX];
    json_error_t jerr;
    snprintf(path, sizeof(path), "%s/plan/points.json", dir);
    json_t *plan = json_load_file(path, 0, &jerr);
    if (!plan) {
        snprintf(err, cap, "%s is not a fleet folder: %s: %s", dir, path, jerr.text);
        return NULL;
    }
    snprintf(path, sizeof(path), "%s/plan/sweep.json", dir);
    json_t *spec = json_load_file(path, 0, &jerr);
    if (!spec || !json_is_array(json_object_get(plan, "points"))) {
        snprintf(err, cap, "%s: %s", path, spec ? "points.json has no points" : jerr.text);
        json_decref(spec);
        json_decref(plan);
        return NULL;
    }
    json_object_set_new(plan, "spec", spec);
    return plan;
}
