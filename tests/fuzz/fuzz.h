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

/* The techniques the daemon registers (their GL halves are not linked). */
static const char *const FUZZ_TECHNIQUES[] = {"forward", "unlit", "osl", NULL};

#endif
