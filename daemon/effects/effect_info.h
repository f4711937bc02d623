#ifndef SHADEBENCH_EFFECT_INFO_H
#define SHADEBENCH_EFFECT_INFO_H

/* The GL-free half of a post effect the harness runs after any technique on
 * its HDR output (look.post): its name, summary, the named passes it runs
 * and its options, an option table over its own options struct read by the
 * generic reader (common/options.h) as techniques' are, so that bad input
 * is answered alike: "look.post[1].radius: must be an integer from 2 to 32".
 * Each effect's folder (daemon/effects/NAME/) defines NAME_info; the
 * registry (registry.mk, generated into effect_infos) lists them. Effects
 * are part of the harness, not of a catalogue a caller hands in.
 * Immutable; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/frame_needs.h"
#include "common/options.h"

/* Effects the registry may hold. */
#define EFFECT_REGISTRY_MAX 16
/* Named passes one effect instance may run in a frame. */
#define EFFECT_MAX_PASSES 6

/* What an effect is, for the parts of the daemon that must choose among
 * effects without naming them. */
enum effect_flag {
    /* It anti-aliases (TAA): a job's reference, the supersampled truth it
     * approximates, renders the job's look without it unless the job gives
     * a reference_look. */
    EFFECT_ANTIALIASING = 1u << 0,
};

struct effect_info {
    const char *name;
    const char *summary;
    /* Every pass the effect may run, NULL-terminated (for /v1/info). */
    const char *const *passes;
    /* Its options ({"<name>": {...}} in look.post); the check names fields
     * under the entry's path ("look.post[1]"). */
    struct opt_table options;
    /* The passes one instance runs with these options, in frame order, as
     * suffixes ("bright", "blur_h", ...); returns how many (at most
     * EFFECT_MAX_PASSES). */
    int (*active_passes)(const void *opts, const char **out);
    /* Optional: what one instance with these options needs of time
     * (common/frame_needs.h: history frames, jitter, motion vectors); NULL
     * for none. */
    void (*needs)(const void *opts, struct frame_needs *out);
    unsigned flags; /* enum effect_flag */
};

/* Every registered effect's info, in registry order (the order of
 * daemon/effects/registry.mk), NULL-terminated. */
extern const struct effect_info *const effect_infos[];

/* Index of name in effect_infos, or -1. */
int effect_find(const char *name);

/* /v1/info's "effects": each effect with its passes and options (type,
 * default, rule, summary), as techniques are described. New reference. */
json_t *effect_catalog_json(void);

/* Checks every registered effect's info: name, summary, passes, hooks,
 * options table, options within OPT_MAX_BYTES, names unique. */
bool effect_infos_check(char *err, size_t errlen);

/* effect_infos_check, then every effect's GL half: its hooks, and that the
 * GL registry follows effect_infos. Defined by the GL half of the registry
 * (daemon/effects/registry.c, the daemon only); at start-up, before any
 * job. */
bool effect_registry_check(char *err, size_t errlen);

#endif
