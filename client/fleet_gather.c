/* Gathering a fleet's task folders into one sweep result: per device class
 * the table a daemon's sweep has (sweep_table_row on each task's job.json),
 * its CSV, charts and report (the daemon's own code, libsb-reports), and
 * across classes a device column and a view that compares devices. Only
 * task folders that shadebenchd --once renamed into place are read (a
 * half-written one is a ".partial-" sibling), and nothing of the gathering
 * itself (time, host, order of the directory listing) reaches the output:
 * gathering twice writes the same bytes. Single-threaded. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/fleet.h"
#include "client/junit.h" /* xml_escaped */
#include "common/fsutil.h"
#include "common/result_keys.h"
#include "daemon/reports/charts.h"
#include "daemon/reports/report.h"
#include "daemon/reports/sweep_verdict.h"
#include "daemon/spec/sweep_table.h"

/* A device class's points as the report's job_dir callback finds them. */
struct class_dirs {
    json_t *dirs; /* {"CLASS/N": folder} */
};

static bool task_dir(void *ctx, const char *job_id, char *dir, size_t cap, int *last_frame)
{
    const struct class_dirs *cd = ctx;
    const char *d = json_string_value(json_object_get(cd->dirs, job_id));
    if (!d)
        return false;
    snprintf(dir, cap, "%s", d);
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/job.json", d);
    json_t *job = json_load_file(path, 0, NULL);
    json_t *caps = json_object_get(json_object_get(job, RK_RESULT), RK_CAPTURES);
    *last_frame = (int)json_integer_value(
        json_object_get(json_array_get(caps, json_array_size(caps) - 1), "frame"));
    json_decref(job);
    return true;
}

static void add_class(json_t *classes, const char *name)
{
    size_t i;
    json_t *c;
    json_array_foreach(classes, i, c) if (!strcmp(json_string_value(c), name)) return;
    json_array_append_new(classes, json_string(name));
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The device classes of dirs: those Slurm was asked for, in the order
 * given, then any other task folder's, sorted (a CI runner's labels). */
static json_t *find_classes(const char *const *dirs, int ndirs)
{
    json_t *classes = json_array();
    char path[PATH_MAX];
    for (int d = 0; d < ndirs; d++) {
        snprintf(path, sizeof(path), "%s/slurm/submissions.json", dirs[d]);
        json_t *subs = json_load_file(path, 0, NULL);
        size_t i;
        json_t *s;
        json_array_foreach(subs, i, s) {
            const char *c = json_string_value(json_object_get(s, "class"));
            if (c)
                add_class(classes, c);
        }
        json_decref(subs);
    }
    for (int d = 0; d < ndirs; d++) {
        snprintf(path, sizeof(path), "%s/tasks", dirs[d]);
        DIR *dir = opendir(path);
        if (!dir)
            continue;
        char *names[256];
        size_t n = 0;
        struct dirent *e;
        while ((e = readdir(dir)) && n < 256)
            if (e->d_name[0] != '.')
                names[n++] = strdup(e->d_name);
        closedir(dir);
        qsort(names, n, sizeof(names[0]), cmp_str);
        for (size_t i = 0; i < n; i++) {
            if (names[i])
                add_class(classes, names[i]);
            free(names[i]);
        }
    }
    return classes;
}

/* What Slurm said of each task without a folder: {CLASS: {N: {...}}}. */
static json_t *load_states(const char *const *dirs, int ndirs)
{
    json_t *all = json_object();
    char path[PATH_MAX];
    for (int d = ndirs - 1; d >= 0; d--) {
        snprintf(path, sizeof(path), "%s/slurm/states.json", dirs[d]);
        json_t *st = json_load_file(path, 0, NULL);
        const char *cls;
        json_t *tasks;
        json_object_foreach(st, cls, tasks) {
            json_t *into = json_object_get(all, cls);
            if (!into)
                json_object_set_new(all, cls, into = json_object());
            json_object_update(into, tasks);
        }
        json_decref(st);
    }
    return all;
}

static bool write_text(const char *path, const char *data, size_t len, char *err, size_t cap)
{
    if (fs_write_atomic(path, data, len))
        return true;
    snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
    return false;
}

/* The device a class's results name: the first task's, with the nodes seen. */
static json_t *class_device(const char *cls, const json_t *rows)
{
    json_t *dev = json_pack("{s:s}", "class", cls), *nodes = json_array();
    size_t i;
    json_t *row;
    json_array_foreach(rows, i, row) {
        json_t *d = json_object_get(row, "device");
        static const char *const keys[] = {"gl_renderer", "gl_version", "gl_vendor", "egl_device",
                                           "egl_platform"};
        for (size_t k = 0; k < sizeof(keys) / sizeof(keys[0]); k++)
            if (!json_object_get(dev, keys[k]) && json_object_get(d, keys[k]))
                json_object_set(dev, keys[k], json_object_get(d, keys[k]));
        const char *node = json_string_value(json_object_get(d, "node"));
        if (node)
            add_class(nodes, node);
    }
    json_object_set_new(dev, "nodes", nodes);
    return dev;
}

