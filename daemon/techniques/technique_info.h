#ifndef SHADEBENCH_TECHNIQUE_INFO_H
#define SHADEBENCH_TECHNIQUE_INFO_H

/* The GL-free half of a technique: its name, summary, named passes, options
 * (an option table over its own options struct: common/options.h) and what
 * it can do. Each technique's folder defines one, named NAME_info after its
 * folder (daemon/techniques/NAME/); the registry lists them
 * (technique_infos) and the job parser, sweeps, reports and /v1/info read
 * them through a catalogue (catalog.h), so adding a technique changes
 * nothing in jobs, sweeps or HTTP. The GL half (technique.h) points at its
 * info. Immutable; any thread. */

#include <stdbool.h>
#include <stddef.h>

#include "common/frame_needs.h"
#include "common/options.h"

struct look_spec;

/* Bytes of one technique's options struct, stored inline in a job spec. */
#define TECHNIQUE_OPTIONS_BYTES OPT_MAX_BYTES
/* Named passes a technique may declare (the harness adds its own). */
#define TECHNIQUE_MAX_PASSES 16

/* What a technique can do, for the parts of the daemon that must choose
 * among techniques without naming them. */
enum technique_flag {
    /* The plain technique: what a job runs when it names none, and what a
     * sweep scores its points against when its base names no reference.
     * The catalogue takes the first technique that says so. */
    TECHNIQUE_BASELINE = 1u << 0,
    /* Its light lists hold a bounded number of lights and count what they
     * drop (result.<name>.overflow.frames), so a sweep's no_overflow
     * criterion can judge it. */
    TECHNIQUE_BOUNDED_LIGHT_LISTS = 1u << 1,
    /* It reads no light: the harness makes neither the look's shadow maps
     * nor its probes for it, so that it pays only for what it draws (the
     * cost floor). */
    TECHNIQUE_READS_NO_LIGHT = 1u << 2,
};

struct technique_info {
    const char *name;
    const char *summary;
    /* The passes a frame runs, in order, NULL-terminated; each is timed and
     * shown in debug captures under this name. */
    const char *const *passes;
    /* Its options ("<name>": {...} in a job); fields NULL for none. The
     * check names fields under the prefix it is handed, "<name>". */
    struct opt_table options;
    unsigned flags; /* enum technique_flag */
    /* Optional: what the technique with these options needs of time
     * (common/frame_needs.h: history frames, jitter, motion vectors), as
     * effects declare it; NULL for none (every frame drawn afresh). */
    void (*needs)(const void *opts, struct frame_needs *out);
    /* Bytes a pixel of the planes it draws beside the harness's output
     * (g-buffers, the heat map), every MSAA sample counted, for its options,
     * the look and whether the scene is textured: what the memory estimate
     * (daemon/jobs/job_cost.h) charges it. NULL: none. */
    double (*planes_bpp)(const void *options, const struct look_spec *look, bool textured,
                         int samples);
};

/* Every registered technique's info, in registry order (the order of
 * daemon/techniques/registry.mk), NULL-terminated. */
extern const struct technique_info *const technique_infos[];

#endif
