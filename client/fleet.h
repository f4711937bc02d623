#ifndef SHADEBENCH_FLEET_H
#define SHADEBENCH_FLEET_H

/* A sweep across a fleet: the client expands it into its point jobs with the
 * daemon's own expansion (sweep_spec, linked from libsb-jobs), a Slurm job
 * array runs each point as `shadebenchd --once` on the node it is given
 * (one array per device class), and the task folders are gathered into one
 * sweep result with a device column: the same table, CSV, charts and report
 * as a daemon's sweep, per device class, and a view that compares devices.
 * Single-threaded, like the rest of the client.
 *
 * The fleet folder (--out DIR), shared by every node:
 *   plan/sweep.json      the sweep as given; plan/points.json its points
 *   plan/N.json          point N's job
 *   tasks/CLASS/N/       point N's result on device class CLASS, written
 *                        whole by shadebenchd --once (job.json, task.json,
 *                        result.json, timings.csv, captures)
 *   slurm/               task.sh, submissions.json, states.json, logs/
 *   sweep.json, table.csv, report.html        the gathered sweep
 *   devices/CLASS/{sweep.json,table.csv,charts/,report.html}  per class */

#include <jansson.h>
#include <stdbool.h>
#include <stdio.h>

struct options;

struct fleet_options {
    bool slurm;
    const char *partition;
    const char *gres;        /* --gres, as sbatch takes it ("gpu:1") */
    const char *constraint;  /* one device class, by node feature */
    const char *devices;     /* D1,D2,...: one array per feature */
    const char *shadebenchd; /* the daemon on the nodes */
    const char *resume;      /* a fleet folder to complete */
    const char *time_limit;  /* sbatch --time, per task */
    int max_parallel;        /* the array's %M; 0: Slurm's limit */
    bool requeue;
};

/* The plan: expands body (a sweep, as POST /v1/sweeps takes it) into dir's
 * plan/ folder. A find sweep is refused (each probe depends on the last).
 * False with err naming the field and the rule, as the daemon would. */
bool fleet_plan_write(const json_t *body, const char *dir, char *err, size_t cap);
/* plan/points.json of dir: {"points": [{"index", "technique", "values"}], "spec", ...};
 * NULL with err. New reference. */
json_t *fleet_plan_read(const char *dir, char *err, size_t cap);

/* Gathers the task folders of dirs (fleet folders of one plan: the same
 * plan/sweep.json) into out: sweep.json, table.csv, report.html and
 * devices/CLASS/. Slurm's states for tasks with no folder come from each
 * dir's slurm/states.json. A pure function of the folders: gathering twice
 * writes the same bytes. Returns the gathered sweep (new reference), NULL
 * with err. */
json_t *fleet_gather(const char *const *dirs, int ndirs, const char *out, const char *series,
                     char *err, size_t cap);

/* The device comparison of a gathered sweep's groups ([{"class", "device",
 * "sweep"}]): per point each device's median time and quality, per group of
 * the other swept values the fastest technique on each device, and each
 * device's crossovers. Pure (tests/unit/test_fleet.c). New reference. */
json_t *fleet_device_view(const json_t *groups, const char *series);
/* The view as plain text tables, for compare-devices. */
void fleet_view_print(FILE *f, const json_t *view);

/* Commands. */
int cmd_sweep_slurm(const struct options *o, const char *sweep_file);
int cmd_gather(const struct options *o, const char *const *dirs, int n);
/* Writes the plan only (--out DIR), for runners other than Slurm. */
int cmd_plan(const struct options *o, const char *sweep_file);
int cmd_compare_devices(const struct options *o, const char *dir);

/* The sweep table as CSV: swept values, then the figures; with devices,
 * the device class first (cmd_sweep.c's table.csv). */
bool sweep_csv_write(const json_t *sweep, const char *path);

#endif
