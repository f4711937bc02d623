#ifndef SHADEBENCH_TESTS_CHECK_H
#define SHADEBENCH_TESTS_CHECK_H

/* A minimal assertion helper: every failed CHECK is reported with its line,
 * and the test exits non-zero if any failed. */
#include <stdio.h>

static int check_failures;
static int check_count;

#define CHECK(cond)                                                              \
    do {                                                                         \
        check_count++;                                                           \
        if (!(cond)) {                                                           \
            check_failures++;                                                    \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                        \
    } while (0)

#define CHECK_NEAR(a, b, eps) CHECK(((a) - (b)) <= (eps) && ((b) - (a)) <= (eps))

static inline int check_finish(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, check_count, check_failures);
    return check_failures ? 1 : 0;
}

#endif
