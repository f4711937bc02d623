#ifndef SHADEBENCH_SUGGEST_H
#define SHADEBENCH_SUGGEST_H

/* "Did you mean --runs?": the nearest of a set of names to a mistyped one,
 * by edit distance (insertions, deletions, substitutions and swaps of two
 * neighbours each cost 1), for the client's short usage errors. GL-free, no
 * I/O; pure, any thread; unit-tested in tests/unit/test_client.c. */

#include <stddef.h>

/* The one candidate that word begins, if exactly one does ("--fail" for
 * "--fail-inconclusive"); else the candidate nearest to word within a
 * third of its length in edits (at least 1, at most 3); else NULL. */
const char *suggest_nearest(const char *word, const char *const *candidates, size_t n);

/* Edit distance between a and b (optimal string alignment). */
size_t suggest_distance(const char *a, const char *b);

#endif
