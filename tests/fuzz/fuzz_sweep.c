/* The sweep parser on any bytes. Invariants: it never crashes; a refusal
 * makes an error JSON; and every point of an accepted sweep is a job the job
 * parser accepts (every grid point, and for a search both ends and the
 * values bisection would probe). */
#include <jansson.h>
#include <math.h>
#include <string.h>

#include "daemon/spec/sweep_spec.h"
#include "tests/fuzz/fuzz.h"

static void valid_job(json_t *job)
{
    struct job_spec spec;
    struct job_error err;
    bool ok = job_spec_parse(job, FUZZ_TECHNIQUES, &spec, &err);
    if (!ok) {
        char *text = json_dumps(job, JSON_COMPACT);
        fprintf(stderr, "accepted sweep has an invalid point: %s: %s\n%s\n", err.field,
                err.message, text ? text : "?");
        free(text);
    }
    FUZZ_ASSERT(ok);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > JOB_MAX_BODY_BYTES)
        return 0;
    json_t *body = json_loadb((const char *)data, size, JSON_REJECT_DUPLICATES, NULL);
    if (!body)
        return 0;
    struct sweep_spec s;
    struct job_error err;
    if (!sweep_spec_parse(body, FUZZ_TECHNIQUES, &s, &err)) {
        json_t *e = job_error_to_json(&err);
        FUZZ_ASSERT(e != NULL);
        char *text = json_dumps(e, JSON_COMPACT);
        FUZZ_ASSERT(text != NULL);
        free(text);
        json_decref(e);
        sweep_spec_finish(&s);
        json_decref(body);
        return 0;
    }
    FUZZ_ASSERT(s.npoints >= 1 && s.npoints <= SWEEP_MAX_POINTS);
    if (s.kind == SWEEP_VARY) {
        for (size_t p = 0; p < s.npoints; p++) {
            json_t *values, *job = sweep_point_job(&s, p, &values);
            valid_job(job);
            json_decref(job);
            json_decref(values);
        }
    } else {
        /* Bisection probes lie between the ends; for integer fields they are
         * whole numbers. */
        double lo = s.from, hi = s.to;
        for (int i = 0; i < s.max_probes; i++) {
            double v = i == 0 ? s.from : (i == 1 ? s.to : (s.integer ? floor((lo + hi) / 2) : (lo + hi) / 2));
            json_t *job = sweep_probe_job(&s, v);
            valid_job(job);
            json_decref(job);
            if (i >= 2 && (i & 1))
                lo = v;
            else if (i >= 2)
                hi = v;
        }
    }
    sweep_spec_finish(&s);
    json_decref(body);
    return 0;
}
