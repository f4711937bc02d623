#ifndef SHADEBENCH_JUNIT_H
#define SHADEBENCH_JUNIT_H

/* Verdicts as test cases, written as JUnit XML that CI systems track from
 * build to build: names come from what a job measures (technique, scene,
 * technique options, frame), never from its id, so the same check keeps its
 * name across builds; every case has its real duration, and its figures as
 * properties and as output, which is also printed to the CI log.
 * GL-free, no network; single-threaded (one collection per command). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* A case has one of four outcomes: passed; failed (failure set, with a
 * type by cause: "regression", "quality", "job_failed", or "inconclusive"
 * for an undecided check the user asked to fail on); inconclusive (skipped
 * set: the check ran but could not decide, written as <skipped
 * message="..."> so that CI dashboards show it as not passed, with the
 * reason); or skipped (the check judged nothing: no reference to score a
 * capture against, or a job's timing figures measured on a busy machine;
 * <skipped> too, never a pass, and no effect on the exit status). */
#define JUNIT_REGRESSION "regression"
#define JUNIT_QUALITY "quality"
#define JUNIT_JOB_FAILED "job_failed"
#define JUNIT_INCONCLUSIVE "inconclusive"

struct junit_case {
    char classname[96];
    char name[400];
    char failure[1024];     /* empty: passed */
    char failure_type[24];  /* the first failure's cause */
    char skipped[1024];     /* inconclusive or judged nothing: why */
    char skip_tag[16];      /* the log's word for a case that judged nothing:
                               "SKIP", "NOISY" */
    bool inconclusive;      /* failure or skipped comes from an undecided check */
    char output[2048];
    double time_s;
    json_t *properties; /* name -> string or number, in insertion order */
};

struct junit {
    struct junit_case *cases;
    size_t count, cap;
};

void junit_init(struct junit *j);
void junit_finish(struct junit *j);

/* A new case; NULL when out of memory. A name already in j gets " (2)",
 * " (3)", ... so that every case of a file is unique (the callers' names
 * already are; this keeps a collision from merging two cases in a CI
 * system). */
struct junit_case *junit_add(struct junit *j, const char *classname, const char *name);

/* A failure of the given cause (JUNIT_REGRESSION, JUNIT_QUALITY,
 * JUNIT_JOB_FAILED). */
void junit_fail(struct junit_case *c, const char *type, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* An undecided check: skipped with the reason, or with fail set a failure
 * of type "inconclusive". */
void junit_inconclusive(struct junit_case *c, bool fail, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* A check that judged nothing: skipped, printed with tag ("SKIP", "NOISY"). */
void junit_skip(struct junit_case *c, const char *tag, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void junit_out(struct junit_case *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void junit_prop_num(struct junit_case *c, const char *name, double value);
void junit_prop_str(struct junit_case *c, const char *name, const char *value);

/* s as XML (and HTML) text or attribute value: markup characters escaped,
 * control characters other than newline and tab dropped. */
void xml_escaped(FILE *f, const char *s);

size_t junit_failures(const struct junit *j);
/* Failures other than undecided checks, undecided checks (skipped or
 * failed on request), and checks that judged nothing. */
size_t junit_real_failures(const struct junit *j);
size_t junit_undecided(const struct junit *j);
size_t junit_judged_nothing(const struct junit *j);

/* Writes the XML; false when the file cannot be written. */
bool junit_write(const struct junit *j, const char *path, const char *suite, double time_s);

/* The CI log: one line a case, PASS, FAIL, INCONCLUSIVE or SKIP (NOISY),
 * its properties and output; color: the word in colour (a terminal without
 * NO_COLOR). */
void junit_print(const struct junit *j, FILE *f, bool color);

/* A stable name for a job from its spec, best the spec as the user wrote it
 * (the job file: a new daemon default then renames nothing), else as the
 * daemon understood it (fetch):
 * "osl async_distance=20 osl(reshade=touched resolution=auto texel_density=1)
 *  grid 160x120 10 lights moving #1a2b3c4d, 20 frames": the technique and
 * its options (top-level numbers that are set, and the object named after
 * it), the scene's preset, size, lights and their motion, the workload's
 * hash (the first 8 digits of workload_key: jobs that differ anywhere in
 * what is timed get different names, without burying the name, and history
 * prints the same hash for the same workload), and the frames. Options of other techniques and the fields that do not change
 * what is measured (labels, repeat, captures, reference, metrics) are left
 * out, and so are scene fields the spec does not name. At most 240
 * characters. */
void junit_job_name(const json_t *spec, char *out, size_t cap);

#endif
