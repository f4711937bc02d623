#ifndef SHADEBENCH_CATALOG_H
#define SHADEBENCH_CATALOG_H

/* The catalogue of every registered technique's GL-free half, for the job
 * parser, sweeps, reports and /v1/info: the one view of the registry that
 * code which must not include GL headers (HTTP threads, main) may have.
 * Built on the first call, which main makes before it starts any thread;
 * immutable and safe from any thread afterwards. NULL when a registered
 * technique fails its checks (err says which). */

#include <stddef.h>

#include "daemon/techniques/technique_info.h"

const struct technique_catalog *technique_catalog(void);
/* Why technique_catalog() returned NULL. */
const char *technique_catalog_error(void);

#endif
