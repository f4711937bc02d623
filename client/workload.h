#ifndef SHADEBENCH_WORKLOAD_H
#define SHADEBENCH_WORKLOAD_H

/* What makes two jobs the same measurement, so that history compares like
 * with like: the technique and every spec field that changes what is timed
 * (scene, look, frames, warm-up, the technique's own options), but not the
 * fields that do not (labels, repeat, captures, reference, metrics,
 * timeout: gate_nonsemantic_field) nor another technique's options. Numbers
 * compare by value (20 and 20.0 are one workload).
 * Give it the spec as the user wrote it when there is one; from the daemon's
 * normalised spec, two jobs are the same workload when the daemon filled in
 * the same defaults for both.
 * GL-free, no I/O; pure functions on JSON, any thread; unit-tested in
 * tests/unit/test_client.c. */

#include <jansson.h>
#include <stddef.h>

/* The spec reduced to the fields that define the workload, numbers
 * normalised. New reference (an empty object for a spec that is not one). */
json_t *workload_canonical(const json_t *spec);

/* A key equal for two specs exactly when their canonical forms are equal:
 * "<technique>#<16 hex digits of FNV-1a 64 over the sorted canonical JSON>". */
void workload_key(const json_t *spec, char *out, size_t cap);

/* The workload for people: the JUnit name of the canonical spec
 * (junit_job_name: technique, options, scene, frames) with its hash
 * replaced by the first 8 digits of workload_key's, so that two workloads
 * that differ only in a field the name does not spell out (warm-up
 * frames, say) still read differently. */
void workload_describe(const json_t *spec, char *out, size_t cap);

#endif
