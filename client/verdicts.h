#ifndef SHADEBENCH_VERDICTS_H
#define SHADEBENCH_VERDICTS_H

/* Verdicts shared by the client's commands: quality per capture, a job's
 * figures as a test case, the run set a gate or an A/B comparison collects
 * (each run a job of its own, so that each carries its own interference
 * figures and a disturbed run can be replaced alone), and the JUnit file
 * and exit status at the end. Single-threaded. */

#include <jansson.h>
#include <stdbool.h>

#include "client/client.h"
#include "client/gate.h"
#include "client/junit.h"

/* One case per capture: PerceptualDiff, --min-ssim, --max-flip. */
void quality_cases(const struct options *o, const json_t *result, const char *classname,
                   const char *name, struct junit *j);

/* "2026-11-21T10:00:05.123Z" (the daemon's times) in seconds since 1970;
 * NAN when it is not one. */
double iso_unix_s(const char *s);

/* The job case: failed unless done; the figures as properties. time_s 0:
 * the job's span from creation to its end. */
struct junit_case *job_case(struct junit *j, const char *classname, const char *name,
                            const json_t *job, double time_s);

/* The classname of a job's cases: "shadebench.<technique>". */
void job_classname(const json_t *spec, char *out, size_t cap);

/* Runs collected by submitting one job file again and again. */
struct run_set {
    struct conn *conn;
    const char *what;       /* progress prefix: "run", "A", "B" */
    size_t planned;         /* the runs asked for (--runs): the log counts against it */
    int budget;             /* extra runs allowed beyond them (--max-reruns) */
    struct gate_run *runs;
    json_t *jobs;           /* the final job JSON of each run, same order */
    size_t n, cap;
    double elapsed_s;       /* submission to end, summed over runs */
    json_t *failed;         /* the job of a run that ended other than done */
};

void run_set_init(struct run_set *s, struct conn *c, const char *what);
void run_set_finish(struct run_set *s);

/* Submits text, follows the job to its end and records it as a run of
 * series. check (may be NULL) is called once the job is queued, with its
 * spec as the daemon understood it; returning false cancels the job and
 * fails. Returns false on a server error, a refused check or a run without
 * the series (message printed); a job that failed is kept in s->failed and
 * returns true. The job's id goes to stdout (one a line, for scripts); the
 * log on stderr gets one line a run when it ends (run_set_line), with a
 * progress bar before it on a terminal only. */
typedef bool (*spec_check_fn)(const json_t *spec, void *ctx);
bool run_set_add(struct run_set *s, const struct options *o, const char *text,
                 const char *series, spec_check_fn check, void *ctx);

/* gate_runs for result.json: each run's job, its medians of every series,
 * interference, and whether it was left out as noisy and why. */
json_t *run_set_json(const struct run_set *s);

/* Writes every run's job.json, result.json and timings.csv to DIR/runs/ID/. */
bool run_set_write(const struct run_set *s, const char *dir);

/* Prints one line a run (its median, other processes' CPU share, noise). */
void run_set_print(const struct run_set *s, const char *series, FILE *f);

/* One run for the log, as it ends: "run 6 (extra 1 of at most 10): job ID,
 * frame_ms 12.345 ms, others took 45% of the CPU, 3.2 s". i counts from 0.
 * Pure (no I/O); for the unit tests too. */
void run_set_line(const struct run_set *s, size_t i, const char *series, char *out, size_t cap);

/* Writes --junit, prints the cases to stderr (unless quiet), and returns
 * the exit status: 1 when a case failed outright, 3 when a check could not
 * decide and the user asked to fail on that, 2 when the file could not be
 * written, else 0 (with a warning for undecided checks). */
int junit_conclude(const struct options *o, struct junit *j, const char *suite, double time_s);

#endif
