#ifndef SHADEBENCH_TESTS_CHECK_H
#define SHADEBENCH_TESTS_CHECK_H

/* A minimal assertion helper: every failed CHECK is reported with its line,
 * and the test exits non-zero if any failed; and check_slurp, a file's bytes
 * for the tests that read fixtures. */
#include <stdio.h>
#include <stdlib.h>

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

/* The test's exit status: 1 when a check failed, or when none was made (a
 * test that checks nothing proves nothing). */
static inline int check_finish(const char *name)
{
    printf("%s: %d checks, %d failed%s\n", name, check_count, check_failures,
           check_count ? "" : " (no check was made: that fails)");
    return check_failures || !check_count ? 1 : 0;
}

/* The whole file at path (malloc'd, *len its size), or NULL. */
static inline unsigned char *check_slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = n >= 0 ? malloc((size_t)n + 1) : NULL;
    *len = buf ? fread(buf, 1, (size_t)n, f) : 0;
    fclose(f);
    return buf;
}

#endif
