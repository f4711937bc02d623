#ifndef SHADEBENCH_CATALOG_H
#define SHADEBENCH_CATALOG_H

/* The catalogue of techniques a daemon accepts: the GL-free halves of the
 * registered techniques, for the job parser, sweeps, reports and /v1/info,
 * which take it as a parameter and never name a technique. main builds it
 * once with technique_catalog_init before any thread starts and hands it
 * to the HTTP server, the queue and the sweeps; a unit test builds the same
 * one without GL. Read-only once built: any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/techniques/technique_info.h"

/* Techniques a catalogue may hold. */
#define TECHNIQUE_MAX 32

struct technique_catalog {
    const struct technique_info *infos[TECHNIQUE_MAX];
    int count;
    int baseline; /* index of the first TECHNIQUE_BASELINE technique; -1 for none */
};

/* Every registered technique (technique_infos), each checked as
 * technique_catalog_add checks it. False with err naming the technique. */
bool technique_catalog_init(struct technique_catalog *c, char *err, size_t errlen);

/* Checks info (name, summary, passes, options table, options size) and
 * adds it; false with err when it fails, its name is taken or the
 * catalogue is full. */
bool technique_catalog_add(struct technique_catalog *c, const struct technique_info *info,
                           char *err, size_t errlen);

/* Index of name, or -1. */
int technique_catalog_find(const struct technique_catalog *c, const char *name);
/* The names of the techniques whose flags hold every bit of having (0: all),
 * quoted and comma-separated (`"a", "b"`), for rule messages. */
void technique_catalog_list(const struct technique_catalog *c, unsigned having, char *buf,
                            size_t cap);
/* /v1/info's "techniques": every technique with its passes and options
 * (type, default, range or choices, summary). New reference. */
json_t *technique_catalog_json(const struct technique_catalog *c);
/* The option at a dotted path ("<technique>.<option>"), for sweeps; NULL when
 * the path names no option of a catalogued technique. */
const struct opt_field *technique_catalog_option(const struct technique_catalog *c,
                                                 const char *path);

#endif
