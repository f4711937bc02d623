/* The job parser on any bytes. Invariants: it never crashes; a refusal
 * always makes an error JSON (whatever bytes it quotes); and what it accepts
 * round-trips: job_spec_to_json -> parse -> the same JSON. */
#include <jansson.h>
#include <string.h>

#include "daemon/spec/job_spec.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > JOB_MAX_BODY_BYTES)
        return 0;
    struct job_spec spec, again;
    struct job_error err;
    if (!job_spec_parse_text((const char *)data, size, FUZZ_TECHNIQUES, &spec, &err)) {
        json_t *e = job_error_to_json(&err);
        FUZZ_ASSERT(e != NULL);
        char *text = json_dumps(e, JSON_COMPACT);
        FUZZ_ASSERT(text != NULL);
        free(text);
        json_decref(e);
        FUZZ_ASSERT(err.field[0] != '\0' && err.message[0] != '\0');
        return 0;
    }
    json_t *first = job_spec_to_json(&spec);
    FUZZ_ASSERT(first != NULL);
    char *first_text = json_dumps(first, JSON_COMPACT | JSON_SORT_KEYS);
    FUZZ_ASSERT(first_text != NULL);
    bool ok = job_spec_parse(first, FUZZ_TECHNIQUES, &again, &err);
    if (!ok)
        fprintf(stderr, "refused its own JSON: %s: %s\n%s\n", err.field, err.message, first_text);
    FUZZ_ASSERT(ok);
    json_t *second = job_spec_to_json(&again);
    char *second_text = json_dumps(second, JSON_COMPACT | JSON_SORT_KEYS);
    FUZZ_ASSERT(second_text != NULL && strcmp(first_text, second_text) == 0);
    FUZZ_ASSERT(job_spec_capture_count(&again) <= JOB_MAX_CAPTURES);
    free(first_text);
    free(second_text);
    json_decref(first);
    json_decref(second);
    return 0;
}
