#ifndef SHADEBENCH_UI_FILES_H
#define SHADEBENCH_UI_FILES_H

/* The dashboard's files (docs/dashboard.md), embedded at build time by
 * build-aux/embed-ui.sh from daemon/api/ui/ and the charting library:
 * served at /ui/NAME, index.html at / too. Constant data; any thread. */

#include <stddef.h>

struct ui_file {
    const char *url;  /* "/ui/app.js" */
    const char *type; /* Content-Type */
    const unsigned char *data;
    size_t len;
};

/* Ends with an entry whose url is NULL. */
extern const struct ui_file ui_files[];
/* A strong ETag over every file: a build's files change together. */
extern const char ui_etag[];

/* The file served at url ("/" is the index), or NULL. */
const struct ui_file *ui_file_find(const char *url);

#endif