/* Point index's row on class from the first dir that has its folder, or a
 * row marking it missing with what Slurm said of it. */
static json_t *gather_row(const char *const *dirs, int ndirs, const char *cls, const json_t *point,
                          const json_t *states, struct class_dirs *cd)
{
    json_int_t index = json_integer_value(json_object_get(point, "index"));
    char path[PATH_MAX + 64], folder[PATH_MAX], key[300];
    snprintf(key, sizeof(key), "%s/%lld", cls, (long long)index);
    for (int d = 0; d < ndirs; d++) {
        snprintf(folder, sizeof(folder), "%s/tasks/%s/%lld", dirs[d], cls, (long long)index);
        snprintf(path, sizeof(path), "%s/job.json", folder);
        json_t *job = json_load_file(path, 0, NULL);
        if (!job)
            continue;
        snprintf(path, sizeof(path), "%s/task.json", folder);
        json_t *task = json_load_file(path, 0, NULL);
        json_t *row = sweep_table_row(job, json_deep_copy(json_object_get(point, "values")));
        /* Job ids are per daemon (time-based): the task's folder names the
         * row uniquely across the fleet. */
        json_object_set(row, "task_job", json_object_get(job, "id"));
        json_object_set_new(row, "job", json_string(key));
        json_t *rd = json_object_get(json_object_get(job, RK_RESULT), "device");
        json_t *dev = json_pack("{s:s}", "class", cls);
        /* Which GPU the task opened, by every name it has, and why
         * (--device allocated: the Slurm variable or cgroup it followed). */
        static const char *const keys[] = {"gl_renderer", "gl_version", "gl_vendor", "egl_device",
                                           "egl_platform", "bus_id", "uuid", "render_node",
                                           "selection"};
        for (size_t k = 0; k < sizeof(keys) / sizeof(keys[0]); k++)
            if (json_object_get(rd, keys[k]))
                json_object_set(dev, keys[k], json_object_get(rd, keys[k]));
        if (json_object_get(task, "node"))
            json_object_set(dev, "node", json_object_get(task, "node"));
        json_t *slurm = json_object_get(task, "slurm");
        if (slurm)
            json_object_set(dev, "slurm", slurm);
        json_object_set_new(row, "device", dev);
        json_object_set_new(cd->dirs, key, json_string(folder));
        json_decref(task);
        json_decref(job);
        return row;
    }
    json_t *st = json_object_get(json_object_get(states, cls), strchr(key, '/') + 1);
    char why[400];
    const char *state = json_string_value(json_object_get(st, "state"));
    if (state)
        snprintf(why, sizeof(why), "no result: Slurm task %s ended %s, exit code %s, on node %s",
                 json_string_value(json_object_get(st, "job_id")) ?
                 json_string_value(json_object_get(st, "job_id")) : "?",
                 state, json_string_value(json_object_get(st, "exit_code")) ?
                 json_string_value(json_object_get(st, "exit_code")) : "?",
                 json_string_value(json_object_get(st, "node")) &&
                 json_string_value(json_object_get(st, "node"))[0] ?
                 json_string_value(json_object_get(st, "node")) : "none");
    else
        snprintf(why, sizeof(why), "no result: no task folder %s in any gathered folder", key);
    json_t *row = json_pack("{s:O, s:s, s:O, s:s, s:s, s:{s:s}}", "values",
                            json_object_get(point, "values"), "job", key, "technique",
                            json_object_get(point, "technique"), "status", "missing", "error", why,
                            "device", "class", cls);
    if (st)
        json_object_set(row, "slurm", st);
    return row;
}

