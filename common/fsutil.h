#ifndef SHADEBENCH_FSUTIL_H
#define SHADEBENCH_FSUTIL_H

/* File helpers shared by the daemon and the client. Any thread. On failure
 * every function leaves errno saying why (cleanup after a failed step never
 * clobbers it), so callers can name the file and the cause. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* Temporary file, fsync, rename: a reader sees the old file or the whole new one. */
bool fs_write_atomic(const char *path, const void *data, size_t len);
bool fs_write_json_atomic(const char *path, const json_t *value);
bool fs_mkdir_p(const char *path);

/* Reads a whole file; NULL when it cannot. *len gets its size. */
char *fs_read_file(const char *path, size_t max, size_t *len);

#endif
