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

#include "daemon/techniques/osl/osl_info.h"
#include "daemon/techniques/technique_info.h"

/* The catalogue of the techniques the daemon registers, as the job and sweep
 * parsers take it: OSL's real GL-free half, and forward and unlit as their
 * infos declare them (no options; their GL halves are not linked). */
static const char *const fuzz_passes[] = {"shading", NULL};
static const struct technique_info fuzz_forward = {
    .name = "forward", .summary = "forward", .passes = fuzz_passes};
static const struct technique_info fuzz_unlit = {
    .name = "unlit", .summary = "unlit", .passes = fuzz_passes};

static inline const struct technique_catalog *fuzz_techniques(void)
{
    static struct technique_catalog c;
    if (!c.count) {
        technique_catalog_add(&c, &fuzz_forward);
        technique_catalog_add(&c, &fuzz_unlit);
        technique_catalog_add(&c, &osl_info);
    }
    return &c;
}
#define FUZZ_TECHNIQUES fuzz_techniques()

#endif