static bool write_class(const char *out, const char *cls, json_t *sweep, const json_t *device,
                        struct class_dirs *cd, char *err, size_t cap)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/devices/%s/charts", out, cls);
    if (!fs_mkdir_p(path)) {
        snprintf(err, cap, "cannot create %s: %s", path, strerror(errno));
        return false;
    }
    snprintf(path, sizeof(path), "%s/devices/%s/sweep.json", out, cls);
    if (!fs_write_json_atomic(path, sweep)) {
        snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
        return false;
    }
    snprintf(path, sizeof(path), "%s/devices/%s/table.csv", out, cls);
    if (!sweep_csv_write(sweep, path)) {
        snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
        return false;
    }
    /* The files shadebench sweep --out downloads from a daemon. */
    static const struct {
        const char *file, *chart;
        bool flip;
    } charts[] = {
        {"speed_accuracy", "speed_accuracy", false},
        {"speed_accuracy_flip", "speed_accuracy", true},
        {"time_vs_param", "time_vs_param", false},
        {"distribution", "distribution", false},
    };
    static const char *const ext[] = {"svg", "png"};
    for (size_t k = 0; k < sizeof(charts) / sizeof(charts[0]); k++)
        for (int f = 0; f < 2; f++) {
            struct chart_options o = {.flip = charts[k].flip, .device = device};
            size_t len = 0;
            char why[256];
            char *data = charts_sweep(sweep, charts[k].chart, f ? CHART_PNG : CHART_SVG, &o, &len,
                                      why, sizeof(why));
            snprintf(path, sizeof(path), "%s/devices/%s/charts/%s.%s", out, cls, charts[k].file,
                     ext[f]);
            bool ok = data && write_text(path, data, len, err, cap);
            free(data);
            if (!ok) {
                if (!data)
                    snprintf(err, cap, "chart %s of %s: %s", charts[k].file, cls, why);
                return false;
            }
        }
    size_t len = 0;
    char *html = report_sweep_html(sweep, device, task_dir, cd, &len);
    snprintf(path, sizeof(path), "%s/devices/%s/report.html", out, cls);
    bool ok = html && write_text(path, html, len, err, cap);
    if (!html)
        snprintf(err, cap, "the report of %s: out of memory", cls);
    free(html);
    return ok;
}

/* The fleet's own page: the devices, the comparison, what is missing, and
 * each class's report beside it. */
static char *fleet_html(const json_t *fleet, size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    if (!f)
        return NULL;
    fputs("<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>shadebench fleet sweep"
          "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
          "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}"
          "td.l{text-align:left}pre{background:#f6f6f6;padding:1em}</style></head><body>\n",
          f);
    const char *status = json_string_value(json_object_get(fleet, "status"));
    json_t *progress = json_object_get(fleet, "progress");
    fprintf(f, "<h1>Fleet sweep: %s</h1>\n<p>%lld of %lld points gathered",
            status ? status : "?",
            (long long)json_integer_value(json_object_get(progress, "points_done")),
            (long long)json_integer_value(json_object_get(progress, "points_total")));
    if (status && strcmp(status, "done"))
        fputs(": <b>partial</b>, the missing points are listed below and the figures cover "
              "what ran", f);
    fputs(".</p>\n<h2>Devices</h2>\n<table><tr><th>class</th><th>GL renderer</th><th>GL version"
          "</th><th>nodes</th><th>points</th><th>report</th></tr>\n", f);
    size_t i, j;
    json_t *d, *n;
    json_array_foreach(json_object_get(fleet, "devices"), i, d) {
        const char *cls = json_string_value(json_object_get(d, "class"));
        fputs("<tr><td class=l>", f);
        xml_escaped(f, cls);
        fputs("</td><td class=l>", f);
        xml_escaped(f, json_string_value(json_object_get(d, "gl_renderer")));
        fputs("</td><td class=l>", f);
        xml_escaped(f, json_string_value(json_object_get(d, "gl_version")));
        fputs("</td><td class=l>", f);
        json_array_foreach(json_object_get(d, "nodes"), j, n) {
            if (j)
                fputs(", ", f);
            xml_escaped(f, json_string_value(n));
        }
        fprintf(f, "</td><td>%lld / %lld</td><td class=l><a href=\"devices/",
                (long long)json_integer_value(json_object_get(d, "points_done")),
                (long long)json_integer_value(json_object_get(d, "points_total")));
        xml_escaped(f, cls);
        fputs("/report.html\">report</a></td></tr>\n", f);
    }
    fputs("</table>\n<h2>Comparison</h2>\n<pre>", f);
    char *text = NULL;
    size_t tlen = 0;
    FILE *t = open_memstream(&text, &tlen);
    if (t) {
        fleet_view_print(t, json_object_get(fleet, "view"));
        fclose(t);
        xml_escaped(f, text);
        free(text);
    }
    fputs("</pre>\n", f);
    json_t *missing = json_object_get(fleet, "missing");
    if (json_array_size(missing)) {
        fputs("<h2>Missing points</h2>\n<ul>\n", f);
        json_t *m;
        json_array_foreach(missing, i, m) {
            fputs("<li>", f);
            xml_escaped(f, json_string_value(json_object_get(m, "job")));
            fputs(" (", f);
            xml_escaped(f, json_string_value(json_object_get(m, "technique")));
            fputs("): ", f);
            xml_escaped(f, json_string_value(json_object_get(m, "error")));
            fputs("</li>\n", f);
        }
        fputs("</ul>\n", f);
    }
    fputs("</body></html>\n", f);
    if (fclose(f) != 0) {
        free(buf);
        return NULL;
    }
    return buf;
}

