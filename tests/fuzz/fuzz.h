#ifndef SHADEBENCH_FUZZ_H
#define SHADEBENCH_FUZZ_H

/* Shared by the libFuzzer targets: the entry point, and the check that turns
 * a broken invariant into a crash libFuzzer reports (and the replay runner
 * into a failed test). */

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FUZZ_ASSERT(cond)                                                                \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #cond); \
            abort();                                                                     \
        }                                                                                \
    } while (0)

#include "daemon/techniques/catalog.h"

/* The catalogue of the techniques the daemon registers, as the job and sweep
 * parsers take it: every registered technique's GL-free half. */
static inline const struct technique_catalog *fuzz_techniques(void)
{
    static struct technique_catalog c;
    if (!c.count) {
        char err[256];
        if (!technique_catalog_init(&c, err, sizeof(err))) {
            fprintf(stderr, "fuzz: %s\n", err);
            abort();
        }
    }
    return &c;
}
#define FUZZ_TECHNIQUES fuzz_techniques()

#endif
