#ifndef SHADEBENCH_WORKLOAD_H
#define SHADEBENCH_WORKLOAD_H

/* What makes two jobs the same measurement, so that history compares like
 * with like: the technique and every spec field that changes what is timed
 * (scene, look, frames, warm-up, the technique's own options), but not the
 * fields that do not (labels, repeat, captures, reference, metrics,
 * timeout: gate_nonsemantic_field) nor another technique's options.
 *
 * One workload has one hash everywhere: in JUnit names (made from the job
 * file as the user wrote it), in history (from the spec the daemon
 * echoes) and in the gate. So the spec is first read by the daemon's own
 * job parser (linked from libsb-jobs, with its catalogue of techniques),
 * which fills in every default, and then every field equal to its default
 * is dropped: the file as written and the daemon's spec give the same
 * canonical form, and a field the daemon adds later with a default changes
 * no hash. A spec this client's parser refuses (a newer daemon's technique)
 * is taken as written. Numbers compare by value (20 and 20.0).
 *
 * GL-free, no I/O; single-threaded (the catalogue is made on first use);
 * unit-tested in tests/unit/test_client.c. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* The spec reduced to the fields that define the workload and differ from
 * their defaults, numbers normalised, the technique always named. New
 * reference (an empty object for a spec that is not one). */
json_t *workload_canonical(const json_t *spec);

/* A key equal for two specs exactly when their canonical forms are equal:
 * "<technique>#<16 hex digits of FNV-1a 64 over the sorted canonical JSON>".
 * Names and history show its first 8 digits. */
void workload_key(const json_t *spec, char *out, size_t cap);

/* The workload for people: the JUnit name (junit_job_name: technique,
 * options, scene, the workload's hash, frames) of the canonical spec with
 * the scene's preset, size, lights and motion always spelled out. */
void workload_describe(const json_t *spec, char *out, size_t cap);

/* Whether quality checks (--min-ssim, --max-flip) can judge the job's
 * captures: it names a reference technique and captures at least one
 * frame. False with why ("it names no \"reference\" technique ...") when
 * not, so that the client refuses the option before any job runs. */
bool workload_quality_judged(const json_t *spec, char *why, size_t cap);

#endif