json_t *fleet_gather(const char *const *dirs, int ndirs, const char *out, const char *series,
                     char *err, size_t cap)
{
    json_t *plan = fleet_plan_read(dirs[0], err, cap);
    if (!plan)
        return NULL;
    for (int d = 1; d < ndirs; d++) {
        json_t *other = fleet_plan_read(dirs[d], err, cap);
        bool same = other && json_equal(json_object_get(other, "spec"), json_object_get(plan, "spec"));
        json_decref(other);
        if (!same) {
            if (other)
                snprintf(err, cap, "%s and %s hold different sweeps (plan/sweep.json): gather "
                                   "folders of one sweep", dirs[0], dirs[d]);
            json_decref(plan);
            return NULL;
        }
    }
    struct sweep_spec spec;
    memset(&spec, 0, sizeof(spec));
    json_t *params = json_object_get(plan, "params"), *p;
    size_t i;
    json_array_foreach(params, i, p) if (i < SWEEP_MAX_PARAMS)
        snprintf(spec.params[spec.nparams++], sizeof(spec.params[0]), "%s", json_string_value(p));
    json_t *classes = find_classes(dirs, ndirs);
    json_t *states = load_states(dirs, ndirs);
    json_t *points = json_object_get(plan, "points");
    size_t npoints = json_array_size(points);
    json_t *all = json_array(), *missing = json_array(), *devices = json_array(),
           *groups = json_array();
    json_t *fleet = NULL;
    long long done_total = 0;
    bool ok = true;
    if (!json_array_size(classes)) {
        snprintf(err, cap, "%s has no task folder (tasks/CLASS/N) and no Slurm submission: "
                           "nothing to gather", dirs[0]);
        ok = false;
    }
    json_t *c;
    json_array_foreach(classes, i, c) {
        if (!ok)
            break;
        const char *cls = json_string_value(c);
        struct class_dirs cd = {json_object()};
        json_t *rows = json_array(), *pt;
        size_t k;
        long long done = 0;
        json_array_foreach(points, k, pt) {
            json_t *row = gather_row(dirs, ndirs, cls, pt, states, &cd);
            const char *st = json_string_value(json_object_get(row, "status"));
            if (!strcmp(st, "missing"))
                json_array_append(missing, row);
            else
                done++;
            json_array_append(all, row);
            json_array_append_new(rows, row);
        }
        done_total += done;
        json_t *device = class_device(cls, rows);
        bool complete = done == (long long)npoints;
        json_t *sweep = json_pack(
            "{s:s, s:s, s:s, s:{s:I, s:I}, s:O, s:O, s:o, s:O}", "id", cls, "kind", "vary", "status",
            complete ? "done" : "partial", "progress", "points_done", (json_int_t)done,
            "points_total", (json_int_t)npoints, "spec", json_object_get(plan, "spec"), "points",
            rows, RK_RESULT, sweep_table_result(&spec, rows), "device", device);
        ok = write_class(out, cls, sweep, device, &cd, err, cap);
        json_t *dv = json_deep_copy(device);
        json_object_set_new(dv, "points_done", json_integer(done));
        json_object_set_new(dv, "points_total", json_integer((json_int_t)npoints));
        json_object_set_new(dv, "status", json_string(complete ? "done" : "partial"));
        json_array_append_new(devices, dv);
        json_array_append_new(groups, json_pack("{s:s, s:O, s:O}", "class", cls, "device", device,
                                                "sweep", sweep));
        json_decref(device);
        json_decref(sweep);
        json_decref(rows);
        json_decref(cd.dirs);
    }
    if (ok) {
        long long total = (long long)npoints * (long long)json_array_size(classes);
        fleet = json_pack("{s:s, s:s, s:{s:I, s:I}, s:O, s:O, s:O, s:O, s:o}", "kind", "fleet",
                          "status", done_total == total ? "done" : "partial", "progress",
                          "points_done", (json_int_t)done_total, "points_total", (json_int_t)total,
                          "spec", json_object_get(plan, "spec"), "devices", devices, "points", all,
                          "missing", missing, "view", fleet_device_view(groups, series));
        char path[PATH_MAX];
        snprintf(path, sizeof(path), "%s/sweep.json", out);
        if (!fs_write_json_atomic(path, fleet)) {
            snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
            ok = false;
        }
        snprintf(path, sizeof(path), "%s/table.csv", out);
        if (ok && !sweep_csv_write(fleet, path)) {
            snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
            ok = false;
        }
        size_t len = 0;
        char *html = ok ? fleet_html(fleet, &len) : NULL;
        snprintf(path, sizeof(path), "%s/report.html", out);
        ok = ok && html && write_text(path, html, len, err, cap);
        free(html);
    }
    json_decref(groups);
    json_decref(devices);
    json_decref(missing);
    json_decref(all);
    json_decref(states);
    json_decref(classes);
    json_decref(plan);
    if (!ok) {
        json_decref(fleet);
        return NULL;
    }
    return fleet;
}
