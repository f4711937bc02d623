#define _POSIX_C_SOURCE 200809L
#include "client/suggest.h"

#include <stdlib.h>
#include <string.h>

size_t suggest_distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    /* Three rows of the dynamic programme: the swap looks two back. */
    size_t *prev2 = calloc(m + 1, sizeof(size_t)), *prev = calloc(m + 1, sizeof(size_t)),
           *cur = calloc(m + 1, sizeof(size_t));
    if (!prev2 || !prev || !cur) {
        free(prev2);
        free(prev);
        free(cur);
        return n > m ? n : m;
    }
    for (size_t j = 0; j <= m; j++)
        prev[j] = j;
    for (size_t i = 1; i <= n; i++) {
        cur[0] = i;
        for (size_t j = 1; j <= m; j++) {
            size_t cost = a[i - 1] != b[j - 1];
            size_t best = prev[j - 1] + cost;
            if (prev[j] + 1 < best)
                best = prev[j] + 1;
            if (cur[j - 1] + 1 < best)
                best = cur[j - 1] + 1;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                prev2[j - 2] + 1 < best)
                best = prev2[j - 2] + 1;
            cur[j] = best;
        }
        size_t *t = prev2;
        prev2 = prev;
        prev = cur;
        cur = t;
    }
    size_t d = prev[m];
    free(prev2);
    free(prev);
    free(cur);
    return d;
}

const char *suggest_nearest(const char *word, const char *const *candidates, size_t n)
{
    size_t len = strlen(word), prefixed = 0;
    const char *prefix_of = NULL;
    for (size_t i = 0; i < n; i++)
        if (len && strncmp(candidates[i], word, len) == 0) {
            prefixed++;
            prefix_of = candidates[i];
        }
    if (prefixed == 1)
        return prefix_of;
    size_t limit = len / 3;
    limit = limit < 1 ? 1 : limit > 3 ? 3 : limit;
    const char *best = NULL;
    size_t best_d = limit + 1;
    for (size_t i = 0; i < n; i++) {
        size_t d = suggest_distance(word, candidates[i]);
        if (d < best_d) {
            best_d = d;
            best = candidates[i];
        }
    }
    return best;
}
