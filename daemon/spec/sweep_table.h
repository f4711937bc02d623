#ifndef SHADEBENCH_SWEEP_TABLE_H
#define SHADEBENCH_SWEEP_TABLE_H

/* A sweep's table, built from its point jobs (GL-free, any thread): the
 * daemon's sweeps (sweeps.c) and the client's fleet gathering (a Slurm
 * array's task folders) share these, so the same points give the same rows
 * whichever way they ran. */

#include <jansson.h>

#include "daemon/spec/sweep_spec.h"

/* The row of a finished point job (as GET /v1/jobs/ID answers it, or the
 * job.json that shadebenchd --once writes): values (stolen), job, status,
 * technique, the three time series with intervals, wall_s, quality and
 * overflow figures. New reference. */
json_t *sweep_table_row(const json_t *job, json_t *values);

/* A grid's result over its rows: pdiff_passing, and with one swept
 * parameter largest_pdiff_pass. New reference. */
json_t *sweep_table_result(const struct sweep_spec *spec, const json_t *points);

#endif
