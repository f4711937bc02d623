/* Forward shading's GL-free half: no options, one pass. */
#include "daemon/techniques/technique_info.h"

static const char *const passes[] = {"shading", NULL};

const struct technique_info forward_info = {
    .name = "forward",
    .summary = "one pass; every light evaluated per fragment (thesis ForwardProg)",
    .passes = passes,
    .flags = TECHNIQUE_BASELINE,
};
